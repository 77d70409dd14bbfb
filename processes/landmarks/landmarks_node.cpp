#include "landmarks_node.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <iostream>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/landmark_set_t.hpp"

namespace snapnav::processes {
LandmarksConfig LandmarksConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix,
                                         const std::string& method) {
  LandmarksConfig c;
  c.omni_channel = channel_prefix + ini.GetString("channels", "omni");
  c.panorama_channel = channel_prefix + ini.GetString("channels", "panorama");
  std::string out = ini.GetString("channels", "landmarks");
  c.raw_input = glue::ReadChoice<bool>(ini, "landmarks", "input", {{"raw", true}, {"panorama", false}});
  c.panorama = glue::ReadPanoramaConfig(ini);
  c.mirror = glue::ReadMirrorConfig(ini);
  const glue::MirrorMask mask = glue::ReadMirrorMask(ini);  // the mask, loaded: [mirror] mask
  c.mask_path = mask.path;
  c.mask = mask.mask;
  c.extractor = glue::ReadLandmarkExtractor(ini);
  if (!method.empty()) {
    const auto m = nav::ParseLandmarkMethod(method);
    if (!m || *m == nav::LandmarkMethod::kHog) {
      throw glue::ConfigError("--method '" + method + "': expected vline | sift | surf");
    }
    c.extractor.method = *m;
  }
  ini.CheckAllUsed();
  std::string upper = nav::LandmarkMethodName(c.extractor.method);
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char ch) { return std::toupper(ch); });
  if (const auto pos = out.find("%s"); pos != std::string::npos) out.replace(pos, 2, upper);
  c.landmarks_channel = channel_prefix + out;
  try {
    c.panorama.Validate();
    c.mirror.Validate();
    c.extractor.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  if (c.landmarks_channel == c.input_channel()) {
    throw ini.ValidationError("[channels] landmarks and " + std::string(c.raw_input ? "omni" : "panorama") +
                              " are both '" + c.landmarks_channel + "'");
  }
  return c;
}

void LandmarksConfig::Print(std::ostream& out) const {
  out << "[channels]\nomni = " << omni_channel << "\npanorama = " << panorama_channel << "\nlandmarks = "
      << landmarks_channel << "\n[landmarks]\ninput = " << (raw_input ? "raw" : "panorama") << "\n";
  glue::PrintLandmarkExtractorKeys(out, extractor);
  glue::PrintPanoramaConfig(out, panorama);
  glue::PrintMirrorConfig(out, mirror, mask_path, "mirror");
  glue::PrintLandmarkExtractorSections(out, extractor);
}

LandmarksNode::LandmarksNode(glue::Bus& bus, const LandmarksConfig& config)
    : bus_(bus), config_(config), frames_to_panoramas_(config.panorama, config.mirror) {
  frames_to_panoramas_.SetMask(config_.mask);
  bus_.Subscribe(config_.input_channel(), &LandmarksNode::OnFrame, this);
}

int64_t LandmarksNode::rejected_total() const {
  int64_t n = 0;
  for (const auto& [_, count] : rejected_) n += count;
  return n;
}

void LandmarksNode::Report(std::ostream& out) const {
  out << "landmarks: " << nav::LandmarkMethodName(config_.extractor.method) << ", frames " << frames_
      << ", sets published " << published_ << " (" << empty_sets_ << " without landmarks), landmarks " << landmarks_
      << (published_ > 0 ? " (" + std::to_string(landmarks_ / published_) + " per set, " +
                               std::to_string(static_cast<int>(std::lround(seconds_ * 1000 / published_))) +
                               " ms extraction per frame)"
                         : std::string())
      << ", rejected " << rejected_total() << "\n";
  for (const auto& [reason, count] : rejected_) out << "landmarks:   rejected (" << reason << "): " << count << "\n";
}

void LandmarksNode::OnFrame(const omni_frame_t& frame) {
  ++frames_;
  const auto panorama = frames_to_panoramas_.Convert(frame);
  if (!panorama) {
    ++rejected_[frames_to_panoramas_.reason()];
    bus_.CountDecodeError(frames_to_panoramas_.reason() + ": " + frames_to_panoramas_.detail());
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  nav::LandmarkSet set;
  try {
    set = nav::ExtractLandmarks(*panorama, config_.extractor, frames_to_panoramas_.mask(),
                                frames_to_panoramas_.mask_clearance());
  } catch (const std::exception& e) {
    ++rejected_["extraction error"];
    throw std::runtime_error(std::string("landmarks: ") + e.what());  // the bus counts it as a handler error
  }
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  bus_.Publish(config_.landmarks_channel, glue::LandmarkSetToMsg(set, config_.panorama, frame.utime, frame.sensor_name));
  ++published_;
  landmarks_ += set.size();
  if (set.empty()) ++empty_sets_;
}

}  // namespace snapnav::processes
