#include "viewer_node.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/occupancy_grid_msg.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::string MethodName(int8_t method) {
  switch (method) {
    case landmark_set_t::HOG: return "hog";
    case landmark_set_t::VLINE: return "vline";
    case landmark_set_t::SIFT: return "sift";
    case landmark_set_t::SURF: return "surf";
    default: return "method " + std::to_string(method);
  }
}

void Positive(const glue::IniFile& ini, const std::string& key, double v, bool allow_zero = false) {
  if (!(allow_zero ? v >= 0 : v > 0) || !std::isfinite(v)) {
    ini.FailKey("viewer", key, std::string("must be ") + (allow_zero ? "at least 0" : "positive"));
  }
}

// The [viewer] keys, declared once: read, printed and described from here (robot_pose_channels as
// written, without the channel prefix the reader adds).
const glue::OptionTable<ViewerConfig>& ViewerTable() {
  using C = ViewerConfig;
  static const auto table =
      glue::OptionTable<C>()
          .Number("refresh_hz", "Hz", &C::refresh_hz)
          .Number("png_interval_s", "s", &C::png_interval_s)
          .Number("width_px", "px", [](auto& c) -> auto& { return c.render.size.width; })
          .Number("height_px", "px", [](auto& c) -> auto& { return c.render.size.height; })
          .Number("ellipse_sigma", "", [](auto& c) -> auto& { return c.render.ellipse_sigma; })
          .Number("ellipse_interval_s", "s", [](auto& c) -> auto& { return c.render.ellipse_interval_s; })
          .Number("min_span_m", "m", [](auto& c) -> auto& { return c.render.min_span_m; })
          .Number("scan_max_age_s", "s", [](auto& c) -> auto& { return c.render.scan_max_age_s; })
          .Number("homing_arrow_px", "px", [](auto& c) -> auto& { return c.render.homing_arrow_px; })
          .List("robot_pose_channels", [](auto& c) -> auto& { return c.render.robot_pose_channels; })
          .Number("trajectory_min_step_m", "m", &C::trajectory_min_step_m)
          .Degrees("trajectory_min_turn_deg", &C::trajectory_min_turn_rad)
          .Number("trajectory_max_gap_s", "s", &C::trajectory_max_gap_s)
          .Number("max_poses_per_channel", "", &C::max_poses_per_channel)
          .Number("max_place_cell_matches", "", &C::max_place_cell_matches);
  return table;
}

}  // namespace

std::string RegexEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (std::string(".[]{}()*+?^$|\\").find(c) != std::string::npos) out += '\\';
    out += c;
  }
  return out;
}

ViewerConfig ViewerConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  ViewerConfig c;
  const std::string regex_prefix = RegexEscape(channel_prefix);
  c.channel_prefix = channel_prefix;
  c.point_map_channel = channel_prefix + ini.GetString("channels", "point_map");
  c.pose_channels = regex_prefix + ini.GetString("channels", "poses");
  c.truth_channel = channel_prefix + ini.GetString("channels", "ground_truth");
  c.panorama_channel = channel_prefix + ini.GetString("channels", "panorama");
  c.omni_channel = channel_prefix + ini.GetString("channels", "omni");
  c.landmark_channels = regex_prefix + ini.GetString("channels", "landmarks");
  c.homing_vector_channel = channel_prefix + ini.GetString("channels", "homing_vector");
  c.place_cell_match_channel = channel_prefix + ini.GetString("channels", "place_cell_match");
  c.scan_channel = channel_prefix + ini.GetString("channels", "scan");
  c.grid_channel = channel_prefix + ini.GetString("channels", "grid");
  c.laser_slam_status_channel = channel_prefix + ini.GetString("channels", "laser_slam_status");
  c.laser_slam_pose_channel = channel_prefix + ini.GetString("channels", "laser_slam_pose");
  c.laser_slam_correction_channel = channel_prefix + ini.GetString("channels", "laser_slam_correction");

  ViewerTable().ReadKeys(ini, "viewer", &c);
  for (auto& ch : c.render.robot_pose_channels) ch = channel_prefix + ch;
  Positive(ini, "refresh_hz", c.refresh_hz);
  Positive(ini, "png_interval_s", c.png_interval_s, true);
  Positive(ini, "trajectory_min_step_m", c.trajectory_min_step_m, true);
  Positive(ini, "trajectory_min_turn_deg", c.trajectory_min_turn_rad, true);
  Positive(ini, "trajectory_max_gap_s", c.trajectory_max_gap_s);
  c.panorama = glue::ReadPanoramaConfig(ini);
  c.mirror = glue::ReadMirrorConfig(ini);
  const glue::MirrorMask mask = glue::ReadMirrorMask(ini);  // the mask, loaded: [mirror] mask
  c.mask_path = mask.path;
  c.mask = mask.mask;
  ini.CheckAllUsed();
  ini.Check([&c] { c.Validate(); });
  return c;
}

