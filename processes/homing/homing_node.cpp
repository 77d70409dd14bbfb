#include "homing_node.hpp"

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <utility>

#include <opencv2/imgcodecs.hpp>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::processes {
namespace {

constexpr double kDeg = M_PI / 180.0;

using glue::ReadChoice;

nav::OrientationRange ReadRange(const glue::IniFile& ini, const std::string& section) {
  const std::string value = ini.GetString(section, "range");
  if (const auto r = nav::ParseOrientationRange(value)) return *r;
  ini.FailKey(section, "range", "expected all | vertical | horizontal | narrow_vertical");
}

nav::HogOptions ReadHog(const glue::IniFile& ini, const std::string& section) {
  nav::HogOptions o;
  o.band_top_px = ini.GetInt(section, "band_top_px");
  o.band_height_px = ini.GetInt(section, "band_height_px");
  o.cell_size_px = ini.GetInt(section, "cell_size_px");
  o.bins = ini.GetInt(section, "bins");
  o.range = ReadRange(ini, section);
  return o;
}

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
  out << "[" << section << "]\nratio = " << m.ratio << "\nmutual = " << (m.mutual ? "true" : "false")
      << "\nrelaxed_second_best = " << (m.relaxed_second_best ? "true" : "false")
      << "\nmax_distance = " << m.max_distance << "\nmax_x_displacement_px = " << m.max_x_displacement_px << "\n";
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

}  // namespace

