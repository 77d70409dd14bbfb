#include "homing_node.hpp"

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::processes {
namespace {

using glue::ReadChoice;

void CheckBand(const nav::HogOptions& o, const nav::PanoramaModel& p, const std::string& section) {
  const int band_h = o.band_height_px > 0 ? o.band_height_px : p.height_px - o.band_top_px;
  if (o.band_top_px < 0 || o.band_top_px + band_h > p.height_px || band_h < o.cell_size_px ||
      o.cell_size_px > p.width_px) {
    throw std::invalid_argument("[" + section + "] the band (band_top_px " + std::to_string(o.band_top_px) +
                                ", band_height_px " + std::to_string(o.band_height_px) +
                                ") must hold at least one cell of cell_size_px " + std::to_string(o.cell_size_px) +
                                " inside the " + std::to_string(p.width_px) + "x" + std::to_string(p.height_px) +
                                " panorama");
  }
}

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

const char* InputName(HomingInput i) {
  return i == HomingInput::kRaw ? "raw" : i == HomingInput::kPanorama ? "panorama" : "landmarks";
}

void PrintMatching(std::ostream& out, const char* section, const nav::MatchOptions& m) {
  out << "[" << section << "]\n";
  glue::MatchOptionTable().Print(out, m);
}
const char* HomeName(HomeSource h) {
  switch (h) {
    case HomeSource::kMessage:
      return "message";
    case HomeSource::kImage:
      return "image";
    case HomeSource::kFirst:
      return "first";
  }
  return "?";
}

// The keys of [homing], [hog], [compass], [alv], [preprocess] and [view_fusion], declared once: read,
// printed and described from here. ([panorama], [mirror] and the landmark sections are glue's.)
using Table = glue::OptionTable<HomingConfig>;

// The HOG keys of [hog] and [compass] (`hog` picks the options struct).
template <class F>
Table& AddHog(Table& t, F hog) {
  return t.Number("band_top_px", "px", [hog](auto& c) -> auto& { return hog(c).band_top_px; })
      .Number("band_height_px", "px", [hog](auto& c) -> auto& { return hog(c).band_height_px; })
      .Number("cell_size_px", "px", [hog](auto& c) -> auto& { return hog(c).cell_size_px; })
      .Number("bins", "", [hog](auto& c) -> auto& { return hog(c).bins; })
      .Choice("range", [hog](auto& c) -> auto& { return hog(c).range; },
              {nav::OrientationRange::kAll, nav::OrientationRange::kVertical, nav::OrientationRange::kHorizontal,
               nav::OrientationRange::kNarrowVertical},
              nav::OrientationRangeName)
      .Number("max_masked_share", "", [hog](auto& c) -> auto& { return hog(c).max_masked_share; });
}

const Table& HomingTable() {
  using C = HomingConfig;
  static const auto table = Table()
                                .Choice("input", &C::input,
                                        {HomingInput::kRaw, HomingInput::kPanorama, HomingInput::kLandmarks}, InputName)
                                .Choice("home", &C::home, {HomeSource::kMessage, HomeSource::kImage, HomeSource::kFirst},
                                        HomeName)
                                .Text("home_image", &C::home_image)
                                .Choice("home_image_kind", &C::home_image_raw,
                                        std::vector<std::pair<std::string, bool>>{{"raw", true}, {"panorama", false}});
  return table;
}

const Table& HogTable() {
  static const auto table = [] {
    Table t;
    AddHog(t, [](auto& c) -> auto& { return c.homing.hog; })
        .Number("narrow_range_deg", "deg", [](auto& c) -> auto& { return c.homing.hog.narrow_range_deg; });
    return t;
  }();
  return table;
}

const Table& CompassTable() {
  static const auto table = [] {
    Table t;
    t.Flag("enabled", [](auto& c) -> auto& { return c.homing.use_compass; });
    AddHog(t, [](auto& c) -> auto& { return c.homing.compass_hog; });
    return t;
  }();
  return table;
}

const Table& AlvTable() {
  static const auto table =
      Table()
          .Number("threshold_frac", "", [](auto& c) -> auto& { return c.homing.alv.threshold_frac; })
          .Choice("difference", [](auto& c) -> auto& { return c.homing.alv.difference; },
                  std::vector<std::pair<std::string, nav::AlvDifference>>{
                      {"current_minus_home", nav::AlvDifference::kCurrentMinusHome},
                      {"home_minus_current", nav::AlvDifference::kHomeMinusCurrent}})
          .Choice("weight", [](auto& c) -> auto& { return c.homing.alv.weight; },
                  std::vector<std::pair<std::string, nav::CellWeight>>{{"magnitude", nav::CellWeight::kMagnitude},
                                                                      {"log", nav::CellWeight::kLog}})
          .Number("log_scale", "", [](auto& c) -> auto& { return c.homing.alv.log_scale; })
          .Number("min_bins", "", [](auto& c) -> auto& { return c.homing.alv.min_bins; });
  return table;
}

const Table& PreprocessTable() {
  static const auto table =
      Table()
          .Flag("equalize_histogram", [](auto& c) -> auto& { return c.homing.equalize_histogram; })
          .Flag("warp_compensation", [](auto& c) -> auto& { return c.homing.warp_compensation; })
          .Number("camera_height_m", "m", [](auto& c) -> auto& { return c.homing.warp.camera_height_m; })
          .Number("warp_height_bottom_m", "m", [](auto& c) -> auto& { return c.homing.warp.height_bottom_m; })
          .Number("warp_height_top_m", "m", [](auto& c) -> auto& { return c.homing.warp.height_top_m; });
  return table;
}

const Table& ViewFusionTable() {
  static const auto table =
      Table()
          .Number("home_frames", "", [](auto& c) -> auto& { return c.fusion.home_frames; })
          .Number("home_interval_s", "s", [](auto& c) -> auto& { return c.fusion.home_interval_s; })
          .Number("current_frames", "", [](auto& c) -> auto& { return c.fusion.current_frames; })
          .Number("current_interval_s", "s", [](auto& c) -> auto& { return c.fusion.current_interval_s; })
          .Choice("fusion", [](auto& c) -> auto& { return c.fusion.mode; },
                  {nav::ViewFusion::kPersistent, nav::ViewFusion::kMedian}, nav::ViewFusionName)
          .Number("min_fraction", "", [](auto& c) -> auto& { return c.fusion.persistence.min_fraction; })
          .Number("max_shift_px", "px", [](auto& c) -> auto& { return c.fusion.persistence.max_shift_px; })
          .Number("max_row_shift_px", "px", [](auto& c) -> auto& { return c.fusion.persistence.max_row_shift_px; })
          .Number("max_descriptor_distance_frac", "",
                  [](auto& c) -> auto& { return c.fusion.persistence.max_descriptor_distance_frac; });
  return table;
}

}  // namespace

HomingConfig HomingConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  HomingConfig c;
  c.omni_channel = channel_prefix + ini.GetString("channels", "omni");
  c.panorama_channel = channel_prefix + ini.GetString("channels", "panorama");
  c.home_snapshot_channel = channel_prefix + ini.GetString("channels", "home_snapshot");
  c.homing_vector_channel = channel_prefix + ini.GetString("channels", "homing_vector");
  c.landmarks_channel = channel_prefix + ini.GetString("channels", "landmarks");
  c.home_landmarks_channel = channel_prefix + ini.GetString("channels", "home_landmarks");

  HomingTable().ReadKeys(ini, "homing", &c);
  if (!c.home_image.empty() && std::filesystem::path(c.home_image).is_relative()) {
    // Relative to the config file's folder, so the config works from any working directory.
    c.home_image = (std::filesystem::path(ini.origin()).parent_path() / c.home_image).lexically_normal().string();
  }

  c.panorama = glue::ReadPanoramaConfig(ini);
  c.mirror = glue::ReadMirrorConfig(ini);
  const glue::MirrorMask mask = glue::ReadMirrorMask(ini);  // the mask, loaded: [mirror] mask
  c.mask_path = mask.path;
  c.mask = mask.mask;

  HogTable().ReadKeys(ini, "hog", &c);
  CompassTable().ReadKeys(ini, "compass", &c);
  c.homing.compass_hog.narrow_range_deg = c.homing.hog.narrow_range_deg;
  AlvTable().ReadKeys(ini, "alv", &c);
  PreprocessTable().ReadKeys(ini, "preprocess", &c);

  c.keypoint_homing = glue::ReadLandmarkHoming(ini, nav::LandmarkMethod::kSift);
  c.vline_homing = glue::ReadLandmarkHoming(ini, nav::LandmarkMethod::kVline);

  ViewFusionTable().ReadKeys(ini, "view_fusion", &c);

  ini.CheckAllUsed();
  ini.Check([&c] { c.Validate(); });
  return c;
}

