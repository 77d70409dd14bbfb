#pragma once
// The laser SLAM evaluation of one log (eval-slam) and the real-data suite (eval-slam --suite):
// every entry of a suite file run with one laser SLAM config beside the thesis configuration,
// MRPT's icp-slam and dead reckoning, against each log's reference.
//
// A suite file (config/slam_suite.ini) has a [suite] section and one section per run:
//   [suite]
//   data = ../../shared/data            ; folder of the entries' relative paths (relative to the file)
//   raw_like_tool = ../../shared/tools/carmen_raw_like.py
//   laser_slam_config = laser_slam.ini  ; relative to the file
//   icp_slam = true                     ; run MRPT's icp-slam beside it
//   [aces-n1]                           ; a run: its name
//   kind = carmen_corrected             ; carmen | carmen_corrected | rawlog
//   log = laser/carmen/aces-corrected.log.gz
//   reference = corrected               ; a reference log or CSV | corrected (the log itself) | icp-slam
//   noise = 1                           ; carmen_corrected: raw_like_tool's --noise, --seed, --every
//   seed = 1
//   every = 1
//   goal_ate_m = 0.30                   ; the laser SLAM's ATE goal [m] (0: none)
//   no_worse_than_dead_reckoning = true ; also a goal: ATE <= dead reckoning's
//   graph_goal_ate_m = 0.10             ; optional: the graph back end's ATE goal [m] (0 or absent: none)
// [suite] graph = true|false (optional, default true): the graph back end runs beside the EKF (its
// table: ATE, RPE over 1 m and 10 m, loop closures accepted / rejected / wrong, ms per scan).
// A run whose data file (or the raw-like tool) is missing is skipped with a line naming it.
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "icp_slam.hpp"
#include "slam_graph.hpp"
#include "slam_log.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"

namespace snapnav::eval {

// An ATE figure (RMSE and max after SE(2) alignment) over the scans paired with the reference.
struct AteFigure {
  bool measured = false;
  int pairs = 0;
  double rmse_m = 0, max_m = 0;
};
AteFigure MeasureAte(const std::vector<nav::Pose2>& estimate, const SlamRun& run, const Reference& reference);

// What the laser SLAM decided over a run (LaserSlamUpdate::outcome and prediction, per scan).
struct OutcomeCounts {
  int64_t accepted = 0, gated = 0, ambiguous = 0, no_match = 0, stale_predictions = 0, catch_up_predictions = 0,
          widened = 0;
};
OutcomeCounts CountOutcomes(const SlamRun& run);

struct SuiteEntry {
  std::string name;
  std::string kind;       // carmen | carmen_corrected | rawlog
  std::string log;        // resolved path
  std::string reference;  // resolved path, or "icp-slam"
  int noise_seed = 1, every = 1;
  double noise = 0;
  double goal_ate_m = 0;
  bool no_worse_than_dead_reckoning = false;
  double graph_goal_ate_m = 0;  // the graph back end's (issue 22's goals)
  // CARMEN kinds: the laser's maximum range as log-import's --flaser-max-range-m (farther readings
  // become no-returns: a shorter-range laser, as a Hokuyo URG's 5.6 m) [m]; 0: the log's own.
  // icp-slam, which reads the CARMEN log itself, does not run on such an entry.
  double laser_max_range_m = 0;
};

struct Suite {
  std::string path;
  std::string raw_like_tool;     // resolved
  std::string laser_slam_config; // resolved
  bool icp_slam = true;
  bool graph = true;             // run the graph back end beside the EKF
  std::vector<SuiteEntry> entries;
};
// Reads a suite file; a missing or unknown key, or a bad value, is a glue::ConfigError naming the
// file, line and key.
Suite LoadSuite(const std::string& path);

// Relative pose error (Kuemmerle et al. 2009) over segments of 1 m and 10 m of the reference's travel.
struct RpeFigure {
  bool measured = false;
  double translation_1m_m = 0, rotation_1m_deg = 0;    // RMSE over the 1 m segments
  double translation_10m_m = 0, rotation_10m_deg = 0;  // ... over the 10 m segments (0 if none)
  int segments_10m = 0;
};
RpeFigure MeasureRpe(const std::vector<nav::Pose2>& estimate, const SlamRun& run, const Reference& reference);

// One run of the suite.
struct SuiteResult {
  SuiteEntry entry;
  bool skipped = false;
  std::string skip_reason;
  int64_t scans = 0;
  AteFigure slam, thesis, dead_reckoning, icp_slam;
  double slam_ms_per_scan = 0, thesis_ms_per_scan = 0, icp_slam_ms_per_scan = 0;
  bool icp_slam_ran = false;  // icp-slam ran on this entry (the suite's icp_slam, or icp-slam as the reference)
  OutcomeCounts outcomes;
  bool pass = false;           // every goal of the entry met
  std::string failed;          // which goals failed
  std::string png;             // the trajectory figure (relative to the output folder)
  // The configured back end ("ekf" or "graph": what `slam` above is), and both back ends apart.
  std::string backend = "ekf";
  AteFigure ekf;
  RpeFigure ekf_rpe;
  double ekf_ms_per_scan = 0;
  bool graph_ran = false;
  AteFigure graph, graph_live;    // the optimized trajectory, and the pose as published at each scan
  RpeFigure graph_rpe;
  double graph_front_ms_per_scan = 0, graph_back_ms_per_scan = 0, graph_back_max_ms = 0;
  int keyframes = 0;
  int64_t corrections = 0;
  double largest_correction_m = 0;
  ClosureCheck closures;
  bool graph_pass = false;        // the graph back end met graph_goal_ate_m, no wrong closure, <= DR if asked
  std::string graph_failed;
  std::string graph_png;          // the graph's map and trajectory over the reference
  // Map consistency (ComputeMapConsistency: the median distance of a scan's points to the scans
  // seen on a revisit), over the scans the reference has: a figure that needs no reference, and the
  // reference's own, which tells a SLAM that blurs the map from a reference that is off itself.
  // nullopt where no scan is seen again.
  std::optional<double> ekf_consistency_m, graph_consistency_m, reference_consistency_m;
  // Odometry's systematic errors as the EKF's scans estimated them and as the reference implies.
  OdometryFigure odometry, reference_odometry;
  // The reference's poses its scans contradict (CheckReference; the run's reference_suspects.csv).
  ReferenceCheck reference_check;
};

struct SuiteOptions {
  std::vector<std::string> overrides;  // --set KEY=VALUE of [laser_slam]
  std::vector<std::string> only;       // run only these entries (empty: all)
  IcpSlamOptions icp;
  bool progress = true;
};

// Runs every entry into out_dir/NAME/ (the raw-like log, the LCM log, icp-slam's work files,
// trajectory.png) and writes out_dir/suite.md, suite.csv and summary.json. Returns the results.
std::vector<SuiteResult> RunSuite(const Suite& suite, const std::string& out_dir, const SuiteOptions& options);

// The suite table as Markdown (suite.md's table).
void WriteSuiteTable(std::ostream& out, const std::vector<SuiteResult>& results);
// Odometry's systematic errors per run, the EKF's estimate and the reference's (suite.md).
void WriteOdometryTable(std::ostream& out, const std::vector<SuiteResult>& results);
// The graph back end beside the EKF as Markdown (suite.md's second table).
void WriteGraphTable(std::ostream& out, const std::vector<SuiteResult>& results);

}  // namespace snapnav::eval
