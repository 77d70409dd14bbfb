#pragma once
// laser-slam's occupancy grid on the bus (issue 22, "maps out"): the scans it mapped with, each
// inserted at its pose into MRPT's grid with the code map-export uses (nav::OccupancyGridBuilder),
// published as occupancy_grid_t every `every_s` of message time and whenever a map_request_t
// arrives on the request channel (map-export --live). In --mode localize the fixed map is
// published instead (SetFixed).
//
// With the graph back end the grid follows the graph's corrections: the keyframes' scans are kept
// (AddKeyframeScan), and after a correction (Corrected) the grid is rebuilt from them at the
// optimized keyframe poses before it is next published (once per publication at most, however
// many corrections came between), the scans inserted since then added at their live poses.
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <vector>
#include <optional>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/handler_problems.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/map_request_t.hpp"
#include "snapnav/nav/slam/occupancy_grid.hpp"

namespace snapnav::processes {

struct GridConfig {
  std::string channel;          // occupancy_grid_t out; empty: no grid
  std::string request_channel;  // map_request_t in: publish now
  double every_s = 5;           // publish every this much message time [s]; 0: on request only
  nav::OccupancyGridOptions grid;
  // A scan is inserted when the robot moved or turned this much since the last one inserted (a
  // robot standing still adds nothing; 0 and 0: every mapped scan).
  double keyframe_m = 0.05;
  double keyframe_rad = 0.0872665;  // 5 deg
  // The live grid's memory bound: scans that would grow it beyond this are skipped (counted).
  static constexpr int64_t kMaxCells = 40'000'000;  // 40 MB of MRPT cells: 316 m x 316 m at 5 cm

  // [channels] grid, grid_request and the [grid] section; bad values are glue::ConfigError.
  static GridConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Print(std::ostream& out) const;
};

class GridPublisher {
 public:
  // `source` names the maker in the message ("laser_slam", "map_file:PATH").
  GridPublisher(glue::Bus& bus, const GridConfig& config, std::string source, glue::HandlerProblems& problems);

  // A scan the SLAM mapped with, at its pose: inserted if it moved enough since the last one.
  void AddScan(const laser_scan_t& msg, const nav::Pose2& robot_pose);
  // The graph back end: the scan of keyframe `keyframe` (kept for rebuilding), and a correction
  // of the graph: before the next publication the grid is rebuilt from the kept scans, each at
  // keyframe_poses()[its keyframe] (the graph's optimized poses then).
  void SetKeyframePoses(std::function<std::vector<nav::Pose2>()> keyframe_poses) { keyframe_poses_ = std::move(keyframe_poses); }
  void AddKeyframeScan(int keyframe, const laser_scan_t& msg);
  void Corrected() { rebuild_due_ = !keyframe_scans_.empty(); }
  int64_t rebuilds() const { return rebuilds_; }
  double last_rebuild_ms() const { return last_rebuild_ms_; }
  size_t keyframe_scans() const { return keyframe_scans_.size(); }
  // A fixed map (--mode localize): published as it is; AddScan is then ignored.
  void SetFixed(const nav::OccupancyCells& cells);
  // After a scan: publishes if every_s passed since the last grid (or since the first scan).
  void AfterScan(int64_t utime);

  int64_t published() const { return published_; }
  int64_t requests() const { return requests_; }
  int64_t inserted() const { return added_; }  // scans AddScan inserted
  // Time of a publication (the grid's cells, the message, the send; a rebuild not included).
  double mean_publish_ms() const { return published_ > 0 ? publish_ms_ / static_cast<double>(published_) : 0.0; }
  double max_publish_ms() const { return max_publish_ms_; }
  double mean_insert_ms() const { return inserted() > 0 ? insert_ms_ / static_cast<double>(inserted()) : 0.0; }
  void Report(std::ostream& out) const;

 private:
  void OnRequest(const map_request_t& msg);
  void Publish(int64_t utime);
  void Rebuild();
  nav::OccupancyGridOptions BuilderOptions() const;

  glue::Bus& bus_;
  GridConfig config_;
  std::string source_;
  glue::HandlerProblems& problems_;
  nav::OccupancyGridBuilder builder_;
  std::optional<nav::OccupancyCells> fixed_;
  std::optional<nav::Pose2> last_inserted_;
  int64_t first_utime_ = 0, last_utime_ = 0, last_published_utime_ = 0;
  bool pending_request_ = false;
  int64_t published_ = 0, requests_ = 0;
  double insert_ms_ = 0, publish_ms_ = 0, max_publish_ms_ = 0;
  int64_t last_cells_ = 0;
  int64_t added_ = 0;
  std::function<std::vector<nav::Pose2>()> keyframe_poses_;
  std::map<int, nav::GridScan> keyframe_scans_;  // robot_pose unset: taken from keyframe_poses_ when rebuilt
  bool rebuild_due_ = false;
  int64_t rebuilds_ = 0;
  double last_rebuild_ms_ = 0;
};

}  // namespace snapnav::processes
