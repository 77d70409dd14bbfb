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
//   4. otherwise rejected. The rejected measurements of the last relocalize_window_s are kept,
//      carried forward by odometry like the filter. When a rejected measurement agrees with at
//      least relocalize_after - 1 of them (pairwise d2 <= agree_chi2) and their fused pose still
//      fails the gate against the filter, the filter relocalises: its pose becomes that fused
//      pose and its covariance theirs widened to at least relocalize_sigma_*; the map stays (it
//      is in the world frame). Outliers in between (aliasing, occlusion) do not break the
//      evidence, and they rarely agree with each other once carried by odometry. A kidnapped
//      robot (the laser pose consistently wrong) thus recovers after relocalize_after visual
//      measurements; so does a filter the laser led astray.
//      No relocalisation for a jump shorter than relocalize_min_distance_m (and a turn smaller
//      than relocalize_min_heading_rad): that is a map that drifted while it was built, and
//      jumping off it only corrupts it. No relocalisation either when the last scan fits the map
//      clearly worse at the new pose than at the filter's (relocalize_max_fit_loss): aliasing
//      that moves with the robot (the views a metre behind along a straight wall look alike)
//      agrees with itself too.
// Map protection: while the filter suspects it is lost (at least suspect_after consecutive
// rejected visual measurements) scans do not add points to the map, nor does a scan whose ICP
// fit is below map_min_fit.
//
// Map uncertainty (map_cell_m > 0): a scan matched to the map measures the pose relative to the
// map, and the map is only as certain as the poses it was built from. Every map_cell_m cell the
// scan points reach gets, when first mapped, the filter's covariance then plus the map's drift over
// the distance explored since the previous scan (map_drift_*); a later scan's
// measurement covariance R is ICP's plus the mean recorded covariance of the cells its points fall
// in (LaserSlam::SetMeasurementInflation), and the scan does not make the filter more certain than
// that (the variances after the update are at least the smaller of the prediction's and the
// map's). So while the robot explores (a corridor whose axis the laser cannot see, heading drift
// building up) the filter keeps the uncertainty it really has and the visual measurements weigh
// in; back in a part mapped with a certain pose, the laser dominates again. map_cell_m = 0: the
// laser measurement as LaserSlam makes it (the ICP covariance, far too certain for fusion).

#include <cstdint>
#include <deque>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/laser_slam.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct FusedSlamOptions {
  LaserSlamOptions laser;             // the laser EKF (prediction, ICP, map)
  double gate_chi2 = 11.34;           // Mahalanobis distance^2 gate of a visual measurement (3 dof; 99 %)
  double agree_chi2 = 11.34;          // rejected measurements agree with each other below this (3 dof)
  int relocalize_after = 5;           // relocalise after this many agreeing rejected measurements; 0: never
  double relocalize_sigma_xy_m = 0.2; // after relocalising the position std. dev. is at least this [m]
  double relocalize_sigma_theta_rad = 0.087;  // ... and the heading's [rad] (5 deg)
  double min_fix_sigma_xy_m = 0.05;   // floor of a visual measurement's position std. dev. [m]
  double min_fix_sigma_theta_rad = 0.03;  // floor of its heading std. dev. [rad]
  double max_fix_age_s = 2.0;         // older than this before the latest odometry: stale [s]
  double relocalize_window_s = 10.0;  // rejected measurements are evidence for this long [s]
  // Relocalise only for a jump of at least this distance or this heading change: smaller
  // disagreements come from a map that drifted while it was built (the pose stays on the map, the
  // fixes are refused) [m, rad]. 0, 0: any.
  double relocalize_min_distance_m = 1.0;
  double relocalize_min_heading_rad = 0.35;
  // No relocalisation when the last scan fits the map worse at the new pose than at the filter's
  // by more than this (fraction of the points within 2 laser.point_sigma_m of the map, among those
  // near mapped parts at both poses; not judged when either pose sees less than 30 % mapped
  // parts). 1: never refuse.
  double relocalize_max_fit_loss = 0.2;
  int suspect_after = 1;              // this many consecutive rejections: no points join the map; 0: never
  double map_cell_m = 1.0;            // map uncertainty cells [m]; 0: off (see above)
  // The map's drift while exploring: a cell mapped first gets the filter's covariance plus this
  // std. dev. per square root of the metres travelled since the previous scan (the variance grows
  // with the distance explored) [m, rad over 1 m].
  double map_drift_xy_m = 0.05;
  double map_drift_theta_rad = 0.0087;
  // Added to every scan measurement's covariance (the error of one scan against the map) [m, rad];
  // 0: ICP's own covariance. It also weakens the laser where the map is certain.
  double laser_sigma_xy_m = 0;
  double laser_sigma_theta_rad = 0;
  // A scan with an ICP fit below this adds no points [0-1]; 0: off. Off by default: where the
  // map has nothing yet (just relocalised into an unexplored part) every fit is poor, and the map
  // could never grow there.
  double map_min_fit = 0;
  void Validate() const;              // throws std::invalid_argument naming the option
};