void ViewerConfig::Validate() const {
  render.Validate();
  panorama.Validate();
  mirror.Validate();
  if (max_poses_per_channel < 100) throw std::invalid_argument("[viewer] max_poses_per_channel must be >= 100");
  if (max_place_cell_matches < 1) throw std::invalid_argument("[viewer] max_place_cell_matches must be >= 1");
  if (render.robot_pose_channels.empty()) throw std::invalid_argument("[viewer] robot_pose_channels is empty");
}

void ViewerConfig::Print(std::ostream& out) const {
  out << "[channels]\npoint_map = " << point_map_channel << "\nposes = " << pose_channels
      << "\nground_truth = " << truth_channel << "\npanorama = " << panorama_channel << "\nomni = " << omni_channel
      << "\nlandmarks = " << landmark_channels << "\nhoming_vector = " << homing_vector_channel
      << "\nplace_cell_match = " << place_cell_match_channel << "\nscan = " << scan_channel << "\ngrid = " << grid_channel
      << "\nlaser_slam_status = " << laser_slam_status_channel << "\nlaser_slam_pose = " << laser_slam_pose_channel
      << "\nlaser_slam_correction = " << laser_slam_correction_channel
      << "\n[viewer]\n";
  ViewerTable().Print(out, *this);
  glue::PrintPanoramaConfig(out, panorama);
  glue::PrintMirrorConfig(out, mirror, mask_path, "mirror");
}

ViewerNode::ViewerNode(glue::Bus& bus, const ViewerConfig& config)
    : bus_(bus), config_(config), frames_to_panoramas_(config.panorama, config.mirror) {
  frames_to_panoramas_.SetMask(config_.mask);  // the panorama as the extractors see it
  scene_.truth_channel = config_.truth_channel;
  scene_.source = bus_.url();
  // Every pose channel in one subscription: ground truth and dead reckoning at 50 Hz each, the others
  // at up to 10 Hz; drawing a snapshot stalls the loop for a while, so the queue holds seconds of them.
  bus_.SubscribeRaw(config_.pose_channels, [this](const void* d, size_t n) { OnPose(d, n); },
                    glue::Bus::kOdometryQueueCapacity);
  bus_.Subscribe(config_.point_map_channel, &ViewerNode::OnPointMap, this);
  bus_.Subscribe(config_.panorama_channel, &ViewerNode::OnPanorama, this);
  bus_.Subscribe(config_.omni_channel, &ViewerNode::OnOmniFrame, this);
  bus_.SubscribeRaw(config_.landmark_channels, [this](const void* d, size_t n) { OnLandmarks(d, n); });
  bus_.Subscribe(config_.homing_vector_channel, &ViewerNode::OnHomingVector, this);
  bus_.Subscribe(config_.place_cell_match_channel, &ViewerNode::OnPlaceCellMatch, this);
  bus_.Subscribe(config_.scan_channel, &ViewerNode::OnScan, this);
  bus_.Subscribe(config_.grid_channel, &ViewerNode::OnGrid, this);
  bus_.Subscribe(config_.laser_slam_status_channel, &ViewerNode::OnLaserSlamStatus, this);
  bus_.Subscribe(config_.laser_slam_correction_channel, &ViewerNode::OnLaserSlamCorrection, this);
}

