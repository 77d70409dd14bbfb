#pragma once
// 2D laser SLAM with an EKF on the robot pose (thesis 5.3.1).
//
// The state is the robot pose (x, y, theta) with its covariance. Odometry predicts it
// (PredictWithOdometry, motion noise growing with distance and rotation). Each scan's
// points are matched to their nearest map points within match_distance_m; a closed-form
// 2D alignment of the matches, iterated (ICP), gives a pose measurement whose covariance
// comes from the residuals and the match geometry; the EKF update fuses it with the
// prediction; scan points with no map point near them are added to the map at the
// updated pose. The map is a hash grid of cells of map_resolution_m holding one point
// each: nearest-neighbour queries and insertions cost O(1), and the map cannot grow
// faster than the area explored.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/map_matcher.hpp"
#include "snapnav/nav/point_grid_map.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// The EKF update with a direct pose measurement z (H = I): K = P (P + R)^-1. The angle
// innovation is wrapped. Returns the updated pose; `covariance` is updated in place.
Pose2 EkfPoseUpdate(const Pose2& pose, Eigen::Matrix3d* covariance, const Pose2& z, const Eigen::Matrix3d& r);

constexpr double kStaleMinMotionM = 0.05;  // LaserSlamOptions::stale_fraction applies above this motion per scan

// The filter's options; the matcher's (MatcherOptions) are its base.
struct LaserSlamOptions : MatcherOptions {
  // Odometry noise Q of the prediction. The heading noise per radian turned is 0.4, not dead
  // reckoning's 0.05: on a real robot turning fast, odometry and laser are out of step (CSAIL:
  // 10-25 deg between a scan and its odometry while turning at 60 deg/s), and the heading search
  // window follows this uncertainty.
  DeadReckoningOptions motion = [] {
    DeadReckoningOptions m;
    m.rotation_noise_rad_per_rad = 0.4;
    return m;
  }();
  double initial_sigma_xy_m = 0.01;         // initial covariance
  double initial_sigma_theta_rad = 0.5 * kRadPerDeg;
  double max_range_m = 0;                   // ignore points farther than this (0: no limit)
  // Heading search before ICP: headings within +-search_sigmas predicted standard deviations
  // (at most search_window_max_rad) in search_step_rad steps are scored against the map and ICP
  // starts from the best. Recovery: when fewer than recovery_fit of the points lie within
  // match_distance_m / 2 of the map after ICP, the whole window (and positions +-
  // match_distance_start_m / 2) is searched and ICP runs again; the better fit wins.
  double search_sigmas = 3.5;
  double search_window_max_rad = 30 * kRadPerDeg;  // 0: no search, no recovery
  double search_window_xy_m = 0.3;
  // Fast turns: odometry that lags the laser reports a turn a scan late (CSAIL: 21 deg, then 0.2
  // where the laser saw 15, then 20), so the prediction's heading also gets this std. dev. per
  // radian of the larger of odometry's turn since the last scan and its turn over the interval
  // before; the heading search window follows.
  double turn_noise_rad_per_rad = 1.0;
  // Stale odometry: an interval between two scans with no odometry motion at all is taken as
  // odometry that stopped reporting (CSAIL: the same odometry pose for up to 5 scans while the
  // robot turns, then a jump of 0.5 m and 85 deg). The prediction is then the last scan-to-scan
  // motion, and when odometry moves again, the motion the scans tracked meanwhile is taken out
  // of its increment. (A robot that really stopped: the last motion is small, the scan corrects it.)
  bool stale_odometry = true;
  // ... and so is an interval whose odometry translation is below this fraction of the last
  // scan-to-scan translation (when that was at least kStaleMinMotionM): a moving robot cannot
  // stop within one scan (CSAIL: 0.21 m per scan, then 0.004, 0, 0, then 0.83 m). 0: only
  // intervals with no motion at all.
  double stale_fraction = 0.25;
  // A scan is this much older than its utime (a laser on a slow serial line stamps it when it has
  // arrived: CSAIL's SICK, its odometry pose half a scan interval ahead of the scan). The scan is
  // matched at its utime minus this, odometry interpolated (LaserSlam's timed Predict / Update).
  // 0 (the default): stamped at acquisition, as laser-hokuyo and the simulator do; a latency set
  // for such a laser puts pose() that much odometry ahead of the truth.
  double scan_latency_s = 0;
  double recovery_fit = 0.6;
  // The update should sit where the scan fits: when the updated pose scores (against the map,
  // every point) more than this fraction below the ICP pose, the prediction was off by more than
  // its covariance allowed (odometry jitter along a corridor, where the measurement covariance
  // leaves the axis to the prediction; a late turn): its covariance is widened by the innovation
  // and the update redone. 0: off.
  double update_score_margin = 0.05;
  double map_resolution_m = 0.05;           // grid cell of the map (decimation)
  double add_distance_m = 0.08;             // a scan point is new if no map point is this close
  int scan_step = 1;                        // use every n-th point of a scan
  // Nearest map points through the map's lookup grid of cells of this size (PointGridMap): one
  // table lookup per query, the nearest of the points nearest to the cell's centre. 0: exact
  // search over buckets.
  double lookup_cell_m = 0.05;
  void Validate() const;                    // throws std::invalid_argument
};

