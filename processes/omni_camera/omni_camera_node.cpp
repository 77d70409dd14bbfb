#include "omni_camera_node.hpp"

#include <algorithm>
#include <chrono>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::processes {
namespace {

std::string SizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

// Warnings of one kind: the first few, then every 100th.
bool ShouldWarn(int64_t count) { return count <= 5 || count % 100 == 0; }

// Sleeps until the monotonic time `due_utime`, waking up early on a shutdown request.
void SleepUntil(int64_t due_utime) {
  for (;;) {
    const int64_t left = due_utime - glue::MonotonicUtime();
    if (left <= 0 || glue::ShutdownRequested()) return;
    std::this_thread::sleep_for(std::chrono::microseconds(std::min<int64_t>(left, 50000)));
  }
}

}  // namespace

namespace {

// The [camera] keys, declared once: read, printed and described from here.
const glue::OptionTable<OmniCameraConfig>& CameraTable() {
  using C = OmniCameraConfig;
  // A value that does not parse (an unknown source kind or encoding) names its file, line and key.
  const auto parsed = [](const glue::IniFile& ini, const std::string& s, const std::string& k, auto parse) {
    try {
      return parse(ini.GetString(s, k));
    } catch (const std::invalid_argument& e) {
      ini.FailKey(s, k, e.what());
    }
  };
  static const auto table =
      glue::OptionTable<C>()
          .Text("sensor_name", [](auto& c) -> auto& { return c.frame.sensor_name; })
          .Custom(
              "source", "",
              [parsed](const glue::IniFile& ini, const std::string& s, const std::string& k, C& c) {
                c.capture.source = parsed(ini, s, k, [](const std::string& v) { return FrameSourceSpec::Parse(v); });
              },
              [](std::ostream& out, const C& c) { out << c.capture.source.ToString(); })
          .Number("width_px", "px", [](auto& c) -> auto& { return c.capture.width_px; })
          .Number("height_px", "px", [](auto& c) -> auto& { return c.capture.height_px; })
          .Number("rate_hz", "Hz", [](auto& c) -> auto& { return c.capture.rate_hz; })
          .Flag("loop", [](auto& c) -> auto& { return c.capture.loop; })
          .Custom(
              "encoding", "",
              [parsed](const glue::IniFile& ini, const std::string& s, const std::string& k, C& c) {
                c.frame.encoding = parsed(ini, s, k, [](const std::string& v) { return glue::ParseFrameEncoding(v); });
              },
              [](std::ostream& out, const C& c) { out << glue::FrameEncodingName(c.frame.encoding); })
          .Number("jpeg_quality", "", [](auto& c) -> auto& { return c.frame.jpeg_quality; });
  return table;
}

}  // namespace

OmniCameraConfig OmniCameraConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  OmniCameraConfig c;
  c.frame_channel = channel_prefix + ini.GetString("channels", "frame");
  CameraTable().ReadKeys(ini, "camera", &c);
  c.frame.mirror = glue::ReadMirrorConfig(ini);
  // The mask is for the processes that read the frames; the camera checks that it fits.
  c.mask_path = glue::ReadMirrorMask(ini, c.capture.width_px > 0 ? cv::Size(c.capture.width_px, c.capture.height_px)
                                                                 : cv::Size()).path;
  ini.CheckAllUsed();
  ini.Check([&c] { c.Validate(); });
  return c;
}

void OmniCameraConfig::Validate() const {
  if (frame_channel.empty()) throw std::invalid_argument("[channels] frame must not be empty");
  capture.Validate();
  frame.Validate();
  if (capture.width_px > 0) CheckMirrorFitsImage(frame.mirror, capture.width_px, capture.height_px);
}

void OmniCameraConfig::Print(std::ostream& out) const {
  out << "[channels]\nframe = " << frame_channel << "\n[camera]\n";
  CameraTable().Print(out, *this);
  glue::PrintMirrorConfig(out, frame.mirror, mask_path, "mirror");
}

