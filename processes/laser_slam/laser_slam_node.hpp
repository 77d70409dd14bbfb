#pragma once
// laser-slam: libnav's 2D laser SLAM (EKF on the pose, ICP against a point map) on the bus.
// ODOMETRY increments predict, each LASER_SCAN updates; one pose_t per scan on POSE_LASER_SLAM
// and one laser_slam_status_t on LASER_SLAM_STATUS (the match's outcome: accepted, gated,
// ambiguous, no match; how sure it is), and every n-th updating scan the map as point_map_t on
// POINT_MAP. With backend = graph, after each correction of the graph a pose_correction_t on
// LASER_SLAM_CORRECTION: how to move every pose published so far to where the graph now puts it.
//
// Order: messages are processed in arrival order, never reordered by utime. A log (and the
// simulator) is time ordered, so an odometry increment that ends before a scan arrives before
// it. Live, an increment that arrives after a scan it precedes in time is applied to the next
// scan's prediction instead (counted as "late odometry"; the map does not change).
//
// Frames: the first odometry message only fixes the start (its increment is relative to a
// message never seen): the map frame is the odometry frame at the start, so POSE_LASER_SLAM is
// comparable with POSE_DEAD_RECKONING and, in the simulator, with the ground truth. A scan
// before any odometry starts the filter at the origin instead.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include "grid_publisher.hpp"
#include "localize_config.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/handler_problems.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/laser_scan_checks.hpp"
#include "graph_slam_config.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/slam/pose_corrections.hpp"
#include "snapnav/odometry_t.hpp"

namespace snapnav::processes {

struct LaserSlamConfig {
  std::string odometry_channel;  // odometry_t in
  std::string scan_channel;      // laser_scan_t in
  std::string pose_channel;      // pose_t out
  std::string map_channel;       // point_map_t out
  std::string status_channel;    // laser_slam_status_t out
  std::string correction_channel;  // pose_correction_t out (backend = graph): after each correction
  nav::LaserSlamOptions options;
  int map_every_n_scans = 10;  // publish the map after every n-th updating scan; 0: never
  GridConfig grid;             // the occupancy grid on the bus (grid.channel empty: none)
  LocalizeConfig localize;     // --mode localize (localize.options.tracking = options)
  SlamBackend backend = SlamBackend::kEkf;  // [laser_slam] backend
  nav::GraphSlamOptions graph;               // [laser_slam] graph_* (backend = graph)

  // Reads [channels] and [laser_slam]; every key is required, unknown keys and invalid values
  // are glue::ConfigError.
  static LaserSlamConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Print(std::ostream& out) const;
};

// Limits of a scan's beam count and range_max_m (glue/laser_scan_checks.hpp, shared with fused-slam).
using glue::kMaxLaserBeams;
using glue::kMaxLaserRangeM;

class LaserSlamNode {
 public:
  LaserSlamNode(glue::Bus& bus, const LaserSlamConfig& config);

  int64_t scans() const { return scans_; }                  // decoded scans on the scan channel, skipped ones included
  int64_t updates() const { return updates_; }              // scans given to LaserSlam::Update
  int64_t measured() const { return measured_; }            // updates whose ICP measurement was accepted
  int64_t gated() const { return gated_; }                  // updates whose match was beyond the gate
  int64_t wall_measured() const { return wall_measured_; }  // updates whose heading the walls measured
  int64_t ambiguous() const { return ambiguous_; }          // updates whose match was ambiguous
  int64_t no_match() const { return no_match_; }            // updates with no usable match
  int64_t odometry() const { return odometry_; }            // decoded odometry messages, skipped ones included
  int64_t late_odometry() const { return late_odometry_; }  // older than the last scan, applied anyway
  int64_t poses_published() const { return poses_published_; }
  int64_t maps_published() const { return maps_published_; }
  int64_t corrections_published() const { return corrections_published_; }
  // The occupancy grid's publisher; nullptr without a grid channel.
  const GridPublisher* grid() const { return grid_ ? &*grid_ : nullptr; }
  // Scans and odometry messages skipped, by reason ("no ranges", "no valid points", ...).
  const std::map<std::string, int64_t>& skipped() const { return problems_.skipped(); }
  int64_t skipped(const std::string& reason) const { return problems_.skipped(reason); }
  // Unexpected exceptions caught in a handler (e.g. a failed publish); that message's work is lost.
  int64_t internal_errors() const { return problems_.internal_errors(); }
  // Mean wall time of LaserSlam::Update per updating scan [ms] (a statistic only; 0 before any).
  double mean_update_ms() const { return updates_ > 0 ? update_ms_total_ / static_cast<double>(updates_) : 0.0; }
  // The filter (with backend = graph, the graph back end's front end); nullptr before the first usable message.
  const nav::LaserSlam* slam() const { return slam_ ? &*slam_ : graph_ ? &graph_->front_end() : nullptr; }
  // The graph back end (backend = graph); nullptr otherwise or before the first usable message.
  const nav::GraphSlam* graph() const { return graph_ ? &*graph_ : nullptr; }
  // The node's counts, one line each.
  void Report(std::ostream& out) const;

 private:
  void OnOdometry(const odometry_t& msg);
  void OnScan(const laser_scan_t& msg);
  void HandleOdometry(const odometry_t& msg);
  void HandleScan(const laser_scan_t& msg);
  // Counts a skipped message (a malformed one also as rejected on its channel; glue::HandlerProblems).
  void Skip(const std::string& reason, const std::string& detail, bool malformed) {
    problems_.Skip(reason, detail, malformed);
  }
  void PublishMap(int64_t utime);
  void PublishStatus(int64_t utime, const nav::LaserSlamUpdate* u);
  void PublishCorrection(int64_t utime);

  glue::Bus& bus_;
  LaserSlamConfig config_;
  std::optional<nav::LaserSlam> slam_;   // backend = ekf
  std::optional<nav::GraphSlam> graph_;  // backend = graph
  void Start(const nav::Pose2& pose);    // makes the one of the two the config asks for
  bool started() const { return slam_ || graph_; }
  int64_t last_correction_utime_ = 0;    // the scan of the graph's last correction
  nav::PublishedPoses published_;        // ... per range of publication times: for the correction tables
  bool odometry_seen_ = false;
  int64_t last_scan_utime_ = 0;
  int64_t scans_ = 0, updates_ = 0, measured_ = 0, odometry_ = 0, late_odometry_ = 0;
  int64_t gated_ = 0, ambiguous_ = 0, no_match_ = 0, wall_measured_ = 0;
  int64_t poses_published_ = 0, maps_published_ = 0, corrections_published_ = 0;
  double update_ms_total_ = 0.0;
  glue::HandlerProblems problems_;
  std::optional<GridPublisher> grid_;
};

}  // namespace snapnav::processes
