#pragma once
// Fused visual + laser SLAM (thesis 1.2, 5, 6.3.3): the laser SLAM's EKF on the robot pose
// (nav::LaserSlam: odometry prediction, ICP scan updates, the point map) with a second
// measurement, the pose and covariance of place-cell localization (nav::PlaceCellMemory::
// Localize), fused in the same filter. Visual recognition corrects the drift the laser cannot
// see (a corridor's axis) and recovers from a kidnapping where the laser alone is ambiguous
// (the two symmetric halves of a corridor).
//
// Frame: the filter's frame is the place memory's (the world, or scene, frame): a visual
// measurement is a pose in that frame, and the map is built in it. The filter starts at a pose
// given in that frame; in the simulator the odometry's cumulative pose starts at the true start
// pose, so the first odometry message's pose is such a start (see processes/fused_slam).
//
// Visual measurements, in order:
//   1. stale: older than max_fix_age_s before the latest odometry -> dropped (counted);
//   2. late: carried forward to the latest odometry by the odometry increments since its
//      utime (with their motion noise added to its covariance), as nav::PoseTracker does;
//   3. gate: innovation y = z - x (angle wrapped), S = P + R, d2 = y^T S^-1 y; d2 <= gate_chi2
//      (chi-square, 3 degrees of freedom; 11.34 is the 99 % point) -> EKF update (accepted);
//   4. otherwise rejected. Rejected measurements build a second hypothesis: the first starts
//      it (its pose and covariance); each later rejected one is carried there by odometry like
//      the filter, and if it agrees with the hypothesis (d2 <= agree_chi2) it is fused into it
//      and the count of agreeing rejections grows, else it starts a new hypothesis (count 1).
//      An accepted measurement clears the hypothesis. After relocalize_after agreeing rejected
//      measurements the filter relocalises: its pose becomes the hypothesis' and its covariance
//      the hypothesis' widened to at least relocalize_sigma_*; the map stays (it is in the
//      world frame). A kidnapped robot (the laser pose consistently wrong) thus recovers after
//      relocalize_after visual measurements.
// Map protection: while the filter suspects it is lost (at least suspect_after consecutive
// rejected visual measurements) scans do not add points to the map, nor does a scan whose ICP
// fit is below map_min_fit.

#include <cstdint>
#include <deque>
#include <optional>
#include <utility>

#include <Eigen/Core>

#include "snapnav/nav/laser_slam.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct FusedSlamOptions {
  LaserSlamOptions laser;             // the laser EKF (prediction, ICP, map)
  double gate_chi2 = 11.34;           // Mahalanobis distance^2 gate of a visual measurement (3 dof; 99 %)
  double agree_chi2 = 11.34;          // rejected measurements agree with each other below this (3 dof)
  int relocalize_after = 5;           // relocalise after this many agreeing rejected measurements; 0: never
  double relocalize_sigma_xy_m = 0.3; // after relocalising the position std. dev. is at least this [m]
  double relocalize_sigma_theta_rad = 0.15;  // ... and the heading's [rad]
  double min_fix_sigma_xy_m = 0.05;   // floor of a visual measurement's position std. dev. [m]
  double min_fix_sigma_theta_rad = 0.03;  // floor of its heading std. dev. [rad]
  double max_fix_age_s = 2.0;         // older than this before the latest odometry: stale [s]
  int suspect_after = 1;              // this many consecutive rejections: no points join the map; 0: never
  // A scan with an ICP fit below this adds no points [0-1]; 0: off. Off by default: where the
  // map has nothing yet (just relocalised into an unexplored part) every fit is poor, and the map
  // could never grow there.
  double map_min_fit = 0;
  void Validate() const;              // throws std::invalid_argument naming the option
};

