#pragma once
// fused-slam: fused visual + laser SLAM (nav::FusedSlam; thesis 1.2, 5, 6.3.3) on the bus.
// ODOMETRY increments predict, each LASER_SCAN updates the laser EKF, each POSE_PLACE_CELLS pose
// (the placecells process' localization, pose with covariance) is a second measurement behind a
// Mahalanobis gate; agreeing rejected measurements relocalise the filter (kidnapping).
//
// Out: the fused pose (pose_t, estimator "fused_slam", frame "map") on POSE_EKF
//   - on every scan, with the scan's utime;
//   - on every visual measurement it used or refused, with that measurement's utime and the
//     filter's pose at that time (the current pose moved back by the odometry since), so the
//     latency from an omni frame to the fused pose shows by matching utimes;
// the map (point_map_t, estimator "fused_slam") every n-th updating scan, and a
// fused_slam_status_t (counts, state, last outcome) after every visual measurement and every
// n-th scan.
//
// Frame: the place memory's (world) frame. start = odometry: the filter starts at the first
// odometry message's cumulative pose (in the simulator the odometry starts at the true start
// pose in the scene frame: the memory's frame when it was explored at ground-truth poses);
// start = visual: it starts at the first visual measurement (its pose, its covariance floored),
// for a robot whose odometry frame is not the memory's; odometry and scans before it are counted
// and dropped.
//
// Order: messages are processed in arrival order. A visual measurement arrives late (the view and
// the query take ~70 ms): it is carried forward by the odometry since its utime (max_fix_age_s).
// Odometry older than the last accepted is skipped (counted); after 5 in a row its time restarts
// (glue::MessageClock: a clock jump, a second log) and so does the filter, at its pose and
// covariance with a new map (its odometry history is in the old time). Utimes beyond 0..2^62 us,
// odometry increments beyond glue's bounds and positions beyond glue::kMaxPositionM are skipped.
// The placecells process should localize without its distance filter (or with a wide one), so
// that its fixes do not follow a lost filter's prediction.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/handler_problems.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/message_clock.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/fused_slam.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {

enum class FusedStart { kOdometry, kVisual };
const char* FusedStartName(FusedStart start);  // "odometry", "visual"

struct FusedSlamConfig {
  std::string odometry_channel;  // odometry_t in
  std::string scan_channel;      // laser_scan_t in
  std::string visual_channel;    // pose_t in (place cells)
  std::string pose_channel;      // pose_t out
  std::string map_channel;       // point_map_t out
  std::string status_channel;    // fused_slam_status_t out
  FusedStart start = FusedStart::kOdometry;
  nav::FusedSlamOptions options;
  int map_every_n_scans = 10;     // publish the map after every n-th updating scan; 0: never
  int status_every_n_scans = 10;  // a status after every n-th scan (and every visual measurement); 0: visual only

  // Reads [channels], [laser_slam] (as laser_slam.ini) and [fused_slam]; every key is required,
  // unknown keys and invalid values are glue::ConfigError.
  static FusedSlamConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  // The effective configuration, as an INI file FromIni reads back (channels with their prefix).
  void Print(std::ostream& out) const;
};

class FusedSlamNode {
 public:
  FusedSlamNode(glue::Bus& bus, const FusedSlamConfig& config);

  int64_t scans() const { return scans_; }        // decoded scans, skipped ones included
  int64_t updates() const { return updates_; }    // scans given to the filter
  int64_t odometry() const { return odometry_; }  // decoded odometry messages, skipped ones included
  int64_t visual() const { return visual_; }      // decoded visual measurements, skipped ones included
  int64_t visual_used() const { return visual_used_; }  // given to the filter (or starting it)
  int64_t poses_published() const { return poses_published_; }
  int64_t maps_published() const { return maps_published_; }
  int64_t statuses_published() const { return statuses_published_; }
  // Messages skipped, by reason ("no ranges", "non-finite visual pose", "waiting for a visual fix", ...).
  const std::map<std::string, int64_t>& skipped() const { return problems_.skipped(); }
  int64_t skipped(const std::string& reason) const { return problems_.skipped(reason); }
  int64_t internal_errors() const { return problems_.internal_errors(); }
  double mean_scan_ms() const { return updates_ > 0 ? scan_ms_total_ / static_cast<double>(updates_) : 0.0; }
  double mean_visual_ms() const { return visual_used_ > 0 ? visual_ms_total_ / static_cast<double>(visual_used_) : 0.0; }
  // The filter; nullptr before it started.
  const nav::FusedSlam* slam() const { return slam_ ? &*slam_ : nullptr; }
  void Report(std::ostream& out) const;

 private:
  void OnOdometry(const odometry_t& msg);
  void OnScan(const laser_scan_t& msg);
  void OnVisual(const pose_t& msg);
  void HandleOdometry(const odometry_t& msg);
  void HandleScan(const laser_scan_t& msg);
  void HandleVisual(const pose_t& msg);
  void Skip(const std::string& reason, const std::string& detail, bool malformed) {
    problems_.Skip(reason, detail, malformed);
  }
  void PublishPose(int64_t utime, const nav::Pose2& pose);
  void PublishMap(int64_t utime);
  void PublishStatus(int64_t utime);

  glue::Bus& bus_;
  FusedSlamConfig config_;
  std::optional<nav::FusedSlam> slam_;
  bool odometry_seen_ = false;
  glue::MessageClock odometry_clock_;  // odometry times in order; restarts after a run of older ones
  int64_t time_restarts_ = 0;
  int8_t last_outcome_ = -1;
  double last_mahalanobis2_ = 0, last_fit_ = 0;
  int64_t scans_ = 0, updates_ = 0, odometry_ = 0, visual_ = 0, visual_used_ = 0;
  int64_t poses_published_ = 0, maps_published_ = 0, statuses_published_ = 0;
  double scan_ms_total_ = 0, visual_ms_total_ = 0;
  glue::HandlerProblems problems_;
};

}  // namespace snapnav::processes