HomingConfig HomingConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  HomingConfig c;
  c.omni_channel = channel_prefix + ini.GetString("channels", "omni");
  c.panorama_channel = channel_prefix + ini.GetString("channels", "panorama");
  c.home_snapshot_channel = channel_prefix + ini.GetString("channels", "home_snapshot");
  c.homing_vector_channel = channel_prefix + ini.GetString("channels", "homing_vector");
  c.landmarks_channel = channel_prefix + ini.GetString("channels", "landmarks");
  c.home_landmarks_channel = channel_prefix + ini.GetString("channels", "home_landmarks");

  c.input = ReadChoice<HomingInput>(
      ini, "homing", "input",
      {{"raw", HomingInput::kRaw}, {"panorama", HomingInput::kPanorama}, {"landmarks", HomingInput::kLandmarks}});
  c.home = ReadChoice<HomeSource>(
      ini, "homing", "home",
      {{"message", HomeSource::kMessage}, {"image", HomeSource::kImage}, {"first", HomeSource::kFirst}});
  c.home_image = ini.GetString("homing", "home_image");
  if (!c.home_image.empty() && std::filesystem::path(c.home_image).is_relative()) {
    // Relative to the config file's folder, so the config works from any working directory.
    c.home_image = (std::filesystem::path(ini.origin()).parent_path() / c.home_image).lexically_normal().string();
  }
  c.home_image_raw = ReadChoice<bool>(ini, "homing", "home_image_kind", {{"raw", true}, {"panorama", false}});

  c.panorama = glue::ReadPanoramaConfig(ini);
  c.mirror = glue::ReadMirrorConfig(ini);
  const glue::MirrorMask mask = glue::ReadMirrorMask(ini);  // the mask, loaded: [mirror] mask
  c.mask_path = mask.path;
  c.mask = mask.mask;

  auto& h = c.homing;
  h.hog = ReadHog(ini, "hog");
  h.hog.narrow_range_deg = ini.GetDouble("hog", "narrow_range_deg");
  h.use_compass = ini.GetBool("compass", "enabled");
  h.compass_hog = ReadHog(ini, "compass");
  h.compass_hog.narrow_range_deg = h.hog.narrow_range_deg;

  h.alv.threshold_frac = ini.GetDouble("alv", "threshold_frac");
  h.alv.difference = ReadChoice<nav::AlvDifference>(ini, "alv", "difference",
                                                    {{"current_minus_home", nav::AlvDifference::kCurrentMinusHome},
                                                     {"home_minus_current", nav::AlvDifference::kHomeMinusCurrent}});
  h.alv.weight = ReadChoice<nav::CellWeight>(
      ini, "alv", "weight", {{"magnitude", nav::CellWeight::kMagnitude}, {"log", nav::CellWeight::kLog}});
  h.alv.log_scale = ini.GetDouble("alv", "log_scale");
  h.alv.min_bins = ini.GetInt("alv", "min_bins");

  h.equalize_histogram = ini.GetBool("preprocess", "equalize_histogram");
  h.warp_compensation = ini.GetBool("preprocess", "warp_compensation");
  h.warp.camera_height_m = ini.GetDouble("preprocess", "camera_height_m");
  h.warp.height_bottom_m = ini.GetDouble("preprocess", "warp_height_bottom_m");
  h.warp.height_top_m = ini.GetDouble("preprocess", "warp_height_top_m");

  c.keypoint_homing = glue::ReadLandmarkHoming(ini, nav::LandmarkMethod::kSift);
  c.vline_homing = glue::ReadLandmarkHoming(ini, nav::LandmarkMethod::kVline);

  auto& f = c.fusion;
  f.home_frames = ini.GetInt("view_fusion", "home_frames");
  f.home_interval_s = ini.GetDouble("view_fusion", "home_interval_s");
  f.current_frames = ini.GetInt("view_fusion", "current_frames");
  f.current_interval_s = ini.GetDouble("view_fusion", "current_interval_s");
  f.mode = ReadChoice<nav::ViewFusion>(ini, "view_fusion", "fusion",
                                       {{"persistent", nav::ViewFusion::kPersistent}, {"median", nav::ViewFusion::kMedian}});
  f.persistence.min_fraction = ini.GetDouble("view_fusion", "min_fraction");
  f.persistence.max_shift_px = ini.GetDouble("view_fusion", "max_shift_px");
  f.persistence.max_row_shift_px = ini.GetDouble("view_fusion", "max_row_shift_px");
  f.persistence.max_descriptor_distance_frac = ini.GetDouble("view_fusion", "max_descriptor_distance_frac");

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
  auto print_hog = [&out](const nav::HogOptions& o) {
    out << "band_top_px = " << o.band_top_px << "\nband_height_px = " << o.band_height_px
        << "\ncell_size_px = " << o.cell_size_px << "\nbins = " << o.bins
        << "\nrange = " << nav::OrientationRangeName(o.range) << "\n";
  };
  const auto& h = homing;
  out << "[channels]\nomni = " << omni_channel << "\npanorama = " << panorama_channel
      << "\nhome_snapshot = " << home_snapshot_channel << "\nhoming_vector = " << homing_vector_channel
      << "\nlandmarks = " << landmarks_channel << "\nhome_landmarks = " << home_landmarks_channel << "\n"
      << "[homing]\ninput = " << InputName(input) << "\nhome = " << HomeName(home) << "\nhome_image = " << home_image
      << "\nhome_image_kind = " << (home_image_raw ? "raw" : "panorama") << "\n";
  glue::PrintPanoramaConfig(out, panorama);
  glue::PrintMirrorConfig(out, mirror, mask_path, "mirror");
  out << "[hog]\n";
  print_hog(h.hog);
  out << "narrow_range_deg = " << h.hog.narrow_range_deg
      << "\n[compass]\nenabled = " << (h.use_compass ? "true" : "false") << "\n";
  print_hog(h.compass_hog);
  out << "[alv]\nthreshold_frac = " << h.alv.threshold_frac << "\ndifference = "
      << (h.alv.difference == nav::AlvDifference::kCurrentMinusHome ? "current_minus_home" : "home_minus_current")
      << "\nweight = " << (h.alv.weight == nav::CellWeight::kLog ? "log" : "magnitude")
      << "\nlog_scale = " << h.alv.log_scale << "\nmin_bins = " << h.alv.min_bins << "\n"
      << "[preprocess]\nequalize_histogram = " << (h.equalize_histogram ? "true" : "false")
      << "\nwarp_compensation = " << (h.warp_compensation ? "true" : "false")
      << "\ncamera_height_m = " << h.warp.camera_height_m << "\nwarp_height_bottom_m = " << h.warp.height_bottom_m
      << "\nwarp_height_top_m = " << h.warp.height_top_m << "\n";
  PrintMatching(out, "matching", keypoint_homing.match);
  PrintMatching(out, "vline_matching", vline_homing.match);
  const auto& a = keypoint_homing.alv;
  out << "[landmark_alv]\nvariant = " << nav::AlvVariantName(a.variant) << "\nweight = " << nav::MatchWeightName(a.weight)
      << "\ntop_n = " << a.top_n << "\ndifference = "
      << (a.difference == nav::AlvDifference::kCurrentMinusHome ? "current_minus_home" : "home_minus_current")
      << "\nmax_scale_ratio = " << a.max_scale_ratio << "\nmin_landmarks = " << a.min_landmarks
      << "\nconsensus = " << (a.consensus ? "true" : "false") << "\nconsensus_window_deg = " << a.consensus_window_rad / kDeg
      << "\nrotation_refine_deg = " << a.rotation_refine_rad / kDeg
      << "\nrotation = " << (keypoint_homing.rotation == nav::RotationSource::kMatches ? "matches" : "none")
      << "\nrotation_window_deg = " << keypoint_homing.rotation_window_rad / kDeg << "\n";
  out << "[view_fusion]\nhome_frames = " << fusion.home_frames << "\nhome_interval_s = " << fusion.home_interval_s
      << "\ncurrent_frames = " << fusion.current_frames << "\ncurrent_interval_s = " << fusion.current_interval_s
      << "\nfusion = " << nav::ViewFusionName(fusion.mode)
      << "\nmin_fraction = " << fusion.persistence.min_fraction << "\nmax_shift_px = " << fusion.persistence.max_shift_px
      << "\nmax_row_shift_px = " << fusion.persistence.max_row_shift_px
      << "\nmax_descriptor_distance_frac = " << fusion.persistence.max_descriptor_distance_frac << "\n";
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
