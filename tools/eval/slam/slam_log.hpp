#pragma once
// Laser SLAM evaluation inputs: an LCM log of LASER_SCAN and ODOMETRY read into memory (so
// runs and benchmarks replay it without decoding again), a reference trajectory (a CSV of
// utime,x,y,theta or a CARMEN log of corrected poses whose scans pair with the log's by
// identical ranges, or by their near readings: AlignReference), and a run of dead reckoning and laser SLAM in lockstep over the log.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/trajectory.hpp"

namespace snapnav::eval {

// One step of a SLAM log, in log order: an odometry increment or a scan.
struct SlamStep {
  bool is_scan = false;
  int64_t utime = 0;
  nav::Pose2 odometry_delta;                 // !is_scan: increment in the robot frame
  std::vector<Eigen::Vector2d> points;       // is_scan: valid points in the robot frame
  std::string ranges_key;                    // is_scan: the raw ranges, for pairing with a reference
  float range_max_m = 0;                     // is_scan: the scan's maximum range (readings at it: no return)
};

struct SlamLog {
  std::string path;
  std::vector<SlamStep> steps;
  int64_t scans = 0, odometry = 0, rejected = 0, events = 0;
  int beams = 0;                             // beams of the first scan
  // Damage of the log file (glue::LogReader): places, bytes skipped, one description each
  // ("PATH: byte N: ...").
  int damaged_places = 0;
  uint64_t damaged_bytes = 0;
  std::vector<std::string> damage;
};

// A decoded LASER_SCAN the SLAM log keeps (the checks of the laser-slam process); the others are
// counted as rejected.
bool UsableScan(const laser_scan_t& scan);

// Reads a log made by log-import (or recorded on the bus). Undecodable or invalid messages are
// counted in `rejected`; a damaged file (truncated, corrupt) is read up to and after the damage,
// which is described in `damage` and printed as warnings. Throws std::runtime_error naming the
// file if it cannot be opened or holds no scans. Progress goes to stderr when `progress`.
SlamLog LoadSlamLog(const std::string& path, bool progress = true);

// Reference poses keyed by scan ranges (CARMEN) or by time (CSV `utime,x,y,theta`; MRPT's
// ground truth `*.txt`: `timestamp x y phi`, Unix seconds).
struct Reference {
  std::string path;
  std::map<std::string, nav::Pose2> by_ranges;
  std::vector<nav::StampedPose> by_time;
  // A CARMEN reference's scans in file order (for pairing a log whose ranges were processed
  // otherwise: AlignReference).
  struct Scan {
    std::vector<float> ranges_m;
    float range_max_m = 0;
    nav::Pose2 pose;
  };
  std::vector<Scan> scans;
  int paired_exactly = 0, paired_by_overlap = 0;  // the log's scans paired (with a log: LoadReference)
  // The reference pose of a scan: by identical ranges, else nearest in time within max_dt_us.
  std::optional<nav::Pose2> Find(const std::string& ranges_key, int64_t utime, int64_t max_dt_us = 50000) const;
};
// Throws std::runtime_error naming the file and line on malformed input. With `log`, a CARMEN
// reference is paired with the log's scans (AlignReference) and the pairing printed, with a warning
// when fewer than half of the reference's scans pair.
Reference LoadReference(const std::string& path, const SlamLog* log = nullptr);

// Pairs the log's scans with a CARMEN reference's scans. By identical ranges first; where that
// leaves reference scans unpaired (the log's ranges were processed otherwise: a laser of shorter
// range, or an importer's lower maximum range, turns far readings into no-returns), by their
// overlap: the two sequences are walked in order and a reference scan pairs with the next log scan
// of the same beam count whose readings agree (within 1 mm) wherever both are below the lower of
// the two maximum ranges, and are both at or beyond it elsewhere, on at least a tenth of the beams.
// The pairs are added to by_ranges under the log's ranges, so Find serves them.
void AlignReference(const SlamLog& log, Reference* reference);

// The pose of every scan of a run.
struct SlamRun {
  std::vector<int64_t> utime;
  std::vector<std::string> ranges_key;
  std::vector<nav::Pose2> slam, dead_reckoning;  // slam: LaserSlam::scan_pose() after each scan's update
  std::vector<nav::LaserSlamUpdate> updates;     // what LaserSlam::Update reported for each scan
  double update_seconds = 0;                  // time spent in LaserSlam::Update
  std::vector<Eigen::Vector2d> map;           // the final point map
  double ms_per_scan() const { return slam.empty() ? 0 : 1000 * update_seconds / static_cast<double>(slam.size()); }
};
// Runs dead reckoning and laser SLAM in lockstep over the log.
SlamRun RunSlam(const SlamLog& log, const nav::LaserSlamOptions& options);

// Odometry's systematic errors (nav::OdometryCalibration): as the run's laser SLAM estimated them
// from its matches (its last update), and as the reference implies them (the same estimator fed
// odometry against the reference's motion, over stretches between scans the reference has).
struct OdometryFigure {
  bool measured = false;  // at least one stretch
  double drift_deg_per_m = 0, turn_scale = 0, distance_scale = 0;
  int stretches = 0;
};
OdometryFigure SlamOdometryCalibration(const SlamRun& run);
// `options`: the laser SLAM's (its odometry_calibration and motion noise: the same estimator).
OdometryFigure ReferenceOdometryCalibration(const SlamRun& run, const Reference& reference,
                                            const nav::LaserSlamOptions& options);
// "heading drift 1.45 deg/m, turns +2.0 %, distance +3.1 % (312 stretches)" or "no stretch".
std::string DescribeOdometry(const OdometryFigure& f);

// (estimate, reference) pairs of the scans that have a reference pose.
std::vector<std::pair<nav::Pose2, nav::Pose2>> PairWithReference(const std::vector<nav::Pose2>& estimate,
                                                                 const SlamRun& run, const Reference& reference);

// Map consistency of a trajectory without a reference: the scans are placed at the trajectory's
// poses and each scan point is paired with the nearest point (within max_distance_m) of the
// scans at least min_separation_scans away in the log (the places seen again on a revisit, not
// the scan's neighbours, which the matcher aligned it with anyway; of a 5 cm grid's cell, the
// point of the earliest and of the latest scan that hit it; 90 points per scan). A scan with at least
// min_pairs such pairs gets the median pair distance; the trajectory's figure is the median of
// those over the scans. A consistent map (the same walls seen again in the same place) gives
// small distances; a trajectory that puts a revisit off gives doubled walls, and larger ones.
struct MapConsistency {
  std::vector<double> per_scan_m;  // per scan (in log order): median distance, NaN without enough pairs
  int scans = 0;                   // scans with a figure
  double median_m = 0;             // median over those scans
  double mean_m = 0;
};
// `poses[i]` is the pose of the i-th scan of `log`, or nullopt (the scan is left out).
MapConsistency ComputeMapConsistency(const SlamLog& log, const std::vector<std::optional<nav::Pose2>>& poses,
                                     int min_separation_scans = 30, double max_distance_m = 0.5, int min_pairs = 30);

// The reference's own consistency: a corrected log is another SLAM's output and can hold poses
// its scan contradicts (CSAIL's corrected log: three poses 11-20 deg off what their scans show).
// Each scan with a reference pose, placed there, is compared with the `window` scans with a
// reference pose before it, placed at theirs: the share of its points within `near_m` of theirs
// at the reference pose, and the best share over headings within +-max_turn_deg of it (1 deg
// steps). A pose whose scan fits at least `min_gain` better turned is suspect. Odometry made from
// such a reference (carmen_raw_like.py) carries the jump.
struct ReferenceCheckOptions {
  int window = 4;               // scans before each one [count, >= 1]
  double near_m = 0.1;          // a point fits within this of the others' [m]
  double max_turn_deg = 20;     // headings searched on either side [deg]
  double min_gain = 0.15;       // suspect when turned fits this much better [share of the points]
};
struct ReferenceSuspect {
  int scan = 0;                 // the scan's index in the log (0-based, scans only)
  double fit = 0;               // share of the scan's points near the previous scans' at the reference pose
  double turned_fit = 0;        // ... at the best heading
  double turn_deg = 0;          // that heading less the reference's (the middle of equally good ones)
};
struct ReferenceCheck {
  int checked = 0;              // scans compared with their predecessors
  std::vector<ReferenceSuspect> suspects;
};
// Throws std::invalid_argument on options out of range.
ReferenceCheck CheckReference(const SlamLog& log, const Reference& reference, const ReferenceCheckOptions& options = {});
// "0 of 405 reference poses disagree with their scans" or "3 of 402 ...: scan 42 (fit 0.44 at
// the reference, 0.78 turned +11 deg), ...", and reference_suspects.csv (scan,fit,turned_fit,turn_deg).
std::string DescribeReferenceCheck(const ReferenceCheck& check);
void WriteReferenceCheckCsv(const std::string& path, const ReferenceCheck& check);

}  // namespace snapnav::eval