void HomingConfig::Validate() const {
  panorama.Validate();
  mirror.Validate();
  if (homing.warp_compensation && !(homing.warp.height_top_m > homing.warp.height_bottom_m)) {
    throw std::invalid_argument(
        "[preprocess] warp_height_top_m must exceed warp_height_bottom_m");  // the config's keys
  }
  homing.Validate();
  fusion.persistence.Validate();
  if (fusion.home_frames < 1 || fusion.current_frames < 1) {
    throw std::invalid_argument("[view_fusion] home_frames and current_frames must be >= 1");
  }
  if (!(fusion.home_interval_s > 0) || !(fusion.current_interval_s > 0)) {
    throw std::invalid_argument("[view_fusion] home_interval_s and current_interval_s must be > 0");
  }
  if (input == HomingInput::kLandmarks && fusion.mode == nav::ViewFusion::kMedian &&
      (fusion.home_frames > 1 || fusion.current_frames > 1)) {
    throw std::invalid_argument(
        "[view_fusion] fusion = median needs the frames; landmark sets (input = "
        "landmarks) are fused by persistence (fusion = persistent)");
  }
  CheckBand(homing.hog, panorama, "hog");
  if (homing.use_compass) CheckBand(homing.compass_hog, panorama, "compass");
  if (input == HomingInput::kLandmarks && home == HomeSource::kImage) {
    throw std::invalid_argument("[homing] input = landmarks takes its home from " + home_landmarks_channel +
                                " (home = message) or the first set (home = first), not from an image");
  }
  if (input == HomingInput::kLandmarks &&
      (home_landmarks_channel == landmarks_channel || homing_vector_channel == landmarks_channel)) {
    throw std::invalid_argument("[channels] landmarks, home_landmarks and homing_vector must differ");
  }
  if (home == HomeSource::kImage && home_image.empty()) {
    throw std::invalid_argument("[homing] home = image needs home_image (or --home-image)");
  }
  if (home != HomeSource::kImage && !home_image.empty()) {
    throw std::invalid_argument("[homing] home_image '" + home_image + "' is only read with home = image (home is " +
                                HomeName(home) + "); leave it empty");
  }
  if (home_snapshot_channel == input_channel()) {
    throw std::invalid_argument("[channels] home_snapshot and the input channel are both '" + home_snapshot_channel +
                                "'");
  }
  if (homing_vector_channel == input_channel() || homing_vector_channel == home_snapshot_channel) {
    throw std::invalid_argument("[channels] homing_vector '" + homing_vector_channel +
                                "' must differ from the input and home_snapshot channels");
  }
}

