#include "slam_graph.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "snapnav/nav/dead_reckoning.hpp"

namespace snapnav::eval {
namespace {

using Clock = std::chrono::steady_clock;

// The closure's error against the reference, if both scans have a reference pose.
std::optional<std::pair<double, double>> ClosureError(const nav::LoopClosure& c, const GraphSlamRun& run,
                                                      const Reference& reference) {
  // The scan's reference pose; for a scan the reference leaves out (CSAIL's corrected log holds every
  // 5th scan or so), the nearest within 5 scans that it holds, moved by the run's motion between them.
  const size_t n = run.run.utime.size();
  const auto at = [&](int64_t scan) -> std::optional<nav::Pose2> {
    if (scan < 1 || static_cast<size_t>(scan) > n) return std::nullopt;
    const size_t i = static_cast<size_t>(scan - 1);
    for (size_t d = 0; d <= 5; ++d) {
      for (const size_t j : {i - d, i + d}) {
        if (j >= n) continue;  // (i - d wraps around below 0)
        const auto ref = reference.Find(run.run.ranges_key[j], run.run.utime[j]);
        if (ref) return ref->Compose(run.run.slam[j].Between(run.run.slam[i]));
      }
    }
    return std::nullopt;
  };
  const auto from = at(c.from_scan), to = at(c.to_scan);
  if (!from || !to) return std::nullopt;
  const nav::Pose2 claimed = from->Compose(c.relative);
  return std::make_pair(std::hypot(claimed.x_m - to->x_m, claimed.y_m - to->y_m),
                        std::abs(nav::WrapAngle(claimed.theta_rad - to->theta_rad)));
}

}  // namespace

GraphSlamRun RunGraphSlam(const SlamLog& log, const nav::LaserSlamOptions& front_end, const nav::GraphSlamOptions& graph,
                          double speed) {
  nav::GraphSlam slam(front_end, graph);
  nav::DeadReckoning dr({});
  GraphSlamRun r;
  r.run.slam.reserve(static_cast<size_t>(log.scans));
  std::vector<std::pair<int, nav::Pose2>> anchors;
  std::optional<int64_t> first_utime;
  Clock::time_point started;
  for (const SlamStep& step : log.steps) {
    if (!step.is_scan) {
      slam.Predict(step.odometry_delta, step.utime);
      dr.AddOdometry(step.odometry_delta);
      continue;
    }
    if (speed > 0) {
      if (!first_utime) {
        first_utime = step.utime;
        started = Clock::now();
      }
      std::this_thread::sleep_until(started + std::chrono::microseconds(static_cast<int64_t>(
                                                  static_cast<double>(step.utime - *first_utime) / speed)));
    }
    const auto t0 = Clock::now();
    nav::GraphSlamUpdate u = slam.FrontEnd(step.points, step.utime);
    const auto t1 = Clock::now();
    slam.BackEnd(&u);
    const auto t2 = Clock::now();
    r.front_seconds += std::chrono::duration<double>(t1 - t0).count();
    const double back = std::chrono::duration<double>(t2 - t1).count();
    r.back_seconds += back;
    r.back_max_ms = std::max(r.back_max_ms, 1000 * back);
    r.scan_ms.push_back(1000 * std::chrono::duration<double>(t2 - t0).count());
    if (u.corrected) r.largest_correction_m = std::max(r.largest_correction_m, u.correction_m);
    r.run.updates.push_back(u.front_end);
    r.run.utime.push_back(step.utime);
    r.run.ranges_key.push_back(step.ranges_key);
    r.live.push_back(slam.scan_pose());
    r.run.dead_reckoning.push_back(dr.pose());
    anchors.push_back({u.anchor_keyframe, u.anchor_relative});
  }
  {
    const auto t0 = Clock::now();
    const nav::GraphSlamUpdate u = slam.Flush();
    r.back_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    if (u.corrected) r.largest_correction_m = std::max(r.largest_correction_m, u.correction_m);
  }
  for (const auto& [k, rel] : anchors) r.run.slam.push_back(slam.OptimizedPose(k, rel));
  r.run.update_seconds = r.front_seconds + r.back_seconds;
  r.run.map = slam.Map();
  r.closures = slam.closures();
  r.keyframes = slam.keyframes();
  r.corrections = slam.corrections();
  r.loop_accepted = slam.loop_accepted();
  r.loop_rejected = slam.loop_rejected();
  return r;
}

double GraphSlamRun::scan_p99_ms() const {
  if (scan_ms.empty()) return 0;
  std::vector<double> v = scan_ms;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::ceil(0.99 * static_cast<double>(v.size()))) - 1);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double GraphSlamRun::scan_max_ms() const {
  return scan_ms.empty() ? 0 : *std::max_element(scan_ms.begin(), scan_ms.end());
}

ClosureCheck CheckClosures(const GraphSlamRun& run, const Reference& reference, double max_error_m,
                           double max_error_rad) {
  ClosureCheck check;
  for (const nav::LoopClosure& c : run.closures) {
    ++check.candidates;
    const auto error = ClosureError(c, run, reference);
    const bool right = error && error->first <= max_error_m && error->second <= max_error_rad;
    if (c.outcome == nav::LoopOutcome::kAccepted) {
      ++check.accepted;
      if (!error) {
        ++check.unchecked;
      } else if (!right) {
        ++check.wrong;
        std::ostringstream s;
        s.precision(3);
        s << "keyframe " << c.from_keyframe << " (scan " << c.from_scan << ") -> " << c.to_keyframe << " (scan "
          << c.to_scan << "): " << error->first << " m, " << error->second / nav::kRadPerDeg << " deg";
        check.wrong_closures.push_back(s.str());
      }
    } else if (c.outcome != nav::LoopOutcome::kPending) {
      ++check.rejected;
      check.switched_off += c.outcome == nav::LoopOutcome::kSwitchedOff;
      check.rejected_right += right;
    }
  }
  return check;
}

void WriteClosuresCsv(const std::string& path, const GraphSlamRun& run, const Reference& reference) {
  std::ofstream out(path);
  out << "from_keyframe,to_keyframe,from_scan,to_scan,outcome,score,fit,ambiguity,mahalanobis2,graph_sigma_m,"
         "predicted_x_m,predicted_y_m,predicted_theta_deg,x_m,y_m,theta_deg,reference_error_m,reference_error_deg\n";
  for (const nav::LoopClosure& c : run.closures) {
    const auto error = ClosureError(c, run, reference);
    out << c.from_keyframe << "," << c.to_keyframe << "," << c.from_scan << "," << c.to_scan << ","
        << nav::LoopOutcomeName(c.outcome) << "," << c.score << "," << c.fit << "," << c.ambiguity << ","
        << c.mahalanobis2 << "," << c.graph_sigma_m << "," << c.predicted.x_m << "," << c.predicted.y_m << ","
        << c.predicted.theta_rad / nav::kRadPerDeg << "," << c.relative.x_m << "," << c.relative.y_m << ","
        << c.relative.theta_rad / nav::kRadPerDeg << ",";
    if (error) out << error->first << "," << error->second / nav::kRadPerDeg;
    else out << ",";
    out << "\n";
  }
}

}  // namespace snapnav::eval