OmniCameraNode::OmniCameraNode(glue::Bus& bus, const OmniCameraConfig& config, std::ostream* log)
    : bus_(bus), config_(config), log_(log) {
  config_.Validate();
  source_ = OpenFrameSource(config_.capture);
  source_description_ = source_->description();
  expected_width_px_ = config_.capture.width_px;
  expected_height_px_ = config_.capture.height_px;
}

OmniCameraNode::StepResult OmniCameraNode::Skip(int64_t* counter, const std::string& reason) {
  ++*counter;
  ++consecutive_unusable_;
  last_error_ = reason;
  if (log_ && ShouldWarn(*counter)) *log_ << "omni-camera: skipped frame " << frames_read_ << ": " << reason << "\n";
  if (consecutive_unusable_ >= source_->max_consecutive_failures()) {
    throw std::runtime_error(source_description_ + ": " + std::to_string(consecutive_unusable_) +
                             " frames in a row unusable (last: " + reason + ")");
  }
  return StepResult::kSkipped;
}

OmniCameraNode::StepResult OmniCameraNode::Step() {
  cv::Mat image;
  std::string error;
  const ReadStatus status = source_->Read(&image, &error);
  if (status == ReadStatus::kEnd) return StepResult::kEnd;
  const int64_t utime = glue::WallUtime();  // capture time: this driver is a live source
  ++frames_read_;
  if (status == ReadStatus::kFailed) return Skip(&read_failures_, error);

  if (expected_width_px_ == 0) {
    // No size configured: the first frame fixes it, and the mirror centre must lie inside.
    CheckMirrorFitsImage(config_.frame.mirror, image.cols, image.rows);
    expected_width_px_ = image.cols;
    expected_height_px_ = image.rows;
  }
  if (image.cols != expected_width_px_ || image.rows != expected_height_px_) {
    return Skip(&size_mismatches_, "frame is " + SizeText(image.cols, image.rows) + ", expected " +
                                       SizeText(expected_width_px_, expected_height_px_) +
                                       " ([camera] width_px, height_px; the mirror calibration is for that size)");
  }
  omni_frame_t msg;
  try {
    msg = MatToOmniFrame(image, utime, config_.frame);
  } catch (const std::exception& e) {
    return Skip(&conversion_errors_, e.what());
  }
  bus_.Publish(config_.frame_channel, msg);
  ++published_;
  consecutive_unusable_ = 0;
  return StepResult::kPublished;
}

OmniCameraNode::StopReason OmniCameraNode::Run(int64_t max_frames) {
  const bool paced = !source_->is_device() && config_.capture.rate_hz > 0;
  const int64_t period_us = paced ? static_cast<int64_t>(1e6 / config_.capture.rate_hz) : 0;
  int64_t due = glue::MonotonicUtime();
  for (;;) {
    if (glue::ShutdownRequested()) return StopReason::kShutdown;
    if (max_frames > 0 && published_ >= max_frames) return StopReason::kMaxFrames;
    if (paced) {
      SleepUntil(due);
      if (glue::ShutdownRequested()) return StopReason::kShutdown;
      // Late by more than a period (slow disk, suspended process): restart the schedule, no burst.
      const int64_t now = glue::MonotonicUtime();
      due = (now - due > period_us) ? now + period_us : due + period_us;
    }
    if (Step() == StepResult::kEnd) return StopReason::kEndOfSource;
  }
}

void OmniCameraNode::Report(std::ostream& out) const {
  out << "published " << published_ << " frames on " << config_.frame_channel << " from " << source_description_ << " ("
      << read_failures_ << " unreadable, " << size_mismatches_ << " wrong size, " << conversion_errors_
      << " not converted)";
  if (!last_error_.empty()) out << "; last problem: " << last_error_;
  out << "\n";
}

}  // namespace snapnav::processes