void HomingConfig::Print(std::ostream& out) const {
  out << "[channels]\nomni = " << omni_channel << "\npanorama = " << panorama_channel
      << "\nhome_snapshot = " << home_snapshot_channel << "\nhoming_vector = " << homing_vector_channel
      << "\nlandmarks = " << landmarks_channel << "\nhome_landmarks = " << home_landmarks_channel << "\n"
      << "[homing]\n";
  HomingTable().Print(out, *this);
  glue::PrintPanoramaConfig(out, panorama);
  glue::PrintMirrorConfig(out, mirror, mask_path, "mirror");
  for (const auto& [section, table] : {std::pair<const char*, const Table*>{"hog", &HogTable()},
                                       {"compass", &CompassTable()},
                                       {"alv", &AlvTable()},
                                       {"preprocess", &PreprocessTable()}}) {
    out << "[" << section << "]\n";
    table->Print(out, *this);
  }
  PrintMatching(out, "matching", keypoint_homing.match);
  PrintMatching(out, "vline_matching", vline_homing.match);
  glue::PrintLandmarkAlv(out, keypoint_homing);
  out << "[view_fusion]\n";
  ViewFusionTable().Print(out, *this);
}

cv::Mat LoadHomeImage(const std::string& path, bool raw, const HomingConfig& config) {
  const std::string what = "home image '" + path + "'";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw std::runtime_error(what + " does not exist");
  if (std::filesystem::is_directory(path, ec)) throw std::runtime_error(what + " is a folder, not an image file");
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(what + " cannot be read: " + e.what());
  }
  if (image.empty()) throw std::runtime_error(what + " cannot be read as an image (unreadable or not an image file)");
  const nav::PanoramaModel& p = config.panorama;
  if (!raw) {
    if (image.cols != p.width_px || image.rows != p.height_px) {
      throw std::runtime_error(what + " is " + SizeText(image.cols, image.rows) + ", not the " +
                               SizeText(p.width_px, p.height_px) +
                               " of [panorama] (home_image_kind = panorama; raw for a catadioptric image)");
    }
    return image;
  }
  try {
    nav::Unwrapper unwrapper(config.mirror, p, image.size());
    if (!config.mask.empty()) unwrapper.SetMask(config.mask);
    cv::Mat panorama;
    unwrapper.Unwrap(image, &panorama);
    return panorama;
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(what + " (" + SizeText(image.cols, image.rows) +
                             ") cannot be unwrapped with [mirror]: " + e.what());
  }
}

