#pragma once
// Laser SLAM's graph back end (nav::GraphSlam) over a recorded log, as RunSlam runs the EKF: the
// pose of every scan after the last optimization (the map's trajectory) and as published at the
// time (the live pose), the front end's and the back end's time per scan apart, and every loop
// closure with its verdict against the reference (a closure is wrong when the pose it gives the
// new keyframe from the old keyframe's reference pose is more than max_error_m or max_error_rad
// off the new keyframe's reference pose: its two poses are that far apart in the reference).
#include <cstdint>
#include <string>
#include <vector>

#include "slam_log.hpp"
#include "snapnav/nav/slam/graph_slam.hpp"

namespace snapnav::eval {

struct GraphSlamRun {
  SlamRun run;                    // slam: the optimized pose of every scan; updates: the front end's
  std::vector<nav::Pose2> live;   // the pose published at each scan (GraphSlam::scan_pose then)
  double front_seconds = 0;       // in GraphSlam::FrontEnd (the robust front end, the keyframe decision)
  double back_seconds = 0;        // in GraphSlam::BackEnd (graph, loop search, optimization)
  double back_max_ms = 0;         // the slowest scan's back end
  // The scan thread's time per scan (FrontEnd + BackEnd: with graph_loop_async the back end only
  // adds keyframes, starts jobs and applies them, waiting for the worker if it is not done) [ms].
  std::vector<double> scan_ms;
  double scan_p99_ms() const;
  double scan_max_ms() const;
  std::vector<nav::LoopClosure> closures;
  int keyframes = 0;
  int64_t corrections = 0, loop_accepted = 0, loop_rejected = 0;
  double largest_correction_m = 0;
  double front_ms_per_scan() const { return run.slam.empty() ? 0 : 1000 * front_seconds / static_cast<double>(run.slam.size()); }
  double back_ms_per_scan() const { return run.slam.empty() ? 0 : 1000 * back_seconds / static_cast<double>(run.slam.size()); }
};

// Runs dead reckoning and the graph back end in lockstep over the log; run.map is the optimized map
// (with graph.loop_async, the last job applied at the end: GraphSlam::Flush).
// speed > 0: the scans paced at speed times the log's rate (each handed over no earlier than its
// time since the first scan / speed, as a live run at that rate; the outputs are the same); 0: as
// fast as possible.
GraphSlamRun RunGraphSlam(const SlamLog& log, const nav::LaserSlamOptions& front_end, const nav::GraphSlamOptions& graph,
                          double speed = 0);

// The loop closures of a run against a reference.
struct ClosureCheck {
  int candidates = 0;
  int accepted = 0;    // in the graph at the end
  int rejected = 0;    // rejected, expired, or switched off
  int wrong = 0;       // accepted and wrong
  int unchecked = 0;   // accepted, a scan without a reference pose
  int switched_off = 0;
  int rejected_right = 0;  // rejected although the reference agrees (within the bounds): missed closures
  std::vector<std::string> wrong_closures;  // "keyframe a (scan i) -> b (scan j): 0.62 m, 1.2 deg" each
};
ClosureCheck CheckClosures(const GraphSlamRun& run, const Reference& reference, double max_error_m = 0.5,
                           double max_error_rad = 5 * nav::kRadPerDeg);

// Writes every candidate (closures.csv: keyframes, scans, outcome, score, fit, ambiguity, Mahalanobis
// distance, the graph's std. dev., the match and its error against the reference where there is one).
void WriteClosuresCsv(const std::string& path, const GraphSlamRun& run, const Reference& reference);

}  // namespace snapnav::eval