struct LaserSlamUpdate {
  bool measured = false;       // the scan gave a pose measurement
  int points = 0, matches = 0, added = 0, iterations = 0;
  double fit = 0;              // fraction of the points within match_distance_m / 2 of the map after ICP
  int searches = 0;            // 1 if the heading was searched before ICP
  int starts = 0;              // ICP runs from the search's maxima (refine_starts; a recovery's included)
  int pruned = 0;              // ... of them ended early as clearly worse (refine_prune_iterations)
  int recoveries = 0;          // 1 if a poor fit started a wider search
  bool stale_odometry = false; // odometry had not moved since the last scan: predicted from the last motion
  bool widened = false;        // the update scored below the ICP pose: the prediction was widened
  Pose2 measurement;           // the ICP pose
  Eigen::Matrix3d measurement_covariance = Eigen::Matrix3d::Zero();
  Pose2 start;      // the pose ICP started from (the search's best; after a recovery, its)
  Pose2 predicted;  // the prediction the scan was matched from (after the odometry models)
  Eigen::Matrix3d predicted_covariance = Eigen::Matrix3d::Zero();  // its covariance (turn noise included)
};

class LaserSlam {
 public:
  explicit LaserSlam(const LaserSlamOptions& options, const Pose2& start = {});

  // EKF prediction from one odometry increment (robot frame).
  void Predict(const Pose2& odometry_delta);
  // EKF update from one scan (points in the robot frame). The first scan only builds the map.
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot);
  // The same with message times [us]: the increment ends at end_utime (it starts where the last
  // timed one ended), the scan has `utime`. With scan_latency_s > 0 the scan is matched (and
  // mapped) at utime - scan_latency_s: the increments after that time are taken out of the
  // prediction (the one that straddles it in proportion to its duration) and put back after the
  // update, so that pose() stays the pose at the latest odometry. Without times (the calls above)
  // the latency is not applied.
  void Predict(const Pose2& odometry_delta, int64_t end_utime);
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime);

  const Pose2& pose() const { return pose_; }
  // The pose of the last scan: where it was matched (its utime minus scan_latency_s), after its
  // update. pose() is that pose carried on by the odometry since.
  const Pose2& scan_pose() const { return scan_pose_; }
  const Eigen::Matrix3d& covariance() const { return covariance_; }
  const PointGridMap& map() const { return map_; }
  int64_t scans() const { return scans_; }

 private:
  MapMatcher matcher() const { return MapMatcher(map_, options_); }

  LaserSlamOptions options_;
  Pose2 pose_;
  Eigen::Matrix3d covariance_;
  PointGridMap map_;
  int64_t scans_ = 0;
  LaserSlamUpdate UpdateAtScan(const std::vector<Eigen::Vector2d>& points_robot);
  struct TimedIncrement {
    int64_t start_utime, end_utime;
    Pose2 delta;
  };
  std::deque<TimedIncrement> recent_odometry_;  // timed increments since the last scan's match time
  Pose2 scan_pose_;
  std::optional<int64_t> last_odometry_utime_;  // end of the last timed increment
  Pose2 tail_;                                  // odometry after the last scan's match time (re-applied after it)
  Pose2 odometry_since_scan_;         // odometry's motion since the last scan
  double previous_odometry_turn_rad_ = 0;  // odometry's heading change over the interval before
  std::optional<Pose2> last_scan_pose_;    // the pose after the last scan
  Pose2 last_motion_;                  // the estimate's motion between the last two scans
  std::optional<Pose2> stale_since_;   // the pose at the last scan before odometry went stale
  Pose2 odometry_since_stale_;         // odometry's motion since then

  // ---- For filters built on this one (nav::FusedSlam: a visual pose measurement in the same EKF).
 public:
  // EKF update with a direct pose measurement z of covariance r (EkfPoseUpdate).
  void UpdatePose(const Pose2& z, const Eigen::Matrix3d& r);
  // Replaces the pose and its covariance (relocalisation); the map stays as it is.
  void ResetPose(const Pose2& pose, const Eigen::Matrix3d& covariance);
  // Map protection: with add_points false no scan point joins the map; with min_fit > 0 a scan
  // whose ICP fit (LaserSlamUpdate::fit) is below min_fit adds none either (the first scan, which
  // builds the map, always does). Defaults: true, 0 (every scan maps, as before).
  void SetMapping(bool add_points, double min_fit = 0);
  bool adding_points() const { return add_points_; }

 private:
  bool MayAddPoints(const LaserSlamUpdate& u) const;
  bool add_points_ = true;
  double min_add_fit_ = 0;
};

}  // namespace snapnav::nav