void ViewerNode::OnLaserSlamCorrection(const pose_correction_t& msg) {
  SawUtime(msg.utime);
  if (!corrections_) corrections_.emplace(config_.laser_slam_pose_channel);
  std::string problem;
  const auto taken = corrections_->Take(msg, &problem);
  if (taken == glue::PoseCorrections::Taken::kInvalid) {
    Reject("bad pose correction", problem);
    return;
  }
  if (taken != glue::PoseCorrections::Taken::kTaken) return;
  corrected_through_utime_ = std::max(corrected_through_utime_, msg.utime);
  const auto track = scene_.tracks.find(config_.laser_slam_pose_channel);
  if (track == scene_.tracks.end()) return;
  // The trail redrawn where the estimator now puts it: the jumps up to this correction are joined.
  for (viewer::PoseSample& s : track->second.poses) s.pose = corrections_->Correct(s.utime, s.published);
  viewer::PoseSample& latest = track->second.latest;
  latest.pose = corrections_->Correct(latest.utime, latest.published);
  std::vector<int64_t>& jumps = track->second.jumps;
  jumps.erase(std::remove_if(jumps.begin(), jumps.end(), [&](int64_t t) { return t <= msg.utime; }), jumps.end());
}

void ViewerNode::OnLaserSlamStatus(const laser_slam_status_t& msg) {
  SawUtime(msg.utime);
  if (!msg.corrected) return;
  // The pose of the correction's scan was published just before this status: the trail is broken
  // from the pose before it.
  const int64_t at = msg.correction_utime > 0 ? msg.correction_utime : msg.utime;
  // laser-slam publishes a correction's table before its status: a table already taken joined it.
  if (at <= corrected_through_utime_) return;
  const auto track = scene_.tracks.find(config_.laser_slam_pose_channel);
  if (track == scene_.tracks.end()) return;  // no trail yet to break
  std::vector<int64_t>& jumps = track->second.jumps;
  if (!jumps.empty() && at <= jumps.back()) return;  // announced already (or out of order)
  jumps.push_back(at);
  ++jumps_;
  if (static_cast<int>(jumps.size()) > config_.max_poses_per_channel) jumps.erase(jumps.begin());
}

void ViewerNode::SawUtime(int64_t utime) {
  if (utime <= 0) return;
  if (scene_.first_utime == 0) scene_.first_utime = utime;
  if (utime > scene_.latest_utime) scene_.latest_utime = utime;
}

void ViewerNode::OnPose(const void* data, size_t size) {
  std::string error;
  const auto msg = glue::Decode<pose_t>(data, size, &error);
  if (!msg) {
    bus_.CountDecodeError(error);
    return;
  }
  const nav::Pose2 pose = glue::FromPoseMsg(*msg);
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad)) {
    Reject("non-finite pose", bus_.current().channel);
    return;
  }
  SawUtime(msg->utime);
  viewer::Track& track = scene_.tracks[bus_.current().channel];
  const bool corrected = corrections_ && bus_.current().channel == config_.laser_slam_pose_channel;
  viewer::PoseSample sample{msg->utime, corrected ? corrections_->Correct(msg->utime, pose) : pose, pose,
                            glue::CovarianceOf(*msg)};
  if (!sample.covariance.allFinite()) sample.covariance.setZero();
  // Time going back by more than a second: a new run on the same channel starts a new track.
  if (track.received > 0 && msg->utime < track.latest.utime - 1'000'000) {
    track.poses.clear();
    track.jumps.clear();
    if (bus_.current().channel == config_.laser_slam_pose_channel) {
      corrections_.reset();  // a new run: the old run's tables are not its
      corrected_through_utime_ = 0;
    }
  }
  track.estimator = msg->estimator;
  track.frame = msg->frame;
  track.latest = sample;
  ++track.received;
  bool keep = track.poses.empty();
  if (!keep) {
    const viewer::PoseSample& last = track.poses.back();
    keep = std::hypot(pose.x_m - last.pose.x_m, pose.y_m - last.pose.y_m) >= config_.trajectory_min_step_m ||
           std::abs(nav::WrapAngle(pose.theta_rad - last.pose.theta_rad)) >= config_.trajectory_min_turn_rad ||
           (msg->utime - last.utime) * 1e-6 >= config_.trajectory_max_gap_s;
  }
  if (!keep) return;
  track.poses.push_back(sample);
  if (static_cast<int>(track.poses.size()) > config_.max_poses_per_channel) {
    // Halve the density, keeping the first and the last pose.
    std::vector<viewer::PoseSample> thinned;
    thinned.reserve(track.poses.size() / 2 + 2);
    for (size_t i = 0; i < track.poses.size(); i += 2) thinned.push_back(track.poses[i]);
    if (thinned.back().utime != track.poses.back().utime) thinned.push_back(track.poses.back());
    track.poses.swap(thinned);
  }
}