enum class VisualOutcome {
  kAccepted,     // passed the gate: EKF update
  kRejected,     // beyond the gate (kept as evidence for a relocalisation)
  kRelocalized,  // rejected, and with it relocalize_after agree: the filter jumped to their fused pose
  kStale,        // older than max_fix_age_s
};
const char* VisualOutcomeName(VisualOutcome outcome);  // "accepted", "rejected", "relocalized", "stale"

struct VisualUpdate {
  VisualOutcome outcome = VisualOutcome::kStale;
  double mahalanobis2 = 0;       // d2 against the filter (0 when stale)
  int agreeing_rejections = 0;   // recent rejected measurements agreeing with this one, itself included
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
  int64_t refused_relocalizations() const { return refused_relocalizations_; }  // by the scan fit
  int64_t small_disagreements() const { return small_disagreements_; }  // agreeing rejections too close to relocalise
  int64_t stale() const { return stale_; }
  int consecutive_rejections() const { return consecutive_rejections_; }
  // Of the latest rejected measurement (0 once a measurement is accepted or after relocalising).
  int agreeing_rejections() const { return hypothesis_ ? hypothesis_count_ : 0; }
  bool suspect() const;             // the map is protected: consecutive rejections >= suspect_after
  int64_t unmapped_scans() const { return unmapped_scans_; }  // scans that added no points by protection
  // The fused pose (and covariance) of the latest rejected measurement and those agreeing with it;
  // none once a measurement is accepted or after relocalising.
  std::optional<std::pair<Pose2, Eigen::Matrix3d>> hypothesis() const;
  // The recorded covariance of the map cell holding p (map_cell_m > 0), if it was mapped.
  std::optional<Eigen::Matrix3d> MapCovarianceAt(const Eigen::Vector2d& p) const;

 private:
  struct Hypothesis {
    Pose2 pose;
    Eigen::Matrix3d covariance;
  };
  // z, r carried from utime to the latest odometry; false when older than the history.
  bool CarryForward(int64_t utime, Pose2* z, Eigen::Matrix3d* r) const;
  uint64_t CellKey(const Eigen::Vector2d& p) const;
  // Fraction of the last scan's sample within 2 point_sigma_m of the map at `pose`, among the points near mapped parts
  // (`judged`: their share of the sample).
  double ScanFit(const Pose2& pose, double* judged) const;
  // Mean recorded covariance over a sample of the points at `pose`; false when none is recorded.
  bool MapCovariance(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, Eigen::Matrix3d* out) const;
  // Cells the points reach at `pose` that have no record get `covariance`.
  void RecordMapCovariance(const Pose2& pose, const std::vector<Eigen::Vector2d>& points,
                           const Eigen::Matrix3d& covariance);

  FusedSlamOptions options_;
  LaserSlam laser_;
  std::deque<std::pair<int64_t, Pose2>> history_;  // odometry increments (end utime, delta), oldest first
  int64_t utime_ = 0;
  bool have_time_ = false;
  std::unordered_map<uint64_t, Eigen::Matrix3d> map_covariance_;  // map cell -> covariance when first mapped
  struct Rejected {
    int64_t utime;
    Pose2 pose;
    Eigen::Matrix3d covariance;
  };
  std::deque<Rejected> rejected_window_;  // recent rejected measurements, carried forward by odometry
  std::optional<Hypothesis> hypothesis_;
  int hypothesis_count_ = 0;
  int consecutive_rejections_ = 0;
  int64_t accepted_ = 0, rejected_ = 0, relocalizations_ = 0, stale_ = 0, unmapped_scans_ = 0;
  int64_t refused_relocalizations_ = 0, small_disagreements_ = 0;
  double travelled_since_scan_m_ = 0;  // odometry distance since the last scan [m]
  std::vector<Eigen::Vector2d> last_points_;  // a sample of the last scan (robot frame)
};

}  // namespace snapnav::nav
