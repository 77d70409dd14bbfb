#include "placecells_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/message_clock.hpp"
#include "snapnav/glue/place_cells.hpp"
#include "snapnav/place_cell_match_t.hpp"

namespace snapnav::processes {
namespace {

// Explore poses kept for the nearest-in-time lookup.
constexpr size_t kMaxExplorePoses = 1024;
constexpr double kPanoramaTolerance_rad = 1e-6;

double Seconds(int64_t dt_us) { return static_cast<double>(dt_us) * 1e-6; }

bool Finite(const nav::Pose2& p) { return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad); }

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// The view options the memory file keeps that differ from the config's, as "key: file vs config".
std::string StoredViewDifferences(const nav::PlaceViewOptions& stored, const nav::PlaceViewOptions& config) {
  std::ostringstream out;
  auto differ = [&out](const char* key, const auto& a, const auto& b) {
    if (a != b) out << "\n  " << key << ": " << a << " in the file, " << b << " in the config";
  };
  differ("[landmarks] method", std::string(nav::LandmarkMethodName(stored.features.method)),
         std::string(nav::LandmarkMethodName(config.features.method)));
  if (config.features.method == nav::LandmarkMethod::kSift) {
    differ("[sift] max_features", stored.features.sift.max_features, config.features.sift.max_features);
  }
  differ("[place_view] window_px", stored.window_px, config.window_px);
  differ("[place_view] window_scale", stored.window_scale, config.window_scale);
  differ("[place_view] signature_width_px", stored.signature_width_px, config.signature_width_px);
  differ("[place_view] signature_height_px", stored.signature_height_px, config.signature_height_px);
  differ("[place_view] keep_vlines", stored.keep_vlines, config.keep_vlines);
  differ("[place_view] vline_window_px", stored.vline.window_px, config.vline.window_px);
  differ("[vline] divided", stored.vline.divided, config.vline.divided);
  return out.str();
}

bool SamePanorama(const nav::PanoramaModel& a, const nav::PanoramaModel& b) {
  return a.width_px == b.width_px && a.height_px == b.height_px &&
         std::abs(nav::WrapAngle(a.bearing_col0_rad - b.bearing_col0_rad)) < kPanoramaTolerance_rad &&
         std::abs(a.elevation_top_rad - b.elevation_top_rad) < kPanoramaTolerance_rad &&
         std::abs(a.elevation_bottom_rad - b.elevation_bottom_rad) < kPanoramaTolerance_rad;
}

// The memory the node starts with: the file (localize; explore when it exists) or an empty one.
nav::PlaceCellMemory InitialMemory(const PlaceCellsConfig& config, std::ostream& log) {
  const bool exists = std::filesystem::exists(config.memory_file);
  if (config.mode == PlaceCellsMode::kExplore && !exists) {
    log << "placecells: " << config.memory_file << " does not exist: exploring from an empty memory\n";
    nav::PlaceCellMemory memory(config.view, config.panorama, config.vocabulary);
    memory.SetTemplateCount(config.localizer.measure.templates);
    return memory;
  }
  nav::PlaceCellMemory memory = glue::LoadPlaceMemory(config.memory_file, config.vocabulary);
  const auto& p = memory.panorama();
  if (!SamePanorama(p, config.panorama)) {
    throw std::runtime_error("place-cell memory " + config.memory_file + " was recorded on " +
                             SizeText(p.width_px, p.height_px) + " panoramas (elevations " +
                             std::to_string(p.elevation_top_rad * 180 / M_PI) + ".." +
                             std::to_string(p.elevation_bottom_rad * 180 / M_PI) + " deg), [panorama] is " +
                             SizeText(config.panorama.width_px, config.panorama.height_px) + " (" +
                             std::to_string(config.panorama.elevation_top_rad * 180 / M_PI) + ".." +
                             std::to_string(config.panorama.elevation_bottom_rad * 180 / M_PI) + " deg)");
  }
  if (const std::string diff = StoredViewDifferences(memory.view_options(), config.view); !diff.empty()) {
    throw std::runtime_error("place-cell memory " + config.memory_file +
                             " was recorded with other view options than the config's (views would not compare):" +
                             diff);
  }
  memory.SetTemplateCount(config.localizer.measure.templates);
  log << "placecells: loaded " << config.memory_file << ": " << memory.size() << " cells, "
      << std::fixed << std::setprecision(1) << static_cast<double>(memory.bytes()) / (1 << 20) << " MiB"
      << std::defaultfloat << std::setprecision(6) << "\n";
  return memory;
}

}  // namespace