HomingNode::HomingNode(glue::Bus& bus, const HomingConfig& config)
    : bus_(bus),
      config_(config),
      homer_(config.homing, config.panorama),
      frames_to_panoramas_(config.panorama, config.mirror),
      home_frames_(config.fusion.home_frames, config.fusion.home_interval_s),
      current_frames_(config.fusion.current_frames, config.fusion.current_interval_s),
      home_sets_(config.fusion.home_frames, config.fusion.home_interval_s),
      current_sets_(config.fusion.current_frames, config.fusion.current_interval_s) {
  frames_to_panoramas_.SetMask(config_.mask);
  if (config_.input == HomingInput::kRaw && !config_.mask.empty() && config_.home == HomeSource::kImage &&
      config_.home_image_raw) {
    // The home image's panorama mask, before the home is described.
    nav::Unwrapper u(config_.mirror, config_.panorama, config_.mask.size());
    u.SetMask(config_.mask);
    homer_.SetMask(u.panorama_mask());
  }
  if (config_.input == HomingInput::kLandmarks) {
    bus_.Subscribe(config_.landmarks_channel, &HomingNode::OnLandmarks, this);
    bus_.Subscribe(config_.home_landmarks_channel, &HomingNode::OnHomeLandmarks, this);
    return;
  }
  if (config_.home == HomeSource::kImage) SetHome(LoadHomeImage(config_.home_image, config_.home_image_raw, config_));
  bus_.Subscribe(config_.input_channel(), &HomingNode::OnFrame, this);
  bus_.Subscribe(config_.home_snapshot_channel, &HomingNode::OnHomeSnapshot, this);
}

int64_t HomingNode::rejected_total() const {
  int64_t n = 0;
  for (const auto& [_, count] : rejected_) n += count;
  return n;
}

void HomingNode::Report(std::ostream& out) const {
  out << "homing: frames " << frames_ << ", before any home " << before_home_ << ", homes set " << homes_set_
      << ", vectors published " << published() << " (valid " << published_valid_ << ", no estimate "
      << published_invalid_ << "), unwrapper builds " << frames_to_panoramas_.unwrapper_builds() << ", rejected " << rejected_total();
  if (config_.fusion.current_frames > 1) out << ", between fused frames " << between_fused_frames_;
  out << "\n";
  for (const auto& [reason, count] : rejected_) out << "homing:   rejected (" << reason << "): " << count << "\n";
}

