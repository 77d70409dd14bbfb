#pragma once
// Sections of log-report about a recorded run of the navigation stack, each judged against the
// ground truth: the homing vectors (angular error against the true direction home), the
// place-cell matches (position error of the matched cell), the navigator's progress, and the
// delivery of every message (counts each process published, from the launcher's process logs,
// against what the log holds).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "process_logs.hpp"
#include "results.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/navigator_status_t.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/place_cell_match_t.hpp"

namespace snapnav::report {

// Markdown, flat summary.json entries and PNG files written into the output folder.
struct Section {
  std::string markdown;
  results::Json json = results::Json::object();
};

struct HomingErrors {
  int vectors = 0, valid = 0, evaluated = 0;  // evaluated: valid, ground truth found, not at home
  double mean_deg = 0, median_deg = 0, max_deg = 0;
  double within_45 = 0, within_90 = 0;  // fraction of the evaluated vectors
  std::vector<double> t_s, error_deg;   // per evaluated vector (time since t0)
};
// Angular error of each valid vector: direction_rad (robot frame) against the direction from the
// true pose to `home`; vectors closer than min_distance_m to home are left out.
HomingErrors EvaluateHoming(const std::vector<homing_vector_t>& vectors, const std::vector<nav::StampedPose>& truth,
                            const Eigen::Vector2d& home, int64_t t0_us, double min_distance_m = 0.1);

struct PlaceCellErrors {
  int matches = 0, unmatched = 0, evaluated = 0;
  double mean_m = 0, median_m = 0, max_m = 0;
  std::vector<double> t_s, error_m;
};
// Distance from the matched cell's position to the true position at the view's time.
PlaceCellErrors EvaluatePlaceCells(const std::vector<place_cell_match_t>& matches,
                                   const std::vector<nav::StampedPose>& truth, int64_t t0_us);

// Sections; figures are written into out_dir. `truth` may be empty (nothing to judge against).
Section HomingSection(const std::string& channel, const std::vector<homing_vector_t>& vectors,
                      const std::vector<nav::StampedPose>& truth, const std::optional<Eigen::Vector2d>& home,
                      int64_t t0_us, const std::string& out_dir);
Section PlaceCellSection(const std::string& channel, const std::vector<place_cell_match_t>& matches,
                         const std::vector<nav::StampedPose>& truth, int64_t t0_us, const std::string& out_dir);
Section NavigatorSection(const std::string& channel, const std::vector<navigator_status_t>& statuses,
                         const std::vector<nav::StampedPose>& truth, int64_t t0_us, const std::string& out_dir);

// Each estimator's position error against the ground truth over time, window by window (long runs:
// does the error grow?). Per window of window_s message time: the RMSE of the poses in it (no
// alignment, as the plain ATE). trend_m_per_h: least-squares slope of the window RMSEs; growth_m:
// the mean of the last third of the windows minus the mean of the first third.
struct AteWindows {
  std::vector<double> start_s, rmse_m;  // per window with poses
  std::vector<int> poses;
  double trend_m_per_h = 0, growth_m = 0, max_m = 0, mean_m = 0;
};
AteWindows EvaluateAteWindows(const std::vector<nav::StampedPose>& estimate, const std::vector<nav::StampedPose>& truth,
                              int64_t t0_us, double window_s);
// The table and chart (ate_over_time.png) of every estimator's windows, ate_windows.csv, and the
// JSON keys <channel>_ate_window_{first,last,max,mean}_m, _ate_trend_m_per_h, _ate_growth_m.
Section AteOverTimeSection(const std::map<std::string, std::vector<nav::StampedPose>>& estimates,
                           const std::vector<nav::StampedPose>& truth, int64_t t0_us, double window_s,
                           const std::string& out_dir);

// Per channel: what the processes published (sum over the runs that reported it; a run killed
// by a signal reports nothing, so its channel's count is a lower bound) against what the log
// holds, and what each subscriber received. `recorded`: messages per channel in the log.
struct Delivery {
  std::string channel;
  std::vector<std::string> publishers;
  uint64_t published = 0;
  bool exact = true;  // every run of every publisher reported its counts
  uint64_t recorded = 0;
  std::vector<std::pair<std::string, uint64_t>> received;  // subscriber, received
};
std::vector<Delivery> CompareDelivery(const std::vector<ProcessLog>& logs, const std::map<std::string, int64_t>& recorded);
Section DeliverySection(const std::vector<ProcessLog>& logs, const std::map<std::string, int64_t>& recorded);
// One CSV row per process and channel it used: process, runs, reported_runs, channel, published,
// received, rejected, handler_errors, recorded (messages of the channel in the log).
std::string DeliveryCsv(const std::vector<ProcessLog>& logs, const std::map<std::string, int64_t>& recorded);

}  // namespace snapnav::report