const char* PlaceCellsModeName(PlaceCellsMode mode) {
  return mode == PlaceCellsMode::kExplore ? "explore" : "localize";
}

namespace {

// The [placecells] keys, declared once: read, printed and described from here (the view, localizer
// and vocabulary sections are glue's).
const glue::OptionTable<PlaceCellsConfig>& PlaceCellsTable() {
  using C = PlaceCellsConfig;
  static const auto table =
      glue::OptionTable<C>()
          .Choice("input", &C::raw_input, std::vector<std::pair<std::string, bool>>{{"raw", true}, {"panorama", false}})
          .Choice("mode", &C::mode, {PlaceCellsMode::kExplore, PlaceCellsMode::kLocalize}, PlaceCellsModeName)
          .Text("memory_file", &C::memory_file)
          .Number("novelty_threshold", "", &C::novelty_threshold)
          .Number("save_every_cells", "", &C::save_every_cells)
          .Number("explore_pose_max_age_s", "s", &C::explore_pose_max_age_s)
          .Number("min_interval_s", "s", &C::min_interval_s)
          .Number("min_travel_m", "m", &C::min_travel_m)
          .Number("stats_interval_s", "s", &C::stats_interval_s);
  return table;
}

}  // namespace

PlaceCellsConfig PlaceCellsConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  PlaceCellsConfig c;
  c.omni_channel = channel_prefix + ini.GetString("channels", "omni");
  c.panorama_channel = channel_prefix + ini.GetString("channels", "panorama");
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.explore_pose_channel = channel_prefix + ini.GetString("channels", "explore_pose");
  c.explore_correction_channel = channel_prefix + ini.GetString("channels", "explore_correction");
  c.match_channel = channel_prefix + ini.GetString("channels", "match");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");

  PlaceCellsTable().ReadKeys(ini, "placecells", &c);

  c.panorama = glue::ReadPanoramaConfig(ini);
  c.mirror = glue::ReadMirrorConfig(ini);
  const glue::MirrorMask mask = glue::ReadMirrorMask(ini);  // the mask, loaded: [mirror] mask
  c.mask_path = mask.path;
  c.mask = mask.mask;
  c.view = glue::ReadPlaceViewOptions(ini);
  c.localizer = glue::ReadLocalizerOptions(ini);
  c.vocabulary = glue::ReadVocabularyOptions(ini);
  ini.CheckAllUsed();
  ini.Check([&c] { c.Validate(); });
  return c;
}

void PlaceCellsConfig::Validate() const {
  panorama.Validate();
  mirror.Validate();
  view.Validate();
  localizer.Validate();
  vocabulary.Validate();
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument(what);
  };
  check(!memory_file.empty(), "[placecells] memory_file is empty (or give --memory FILE)");
  check(std::isfinite(novelty_threshold) && novelty_threshold >= 0, "[placecells] novelty_threshold must be >= 0");
  check(save_every_cells >= 0, "[placecells] save_every_cells must be >= 0");
  check(std::isfinite(explore_pose_max_age_s) && explore_pose_max_age_s > 0,
        "[placecells] explore_pose_max_age_s must be > 0");
  check(std::isfinite(min_interval_s) && min_interval_s >= 0, "[placecells] min_interval_s must be >= 0");
  check(std::isfinite(min_travel_m) && min_travel_m >= 0, "[placecells] min_travel_m must be >= 0");
  check(std::isfinite(stats_interval_s) && stats_interval_s >= 0, "[placecells] stats_interval_s must be >= 0");
  const std::string input_key = raw_input ? "omni" : "panorama";
  const std::vector<std::pair<std::string, const std::string*>> inputs = {
      {input_key, &input_channel()}, {"odometry", &odometry_channel}, {"explore_pose", &explore_pose_channel},
      {"explore_correction", &explore_correction_channel}};
  for (const auto& [out_key, out] : {std::pair<std::string, const std::string*>{"match", &match_channel},
                                     std::pair<std::string, const std::string*>{"pose", &pose_channel}}) {
    for (const auto& [in_key, in] : inputs) {
      check(*out != *in, "[channels] " + out_key + " and " + in_key + " are both '" + *out + "'");
    }
  }
  check(match_channel != pose_channel, "[channels] match and pose are both '" + pose_channel + "'");
  for (size_t i = 0; i < inputs.size(); ++i) {
    for (size_t j = i + 1; j < inputs.size(); ++j) {
      check(*inputs[i].second != *inputs[j].second,
            "[channels] " + inputs[i].first + " and " + inputs[j].first + " are both '" + *inputs[i].second + "'");
    }
  }
}