void HomingNode::Reject(const std::string& reason, const std::string& detail) {
  ++rejected_[reason];
  bus_.CountDecodeError(reason + ": " + detail);  // per channel; printed to stderr, rate-limited
}

void HomingNode::SetHome(const cv::Mat& panorama) {
  homer_.SetHome(panorama);
  ++homes_set_;
}

std::optional<cv::Mat> HomingNode::ToPanorama(const omni_frame_t& f) {
  auto panorama = frames_to_panoramas_.Convert(f);
  if (!panorama) {
    Reject(frames_to_panoramas_.reason(), frames_to_panoramas_.detail());
    return panorama;
  }
  // The panorama's mask follows the frames' calibration (a new one when it changes). A home
  // described before keeps the mask it was described with.
  const cv::Mat& mask = frames_to_panoramas_.mask();
  if (mask.data != mask_data_) {
    homer_.SetMask(mask);
    mask_data_ = mask.data;
  }
  return panorama;
}

void HomingNode::OnFrame(const omni_frame_t& frame) {
  ++frames_;
  const auto panorama = ToPanorama(frame);
  if (!panorama) return;
  std::optional<nav::HomingEstimate> estimate;
  try {
    if (!homer_.has_home()) {
      if (config_.home != HomeSource::kFirst) {
        ++before_home_;
        return;
      }
      // The first home_frames frames (home_interval_s apart) are the home: no vectors for them.
      home_frames_.Offer(frame.utime, *panorama);
      if (!home_frames_.full()) {
        ++before_home_;
        return;
      }
      SetHome(nav::MedianImage(home_frames_.items()));
      std::cerr << "homing: home set from the first " << home_frames_.items().size() << " frame(s) ("
                << bus_.current().channel << ", utime " << frame.utime << ")\n";
      return;
    }
    if (!current_frames_.Offer(frame.utime, *panorama)) {
      ++between_fused_frames_;
      return;
    }
    estimate = homer_.Home(current_frames_.items().size() > 1 ? nav::MedianImage(current_frames_.items()) : *panorama);
  } catch (const std::exception& e) {
    ++rejected_["homing error"];
    throw std::runtime_error(std::string("homing: ") + e.what());  // the bus counts it as a handler error
  }
  PublishVector(frame.utime, landmark_set_t::HOG, "hog", estimate);
}

void HomingNode::PublishVector(int64_t utime, int8_t method, const std::string& variant,
                               std::optional<nav::HomingEstimate> estimate) {
  if (estimate && !(std::isfinite(estimate->direction_rad) && std::isfinite(estimate->magnitude) &&
                    std::isfinite(estimate->compass_rotation_rad))) {
    estimate.reset();
  }
  homing_vector_t v{};
  v.utime = utime;
  v.method = method;
  v.alv_variant = variant;
  v.valid = estimate.has_value();
  if (estimate) {
    v.direction_rad = static_cast<float>(estimate->direction_rad);
    v.magnitude = static_cast<float>(estimate->magnitude);
    v.compass_rotation_rad = static_cast<float>(estimate->compass_rotation_rad);
    v.nlandmarks_used = estimate->bins_used;
  }
  bus_.Publish(config_.homing_vector_channel, v);
  if (estimate) {
    ++published_valid_;
  } else {
    ++published_invalid_;
  }
}

void HomingNode::OnHomeSnapshot(const omni_frame_t& frame) {
  const auto panorama = ToPanorama(frame);
  if (!panorama) return;
  try {
    // The home is the median of the last home_frames snapshots (home_interval_s apart).
    if (!home_frames_.Offer(frame.utime, *panorama)) return;
    SetHome(home_frames_.items().size() > 1 ? nav::MedianImage(home_frames_.items()) : *panorama);
  } catch (const std::exception& e) {
    ++rejected_["homing error"];
    throw std::runtime_error(std::string("home snapshot: ") + e.what());
  }
  std::cerr << "homing: home set from " << bus_.current().channel << " (utime " << frame.utime << ", "
            << home_frames_.items().size() << " frame(s))\n";
}