enum class VisualOutcome {
  kAccepted,     // passed the gate: EKF update
  kRejected,     // beyond the gate (kept as evidence for a relocalisation)
  kRelocalized,  // the relocalize_after-th agreeing rejection: the filter jumped to the hypothesis
  kStale,        // older than max_fix_age_s
};
const char* VisualOutcomeName(VisualOutcome outcome);  // "accepted", "rejected", "relocalized", "stale"

struct VisualUpdate {
  VisualOutcome outcome = VisualOutcome::kStale;
  double mahalanobis2 = 0;       // d2 against the filter (0 when stale)
  int agreeing_rejections = 0;   // of the hypothesis after this measurement (0 after accepting)
  Pose2 measurement;             // carried forward to the latest odometry
  Eigen::Matrix3d measurement_covariance = Eigen::Matrix3d::Zero();
};

class FusedSlam {
 public:
  // Starts at `start` (place-memory frame) with the laser options' initial covariance.
  explicit FusedSlam(const FusedSlamOptions& options, const Pose2& start = {});
  // ... or with a given covariance (e.g. a visual fix's, widened). Throws std::invalid_argument on
  // invalid options or a non-finite start.
  FusedSlam(const FusedSlamOptions& options, const Pose2& start, const Eigen::Matrix3d& covariance);

  // EKF prediction from one odometry increment (robot frame of the previous reading) ending at
  // utime; kept max_fix_age_s for late visual measurements. Throws std::invalid_argument on a
  // non-finite increment.
  void Predict(int64_t utime, const Pose2& odometry_delta);
  // EKF update from one scan (points in the robot frame); the map grows unless protected.
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot);
  // A visual pose measurement taken at utime (place-memory frame) with its covariance. Throws
  // std::invalid_argument on a non-finite pose or covariance or a negative variance.
  VisualUpdate AddVisual(int64_t utime, const Pose2& z, const Eigen::Matrix3d& covariance);

  const Pose2& pose() const { return laser_.pose(); }
  const Eigen::Matrix3d& covariance() const { return laser_.covariance(); }
  // The filter's pose at an earlier time: the current pose moved back by the odometry since then
  // (nullopt when utime is older than the odometry kept).
  std::optional<Pose2> PoseAt(int64_t utime) const;
  const PointGridMap& map() const { return laser_.map(); }
  const LaserSlam& laser() const { return laser_; }
  const FusedSlamOptions& options() const { return options_; }
  int64_t utime() const { return utime_; }  // of the latest odometry

  int64_t accepted() const { return accepted_; }
  int64_t rejected() const { return rejected_; }          // relocalising ones included
  int64_t relocalizations() const { return relocalizations_; }
  int64_t stale() const { return stale_; }
  int consecutive_rejections() const { return consecutive_rejections_; }
  int agreeing_rejections() const { return hypothesis_ ? hypothesis_count_ : 0; }
  bool suspect() const;             // the map is protected: consecutive rejections >= suspect_after
  int64_t unmapped_scans() const { return unmapped_scans_; }  // scans that added no points by protection
  // The relocalisation hypothesis (pose, covariance), if rejected measurements started one.
  std::optional<std::pair<Pose2, Eigen::Matrix3d>> hypothesis() const;

 private:
  struct Hypothesis {
    Pose2 pose;
    Eigen::Matrix3d covariance;
  };
  // z, r carried from utime to the latest odometry; false when older than the history.
  bool CarryForward(int64_t utime, Pose2* z, Eigen::Matrix3d* r) const;

  FusedSlamOptions options_;
  LaserSlam laser_;
  std::deque<std::pair<int64_t, Pose2>> history_;  // odometry increments (end utime, delta), oldest first
  int64_t utime_ = 0;
  bool have_time_ = false;
  std::optional<Hypothesis> hypothesis_;
  int hypothesis_count_ = 0;
  int consecutive_rejections_ = 0;
  int64_t accepted_ = 0, rejected_ = 0, relocalizations_ = 0, stale_ = 0, unmapped_scans_ = 0;
};

}  // namespace snapnav::nav
