#pragma once
// laser-slam --mode localize: the robot's pose in a saved map (nav::MapLocalizer: a global search
// over the whole map while lost, then laser SLAM's EKF and matcher tracking against the fixed map).
// ODOMETRY predicts, each LASER_SCAN updates; while localized one pose_t per scan on the pose
// channel (estimator "laser_localize", frame "map": the saved map's frame), and on every scan a
// localization_status_t (lost / localized, the scan's fit, the last global search's score and
// ambiguity). The saved map goes out on the grid channel at start, every [grid] every_s and on
// request, so the viewer draws the robot in it.
#include <cstdint>
#include <iosfwd>
#include <string>

#include "grid_publisher.hpp"
#include "laser_slam_node.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/handler_problems.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/map_localizer.hpp"
#include "snapnav/odometry_t.hpp"

namespace snapnav::processes {

class LocalizeNode {
 public:
  // `map`: the saved map's cells, read from `map_path` (named in the status and the grid's source).
  // Throws std::invalid_argument when the map cannot be localized in (no walls, no free cells).
  LocalizeNode(glue::Bus& bus, const LaserSlamConfig& config, const nav::OccupancyCells& map, const std::string& map_path);

  int64_t scans() const { return scans_; }
  int64_t odometry() const { return odometry_; }
  int64_t poses_published() const { return poses_published_; }
  int64_t statuses_published() const { return statuses_published_; }
  const nav::MapLocalizer& localizer() const { return localizer_; }
  const GridPublisher& grid() const { return grid_; }
  int64_t skipped(const std::string& reason) const { return problems_.skipped(reason); }
  int64_t internal_errors() const { return problems_.internal_errors(); }
  double mean_update_ms() const { return updates_ > 0 ? update_ms_ / static_cast<double>(updates_) : 0.0; }
  double max_search_ms() const { return max_search_ms_; }
  void Report(std::ostream& out) const;

 private:
  void OnOdometry(const odometry_t& msg);
  void OnScan(const laser_scan_t& msg);
  void HandleOdometry(const odometry_t& msg);
  void HandleScan(const laser_scan_t& msg);

  glue::Bus& bus_;
  LaserSlamConfig config_;
  std::string map_path_;
  glue::HandlerProblems problems_;
  nav::MapLocalizer localizer_;
  GridPublisher grid_;
  bool odometry_seen_ = false;
  int64_t scans_ = 0, odometry_ = 0, updates_ = 0, poses_published_ = 0, statuses_published_ = 0;
  double update_ms_ = 0, search_ms_total_ = 0, max_search_ms_ = 0, last_search_ms_ = 0;
  nav::GlobalSearchResult last_global_;
};

}  // namespace snapnav::processes