std::optional<nav::LandmarkSet> HomingNode::ToLandmarks(const landmark_set_t& msg) {
  try {
    return glue::LandmarkSetFromMsg(msg, config_.panorama);
  } catch (const std::invalid_argument& e) {
    Reject("bad landmark set", e.what());
    return std::nullopt;
  }
}

void HomingNode::OnLandmarks(const landmark_set_t& msg) {
  ++frames_;
  auto set = ToLandmarks(msg);
  if (!set) return;
  if (!landmark_homer_ || !landmark_homer_->has_home()) {
    if (config_.home != HomeSource::kFirst) {
      ++before_home_;
      return;
    }
    // The first home_frames sets (home_interval_s apart) are the home: no vectors for them.
    if (!home_sets_.items().empty() && home_sets_.items().front().method != set->method) home_sets_.Clear();
    home_sets_.Offer(msg.utime, std::move(*set));
    if (!home_sets_.full()) {
      ++before_home_;
      return;
    }
    SetHomeLandmarks(Fuse(home_sets_.items()));
    std::cerr << "homing: home set from the first " << home_sets_.items().size() << " landmark set(s) ("
              << bus_.current().channel << ", utime " << msg.utime << ", " << landmark_homer_->home().size()
              << " landmarks)\n";
    return;
  }
  if (set->method != landmark_homer_->home().method) {
    Reject("method differs from the home's",
           std::string(nav::LandmarkMethodName(set->method)) + " set, the home is " +
               nav::LandmarkMethodName(landmark_homer_->home().method));
    return;
  }
  if (!current_sets_.items().empty() && current_sets_.items().front().method != set->method) current_sets_.Clear();
  if (!current_sets_.Offer(msg.utime, std::move(*set))) {
    ++between_fused_frames_;
    return;
  }
  std::optional<nav::LandmarkHoming> result;
  try {
    result = landmark_homer_->Home(Fuse(current_sets_.items()));
  } catch (const std::exception& e) {
    ++rejected_["homing error"];
    throw std::runtime_error(std::string("homing: ") + e.what());
  }
  PublishVector(msg.utime, msg.method, nav::AlvVariantName(landmark_homer_->config().alv.variant),
                result ? std::optional<nav::HomingEstimate>(result->estimate) : std::nullopt);
}

void HomingNode::OnHomeLandmarks(const landmark_set_t& msg) {
  auto set = ToLandmarks(msg);
  if (!set) return;
  // The home is fused from the last home_frames sets (home_interval_s apart) of one method.
  if (!home_sets_.items().empty() && home_sets_.items().front().method != set->method) home_sets_.Clear();
  if (!home_sets_.Offer(msg.utime, std::move(*set))) return;
  try {
    SetHomeLandmarks(Fuse(home_sets_.items()));
  } catch (const std::exception& e) {
    ++rejected_["homing error"];
    throw std::runtime_error(std::string("home landmarks: ") + e.what());
  }
  std::cerr << "homing: home set from " << bus_.current().channel << " (utime " << msg.utime << ", "
            << home_sets_.items().size() << " set(s), " << landmark_homer_->home().size() << " "
            << nav::LandmarkMethodName(landmark_homer_->home().method) << " landmarks)\n";
}

nav::LandmarkSet HomingNode::Fuse(const std::vector<nav::LandmarkSet>& sets) const {
  return sets.size() == 1 ? sets.front() : nav::PersistentLandmarks(sets, config_.fusion.persistence);
}

void HomingNode::SetHomeLandmarks(nav::LandmarkSet set) {
  const auto method = set.method;
  landmark_homer_.emplace(config_.landmark_homing(method), config_.panorama);
  landmark_homer_->SetHome(std::move(set));
  current_sets_.Clear();
  ++homes_set_;
}

}  // namespace snapnav::processes