void PlaceCellsConfig::Print(std::ostream& out) const {
  out << "[channels]\nomni = " << omni_channel << "\npanorama = " << panorama_channel
      << "\nodometry = " << odometry_channel << "\nexplore_pose = " << explore_pose_channel
      << "\nexplore_correction = " << explore_correction_channel
      << "\nmatch = " << match_channel << "\npose = " << pose_channel << "\n"
      << "[placecells]\n";
  PlaceCellsTable().Print(out, *this);
  glue::PrintPanoramaConfig(out, panorama);
  glue::PrintMirrorConfig(out, mirror, mask_path, "mirror");
  glue::PrintPlaceViewOptions(out, view);
  glue::PrintLocalizerOptions(out, localizer);
  glue::PrintVocabularyOptions(out, vocabulary);
}

PlaceCellsNode::PlaceCellsNode(glue::Bus& bus, const PlaceCellsConfig& config, std::ostream& log)
    : bus_(bus),
      config_(config),
      log_(log),
      memory_(InitialMemory(config, log)),
      frames_to_panoramas_(config.panorama, config.mirror),
      corrections_(config.explore_pose_channel) {
  frames_to_panoramas_.SetMask(config_.mask);
  if (config_.mode == PlaceCellsMode::kLocalize && memory_.size() == 0) {
    log_ << "placecells: warning: " << config_.memory_file << " holds no cells: nothing will be localized\n";
  }
  if (config_.mode == PlaceCellsMode::kLocalize && memory_.size() > 0) {
    // The index (vocabulary, line templates) now, before the process says it is ready: built lazily,
    // the first frame trained it (seconds on a busy machine) while the next frames waited in LCM's
    // queue of 30 and the later ones were dropped. The same index either way (seeded).
    const auto t0 = std::chrono::steady_clock::now();
    memory_.BuildIndex();
    log_ << "placecells: index of " << memory_.size() << " cells built in " << std::fixed << std::setprecision(2)
         << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s ("
         << memory_.vocabulary().words() << " words)\n";
    log_.unsetf(std::ios::floatfield);
  }
  bus_.Subscribe(config_.input_channel(), &PlaceCellsNode::OnFrame, this);
  bus_.Subscribe(config_.odometry_channel, &PlaceCellsNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
  if (config_.mode == PlaceCellsMode::kExplore) {
    bus_.Subscribe(config_.explore_pose_channel, &PlaceCellsNode::OnExplorePose, this);
    bus_.Subscribe(config_.explore_correction_channel, &PlaceCellsNode::OnExploreCorrection, this);
  }
}

int64_t PlaceCellsNode::rejected_total() const {
  int64_t n = 0;
  for (const auto& [_, count] : rejected_) n += count;
  return n;
}

void PlaceCellsNode::Reject(const std::string& reason, const std::string& detail) {
  ++rejected_[reason];
  bus_.CountDecodeError(reason + ": " + detail);  // per channel; printed to stderr, rate-limited
}

bool PlaceCellsNode::Save() {
  if (config_.mode != PlaceCellsMode::kExplore || (unsaved_cells_ == 0 && !moved_since_save_)) return false;
  glue::SavePlaceMemory(memory_, config_.memory_file);
  ++saves_;
  unsaved_cells_ = 0;
  moved_since_save_ = false;
  log_ << "placecells: saved " << memory_.size() << " cells to " << config_.memory_file << "\n";
  return true;
}

void PlaceCellsNode::OnOdometry(const odometry_t& msg) {
  const nav::Pose2 pose = glue::OdometryPose(msg);
  if (!Finite(pose)) {
    Reject("bad odometry", "non-finite pose");
    return;
  }
  if (odometry_) travel_since_processed_m_ += std::hypot(pose.x_m - odometry_->x_m, pose.y_m - odometry_->y_m);
  odometry_ = pose;
}

void PlaceCellsNode::OnExplorePose(const pose_t& msg) {
  if (!glue::PlausibleUtime(msg.utime)) {
    Reject("implausible utime", "explore pose at utime " + std::to_string(msg.utime));
    return;
  }
  const nav::Pose2 pose = glue::FromPoseMsg(msg);
  if (!Finite(pose)) {
    Reject("bad explore pose", "non-finite pose");
    return;
  }
  explore_poses_.push_back({msg.utime, pose});
  // Keep the poses of the last few seconds (messages may come out of order: no sorting needed).
  const int64_t keep_us = static_cast<int64_t>(std::max(2.0, 10 * config_.explore_pose_max_age_s) * 1e6);
  while (explore_poses_.size() > kMaxExplorePoses ||
         (explore_poses_.size() > 1 && explore_poses_.front().utime < msg.utime - keep_us)) {
    explore_poses_.pop_front();
  }
}

void PlaceCellsNode::OnExploreCorrection(const pose_correction_t& msg) {
  // The pose source corrected its past (laser-slam's graph back end closed a loop): the cells this
  // run placed move with the part of the trajectory they were placed on. Tables of another pose
  // channel are another estimator's.
  std::string problem;
  const auto taken = corrections_.Take(msg, &problem);
  if (taken == glue::PoseCorrections::Taken::kInvalid) {
    Reject("bad pose correction", problem);
    return;
  }
  if (taken != glue::PoseCorrections::Taken::kTaken) return;
  // Every cell's new pose first (finite, the table's transforms being bounded), then all moved.
  std::vector<std::pair<int, nav::Pose2>> moves;
  double largest_m = 0;
  for (const ExploredCell& e : explored_) {
    const nav::Pose2 now = corrections_.Correct(e.received.utime, e.received.pose);
    const nav::Pose2& was = memory_.cell(e.index).pose;
    const double d = std::hypot(now.x_m - was.x_m, now.y_m - was.y_m);
    if (d < 1e-9 && std::abs(nav::WrapAngle(now.theta_rad - was.theta_rad)) < 1e-9) continue;  // unchanged
    moves.emplace_back(e.index, now);
    largest_m = std::max(largest_m, d);
  }
  for (const auto& [index, pose] : moves) memory_.SetPose(index, pose);
  const int moved = static_cast<int>(moves.size());
  cells_moved_ += moved;
  if (moved > 0) {
    moved_since_save_ = true;
    log_ << "placecells: correction " << msg.corrections << " of " << corrections_.pose_channel() << " moved "
         << moved << " of " << explored_.size() << " cells (at most " << std::fixed << std::setprecision(3)
         << largest_m << " m)\n";
    log_.unsetf(std::ios::floatfield);
  }
}

std::optional<PlaceCellsNode::StampedPose> PlaceCellsNode::ExplorePoseAt(int64_t utime) const {
  const StampedPose* best = nullptr;
  for (const auto& p : explore_poses_) {
    if (!best || std::llabs(p.utime - utime) < std::llabs(best->utime - utime)) best = &p;
  }
  if (!best || Seconds(std::llabs(best->utime - utime)) > config_.explore_pose_max_age_s) return std::nullopt;
  return *best;
}

bool PlaceCellsNode::RateAllows(int64_t utime) const {
  if (!last_processed_utime_ || utime < *last_processed_utime_) return true;  // the first frame, or time went back
  const bool by_time = config_.min_interval_s > 0, by_travel = config_.min_travel_m > 0;
  if (!by_time && !by_travel) return true;
  if (by_time && Seconds(utime - *last_processed_utime_) >= config_.min_interval_s) return true;
  return by_travel && travel_since_processed_m_ >= config_.min_travel_m;
}

std::optional<nav::Pose2> PlaceCellsNode::Prediction() const {
  if (!fix_ || !odometry_at_fix_ || !odometry_) return std::nullopt;
  return fix_->Compose(odometry_at_fix_->Between(*odometry_));
}

void PlaceCellsNode::OnFrame(const omni_frame_t& frame) {
  ++frames_;
  if (!glue::PlausibleUtime(frame.utime)) {  // time differences below must not overflow
    Reject("implausible utime", "frame at utime " + std::to_string(frame.utime));
    return;
  }
  MaybePrintStats(frame.utime);
  // Every frame is converted (a few ms), so each malformed one is counted, processed or not.
  const auto panorama = frames_to_panoramas_.Convert(frame);
  if (!panorama) {
    Reject(frames_to_panoramas_.reason(), frames_to_panoramas_.detail());
    return;
  }
  if (!RateAllows(frame.utime)) {
    ++skipped_["rate limit"];
    return;
  }
  std::optional<StampedPose> pose;
  if (config_.mode == PlaceCellsMode::kExplore) {
    pose = ExplorePoseAt(frame.utime);
    if (!pose) {
      ++skipped_["no explore pose"];
      return;
    }
  }
  last_processed_utime_ = frame.utime;
  travel_since_processed_m_ = 0;
  ++processed_;
  if (config_.mode == PlaceCellsMode::kExplore) {
    Explore(*panorama, frame.utime, *pose);
  } else {
    Localize(*panorama, frame.utime);
  }
}

void PlaceCellsNode::Explore(const cv::Mat& panorama, int64_t utime, const StampedPose& received) {
  // ExploreStep's rule (5.1.4), spelled out so the most similar cell can be published when the
  // view is not novel: novelty is the dissimilarity to the most similar cell (the measure's
  // "unseen" value when there is none), a view above the threshold (or the first) is a new cell.
  const auto t0 = std::chrono::steady_clock::now();
  const auto& measure = config_.localizer.measure;
  place_cell_match_t match{};
  int added = -1;
  try {
    nav::PlaceView view =
        nav::MakePlaceView(panorama, config_.view, frames_to_panoramas_.mask(), frames_to_panoramas_.mask_clearance());
    const int before = memory_.size();
    std::optional<nav::CellComparison> best;
    if (before > 0) best = memory_.MostSimilar(view, config_.localizer);
    const double novelty =
        best ? best->dissimilarity : (measure.measure == nav::PlaceMeasure::kMatchCount ? 1.0 : M_PI);
    if (before == 0 || novelty > config_.novelty_threshold) {
      // At the pose as the newest correction table of its source puts it (unchanged without one).
      added = memory_.Add(corrections_.Correct(received.utime, received.pose), utime, std::move(view));
      explored_.push_back({added, received});
    }
    match = glue::NoPlaceCellMatchMsg(utime, measure.measure, before);
    match.distance = best ? static_cast<float>(best->distance) : 0.0f;
    match.score = static_cast<float>(novelty);
    // The new cell, or the most similar one (none: nothing seen and the threshold not exceeded).
    const int index = added >= 0 ? added : best ? best->cell : -1;
    if (index >= 0) {
      const nav::PlaceCell& cell = memory_.cell(index);
      match.cell_id = cell.id;
      match.x_m = cell.pose.x_m;
      match.y_m = cell.pose.y_m;
      match.theta_rad = cell.pose.theta_rad;
    }
  } catch (const std::exception& e) {
    ++rejected_["place cell error"];
    throw std::runtime_error(std::string("placecells: ") + e.what());  // the bus counts it as a handler error
  }
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (added >= 0) {  // counted and saved before publishing, which may fail
    ++new_cells_;
    ++unsaved_cells_;
    if (config_.save_every_cells > 0 && unsaved_cells_ >= config_.save_every_cells) Save();
  }
  bus_.Publish(config_.match_channel, match);
}

void PlaceCellsNode::Localize(const cv::Mat& panorama, int64_t utime) {
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<nav::Localization> loc;
  try {
    const nav::PlaceView view =
        nav::MakePlaceView(panorama, config_.view, frames_to_panoramas_.mask(), frames_to_panoramas_.mask_clearance());
    loc = memory_.Localize(view, Prediction(), config_.localizer);
  } catch (const std::exception& e) {
    ++rejected_["place cell error"];
    throw std::runtime_error(std::string("placecells: ") + e.what());  // the bus counts it as a handler error
  }
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto measure = config_.localizer.measure.measure;
  if (!loc || !Finite(loc->pose) || !loc->covariance.allFinite()) {
    ++not_localized_;
    bus_.Publish(config_.match_channel, glue::NoPlaceCellMatchMsg(utime, measure, loc ? loc->candidates : 0));
    return;
  }
  ++localized_;
  fix_ = loc->pose;
  odometry_at_fix_ = odometry_;
  bus_.Publish(config_.match_channel, glue::ToPlaceCellMatchMsg(utime, *loc, memory_.cell(loc->cell), measure));
  bus_.Publish(config_.pose_channel, glue::ToPlaceCellPoseMsg(utime, *loc));
}

void PlaceCellsNode::MaybePrintStats(int64_t utime) {
  if (config_.stats_interval_s <= 0) return;
  if (!stats_utime_ || utime < *stats_utime_) {
    stats_utime_ = utime;
    return;
  }
  if (Seconds(utime - *stats_utime_) < config_.stats_interval_s) return;
  stats_utime_ = utime;
  PrintStats(log_, utime);
}

void PlaceCellsNode::PrintStats(std::ostream& out, int64_t utime) const {
  int64_t skipped = 0;
  for (const auto& [_, n] : skipped_) skipped += n;
  out << "placecells: t " << std::fixed << std::setprecision(1) << Seconds(utime) << " s: frames " << frames_
      << ", processed " << processed_;
  if (processed_ > 0) out << " (" << std::setprecision(0) << seconds_ * 1000 / processed_ << " ms each)";
  out << std::defaultfloat << std::setprecision(6) << ", skipped " << skipped << ", rejected " << rejected_total()
      << ", cells " << memory_.size();
  if (config_.mode == PlaceCellsMode::kExplore) {
    out << " (" << new_cells_ << " new, " << unsaved_cells_ << " unsaved)\n";
  } else {
    out << ", localized " << localized_ << ", not localized " << not_localized_ << "\n";
  }
}

void PlaceCellsNode::Report(std::ostream& out) const {
  out << "placecells: " << PlaceCellsModeName(config_.mode) << ", memory " << config_.memory_file << " ("
      << memory_.size() << " cells), frames " << frames_ << ", processed " << processed_;
  if (processed_ > 0) {
    out << " (" << static_cast<int>(std::lround(seconds_ * 1000 / processed_)) << " ms per view)";
  }
  if (config_.mode == PlaceCellsMode::kExplore) {
    out << ", new cells " << new_cells_ << ", saves " << saves_;
    if (corrections_.tables() > 0) {
      out << ", corrections of " << corrections_.pose_channel() << " taken " << corrections_.tables() << " (cells moved "
          << cells_moved_ << ")";
    }
  } else {
    out << ", localized " << localized_ << ", not localized " << not_localized_;
  }
  out << ", rejected " << rejected_total() << "\n";
  for (const auto& [reason, count] : skipped_) out << "placecells:   skipped (" << reason << "): " << count << "\n";
  for (const auto& [reason, count] : rejected_) out << "placecells:   rejected (" << reason << "): " << count << "\n";
}

}  // namespace snapnav::processes