void ViewerNode::OnPointMap(const point_map_t& msg) {
  SawUtime(msg.utime);
  scene_.map_points.clear();
  scene_.map_points.reserve(msg.npoints);
  for (int i = 0; i < msg.npoints; ++i) {
    if (std::isfinite(msg.x_m[i]) && std::isfinite(msg.y_m[i])) scene_.map_points.emplace_back(msg.x_m[i], msg.y_m[i]);
  }
  scene_.map_estimator = msg.estimator;
  scene_.map_utime = msg.utime;
}

void ViewerNode::OnGrid(const occupancy_grid_t& msg) {
  if (const auto problem = glue::CheckOccupancyGrid(msg)) {
    Reject(problem->reason, bus_.current().channel + ": " + problem->detail);
    return;
  }
  SawUtime(msg.utime);
  viewer::GridView g;
  g.utime = msg.utime;
  g.source = msg.source;
  g.resolution_m = msg.resolution_m;
  g.origin_x_m = msg.origin_x_m;
  g.origin_y_m = msg.origin_y_m;
  g.origin_theta_rad = msg.origin_theta_rad;
  g.width = msg.width;
  g.height = msg.height;
  g.cells = msg.cells;
  // The known cells' extent, in the world (the corners of their bounding box, turned by theta).
  int x0 = msg.width, x1 = -1, y0 = msg.height, y1 = -1;
  for (int y = 0; y < msg.height; ++y) {
    const int8_t* row = msg.cells.data() + static_cast<size_t>(y) * static_cast<size_t>(msg.width);
    for (int x = 0; x < msg.width; ++x) {
      if (row[x] < 0) continue;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  if (x1 >= 0) {
    g.any_known = true;
    const double c = std::cos(g.origin_theta_rad), s = std::sin(g.origin_theta_rad), r = g.resolution_m;
    bool first = true;
    for (const int cx : {x0, x1 + 1}) {
      for (const int cy : {y0, y1 + 1}) {
        const double wx = g.origin_x_m + c * cx * r - s * cy * r, wy = g.origin_y_m + s * cx * r + c * cy * r;
        if (first) g.known_x0 = g.known_x1 = wx, g.known_y0 = g.known_y1 = wy, first = false;
        g.known_x0 = std::min(g.known_x0, wx), g.known_x1 = std::max(g.known_x1, wx);
        g.known_y0 = std::min(g.known_y0, wy), g.known_y1 = std::max(g.known_y1, wy);
      }
    }
  }
  scene_.grid = std::move(g);
}

void ViewerNode::OnPanorama(const omni_frame_t& msg) {
  SawUtime(msg.utime);
  have_panorama_channel_ = true;
  pending_frame_ = msg;
}

void ViewerNode::OnOmniFrame(const omni_frame_t& msg) {
  SawUtime(msg.utime);
  if (!have_panorama_channel_) pending_frame_ = msg;
}

void ViewerNode::OnLandmarks(const void* data, size_t size) {
  std::string error;
  const auto msg = glue::Decode<landmark_set_t>(data, size, &error);
  if (!msg) {
    bus_.CountDecodeError(error);
    return;
  }
  if (msg->panorama_width_px <= 0 || msg->panorama_height_px <= 0) {
    Reject("landmark panorama size", bus_.current().channel + ": " + std::to_string(msg->panorama_width_px) + "x" +
                                         std::to_string(msg->panorama_height_px));
    return;
  }
  SawUtime(msg->utime);
  viewer::LandmarkMarks& marks = scene_.landmarks[bus_.current().channel];
  marks.utime = msg->utime;
  marks.method = MethodName(msg->method);
  marks.panorama_width_px = msg->panorama_width_px;
  marks.panorama_height_px = msg->panorama_height_px;
  marks.bearings_rad.clear();
  marks.rows_px.clear();
  for (int i = 0; i < msg->nlandmarks; ++i) {
    if (!std::isfinite(msg->bearings_rad[i])) continue;
    marks.bearings_rad.push_back(msg->bearings_rad[i]);
    marks.rows_px.push_back(msg->rows_px[i]);
  }
}

void ViewerNode::OnHomingVector(const homing_vector_t& msg) {
  SawUtime(msg.utime);
  viewer::HomingView h;
  h.utime = msg.utime;
  h.valid = msg.valid && std::isfinite(msg.direction_rad);
  h.direction_rad = msg.direction_rad;
  h.magnitude = msg.magnitude;
  h.compass_rotation_rad = msg.compass_rotation_rad;
  h.landmarks_used = msg.nlandmarks_used;
  h.method = MethodName(msg.method);
  h.alv_variant = msg.alv_variant;
  scene_.homing = h;
}

void ViewerNode::OnPlaceCellMatch(const place_cell_match_t& msg) {
  SawUtime(msg.utime);
  if (msg.cell_id < 0) return;  // nothing matched
  if (!std::isfinite(msg.x_m) || !std::isfinite(msg.y_m)) {
    Reject("non-finite place cell", bus_.current().channel);
    return;
  }
  scene_.matches.push_back({msg.utime, msg.cell_id, msg.x_m, msg.y_m, msg.theta_rad, msg.distance, msg.score});
  if (static_cast<int>(scene_.matches.size()) > config_.max_place_cell_matches) {
    scene_.matches.erase(scene_.matches.begin(),
                         scene_.matches.begin() + (scene_.matches.size() - config_.max_place_cell_matches));
  }
}

void ViewerNode::OnScan(const laser_scan_t& msg) {
  SawUtime(msg.utime);
  viewer::ScanView scan;
  scan.utime = msg.utime;
  scan.mount = {msg.sensor_x_m, msg.sensor_y_m, msg.sensor_theta_rad};
  scan.points.reserve(msg.nranges);
  for (int i = 0; i < msg.nranges; ++i) {
    const float r = msg.ranges_m[i];
    if (!(r >= msg.range_min_m) || !(r < msg.range_max_m)) continue;
    const double a = msg.angle_min_rad + i * static_cast<double>(msg.angle_increment_rad);
    scan.points.emplace_back(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)));
  }
  scene_.scan = std::move(scan);
}

void ViewerNode::Reject(const std::string& reason, const std::string& detail) {
  const int64_t n = ++rejected_[reason];
  if (n <= 5 || n % 100 == 0) std::cerr << "viewer: refused #" << n << " (" << reason << "): " << detail << "\n";
}

int64_t ViewerNode::rejected_total() const {
  int64_t n = 0;
  for (const auto& [_, k] : rejected_) n += k;
  return n;
}

void ViewerNode::UpdatePanorama() {
  if (!pending_frame_) return;
  const omni_frame_t frame = std::move(*pending_frame_);
  pending_frame_.reset();
  viewer::PanoramaView view;
  view.utime = frame.utime;
  if (frame.kind == omni_frame_t::PANORAMA) {
    try {
      view.image = glue::FrameToImage(frame);
    } catch (const std::exception& e) {
      Reject("undecodable image", config_.panorama_channel + ": " + e.what());
      return;
    }
    view.bearing_col0_rad = frame.bearing_col0_rad;
    view.source = config_.panorama_channel;
  } else {
    auto panorama = frames_to_panoramas_.Convert(frame);
    if (!panorama) {
      Reject(frames_to_panoramas_.reason(), config_.omni_channel + ": " + frames_to_panoramas_.detail());
      return;
    }
    view.image = *panorama;
    view.bearing_col0_rad = config_.panorama.bearing_col0_rad;
    view.source = config_.omni_channel + " (unwrapped)";
  }
  scene_.panorama = std::move(view);
}

const viewer::ViewerScene& ViewerNode::Scene() {
  UpdatePanorama();
  scene_.channel_counts.clear();
  for (const auto& [ch, s] : bus_.stats()) {
    if (ch.rfind(config_.channel_prefix, 0) == 0) scene_.channel_counts[ch] = static_cast<int64_t>(s.received);
  }
  scene_.rejected = static_cast<int64_t>(bus_.total_errors()) + rejected_total();
  return scene_;
}

void ViewerNode::Report(std::ostream& out) const {
  out << "viewer: " << scene_.tracks.size() << " pose channels, " << scene_.matches.size() << " place-cell matches, "
      << scene_.map_points.size() << " map points, "
      << (scene_.grid ? std::to_string(scene_.grid->width) + " x " + std::to_string(scene_.grid->height) + " grid cells, " : std::string("no grid, "))
      << jumps_ << " laser SLAM corrections marked, " << rejected_total() << " refused";
  for (const auto& [reason, n] : rejected_) out << "; " << reason << ": " << n;
  out << "\n";
}

}  // namespace snapnav::processes
