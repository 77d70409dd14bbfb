#pragma once
// Fused visual + laser SLAM (thesis 1.2, 5, 6.3.3): the laser SLAM's EKF on the robot pose
// (nav::LaserSlam: odometry prediction, ICP scan updates, the point map) with a second
// measurement, the pose and covariance of place-cell localization (nav::PlaceCellMemory::
// Localize), fused in the same filter. Visual recognition corrects the drift the laser cannot
// see (a corridor's axis) and recovers from a kidnapping where the laser alone is ambiguous
// (the two symmetric halves of a corridor).
//
// Frames. The laser part is nav::LaserSlam, run exactly as laser-only SLAM in its own map frame
// (the start pose is its origin): its pose m follows ICP against its own map with the laser's
// local precision, and nothing the camera says moves it (but for a relocalisation). The world
// (place-memory) frame is the start pose composed with the map frame, minus the map's offset:
// the map is built from the laser's own estimates, so it is off the world by an error that grows
// while it is explored (a corridor bends with the heading drift) and that is the same on every
// later visit. That error is not white noise per scan (the old scheme inflated each scan's R by
// it, so the laser lost its local precision, and its covariance stopped growing while exploring):
// it is estimated, per map cell, from the visual measurements.
//
// Map offset (map_cell_m cells of the map frame). Every cell holds an offset o = (t, phi): the
// map there is shifted by t and turned by phi about the cell's centre c with respect to the
// world, with a covariance O. A cell gets its offset when a scan point first falls in it: the
// robot's offset then, carried rigidly from the robot to c (a heading offset moves far cells
// more), its covariance plus the map's drift over the distance travelled since the previous
// scan (map_drift_*): cells mapped from a pose matched to a part mapped just before inherit its
// uncertainty plus the drift of one more scan, so the uncertainty grows along an exploration and
// stays where the laser matches parts mapped long ago. The robot's offset u (at its position p)
// is, after every scan, the mean of the offsets of the cells the scan's points fall in, each
// carried to p (u = mean A_c(p) o_c, A_c(p) = [I, J (p - c); 0, 1]); between scans it is carried
// with the robot. The world pose is start (+) (m - u), its covariance P_m + U (the laser's, relative
// to the map, and the offset's), turned into the world frame.
//
// Visual measurements, in order:
//   1. stale: older than max_fix_age_s before the latest odometry -> dropped (counted);
//   2. late: carried forward to the latest odometry by the odometry increments since its
//      utime (with their motion noise added to its covariance), as nav::PoseTracker does;
//   3. gate: in the map frame a fix z measures the offset, m - z, with covariance R + P_m;
//      y = (m - z) - u (angle wrapped), S = U + R + P_m, d2 = y^T S^-1 y (the same as the
//      innovation of the world pose); d2 <= gate_chi2 (chi-square, 3 degrees of freedom; 11.34 is
//      the 99 % point) -> accepted: every cell the last scan saw measures the offset at the robot
//      too and gets its own Kalman update (innovation y_c = (m - z) - A_c o_c, S_c = A_c O_c A_c^T
//      + R + P_m, K_c = O_c A_c^T S_c^-1), and u is their mean again (no cell under the robot,
//      just relocalised: u alone, K = U S^-1); the laser's pose and map stay as they are;
//   4. otherwise rejected. The rejected measurements of the last relocalize_window_s are kept,
//      carried forward by odometry like the filter. When a rejected measurement agrees with at
//      least relocalize_after - 1 of them (pairwise d2 <= agree_chi2) and their fused pose still
//      fails the gate against the filter, the filter relocalises: the laser's pose jumps so that
//      the world pose is that fused pose (the offset of the cells there kept); their covariance,
//      widened to at least relocalize_sigma_*, becomes the laser's where the map has cells there
//      (ICP searches it; the robot's offset is theirs), else the robot's offset's (the laser
//      starts a new part of its map with its initial covariance, and that part is off the world
//      by the relocalised pose's error); the map stays (it is still right where it was built). Outliers in
//      between (aliasing, occlusion) do not break the evidence, and they rarely agree with each
//      other once carried by odometry. A kidnapped robot (the laser pose consistently wrong) thus
//      recovers after relocalize_after visual measurements; so does a filter the laser led astray.
//      No relocalisation for a jump shorter than relocalize_min_distance_m (and a turn smaller
//      than relocalize_min_heading_rad): that is a map that drifted while it was built, and
//      jumping off it only corrupts it. No relocalisation either when the last scan fits the map
//      clearly worse at the new pose than at the filter's (relocalize_max_fit_loss): aliasing
//      that moves with the robot (the views a metre behind along a straight wall look alike)
//      agrees with itself too. With relocalize_net_of_accepted, the measurements accepted since
//      the oldest of the agreeing rejected ones count against them: a kidnapped filter rejects
//      every measurement after the kidnapping, while aliasing interleaves its wrong measurements
//      with right ones that the filter accepts (people11: four wrong fixes 1 m ahead among three
//      accepted ones moved a filter that was right).
// Dynamic obstacles: before the laser's update, every scan point is tested at the predicted pose
// against the map points at least dynamic_map_age_s old. One the map does not explain (none within
// dynamic_explain_m) but that stands in front of a mapped surface (a map point within
// dynamic_explain_m of its beam, up to dynamic_max_behind_m beyond it) is something that was not
// there when that part of the map was built: a person. Those points are left out of the laser's
// update and its map (laser-only SLAM matches them and maps their trails: among walking people its
// pose jumps by 1-3 cm). A new wall has nothing mapped behind it and is kept; so is everything when
// more than dynamic_max_fraction of the scan is dynamic (the prediction is off: a kidnapping, a
// relocalisation's wide covariance), and no point is tested while the prediction's position std.
// dev. exceeds dynamic_explain_m. Their share of the scan is the view's occluded fraction;
// occlusion_fix_inflation widens the visual measurements by it.
// Map protection: while the filter suspects it is lost (at least suspect_after consecutive
// rejected visual measurements) scans do not add points to the map, nor does a scan whose ICP
// fit is below map_min_fit.
//
// Consistency (the covariance against the errors; all off by default, on in config/fused_slam.ini).
// Three things made the covariance claim far less than the errors (corridor NEES 48):
//   - the map's drift was added per scan, to the cells that scan reached first: most scans reach
//     none, and their drift was lost (map_drift_accumulates: since the last scan that did);
//   - along a corridor's axis the laser's covariance claims millimetres from the walls' noisy
//     normals while its pose slides with the odometry (laser_min_constraint: fused SLAM's own
//     covariance of the laser without those directions, P_l, and the laser's drift d from its map
//     as a state the fixes estimate; map_inherits_laser_drift: new cells are built at m and inherit
//     d and P_l);
//   - the fixes' errors are correlated along the path (neighbouring views are alike), so a run of
//     them is worth fewer independent ones (fix_correlation_m).
//
// Where the laser sees its map well and the map was built from a certain pose (a room seen from
// the start), the offsets stay as certain as the start (start_sigma_*) and the fixes, centimetres
// off, move the world pose by micrometres: fused SLAM is then the laser SLAM. Where the map drifts
// (a corridor), the offsets' uncertainty grows with it and the fixes hold the world pose.

#include <cstdint>
#include <deque>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/slam/laser_slam.hpp"
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
  // The measurements accepted since the oldest agreeing rejected one count against the
  // relocalisation: relocalise when the agreeing rejected ones outnumber them by relocalize_after.
  bool relocalize_net_of_accepted = true;
  int suspect_after = 0;              // this many consecutive rejections: no points join the map; 0: never
  // The start pose's uncertainty in the world frame: the offset of the map first seen from it
  // [m, rad] (FusedSlam(options, start, covariance) takes a covariance instead).
  double start_sigma_xy_m = 0.001;
  double start_sigma_theta_rad = 0.000175;
  double map_cell_m = 2.0;            // map offset cells [m] (see above)
  // The map's drift while exploring: a cell mapped first gets the offset covariance of the robot
  // plus this std. dev. per square root of the metres travelled since the previous scan [m, rad
  // over 1 m].
  double map_drift_xy_m = 0.05;
  double map_drift_theta_rad = 0.0087;
  // ... the metres travelled since the last scan that reached new cells, not since the previous scan
  // (false): the map drifts while the robot travels, and a scan that maps no new cell does not
  // undo the drift it travelled (with false it is lost, and a corridor mapped a cell every 2 m gets
  // the drift of 3 cm each time) [true | false].
  bool map_drift_accumulates = false;
  // A scan with an ICP fit below this adds no points [0-1]; 0: off. Off by default: where the
  // map has nothing yet (just relocalised into an unexplored part) every fit is poor, and the map
  // could never grow there.
  double map_min_fit = 0;
  // Dynamic obstacles (people) in the scan. A scan point farther than dynamic_explain_m from the
  // map at the predicted pose, with a map point within dynamic_explain_m of its beam's line up to
  // dynamic_max_behind_m beyond it, stands in front of a part of the map the laser has seen: an
  // obstacle that was not there when that part was mapped. Only map points at least
  // dynamic_map_age_s old count, for both (a walking person's points of the scans just before
  // would explain it; a person who stands still that long becomes part of the map). Not tested
  // when the laser's predicted position std. dev. exceeds dynamic_explain_m (just relocalised). Such points are left out of the
  // laser's update and map (nav::LaserSlam gets the rest); their share of the scan is the
  // view's occluded fraction. More than dynamic_max_fraction of the scan so: the prediction is
  // off (a kidnapping, a slip), not people, and no point is left out. dynamic_explain_m 0: off.
  double dynamic_explain_m = 0.1;
  double dynamic_max_behind_m = 4.0;
  double dynamic_map_age_s = 1.0;
  double dynamic_max_fraction = 1.0;
  // A visual measurement's covariance is multiplied by (1 + occlusion_fix_inflation f)^2, f the
  // last scan's occluded fraction: people in the view move the place cells' match (the memory was
  // recorded without them) [1, 0: off].
  double occlusion_fix_inflation = 0;
  // Degeneracy of the laser (a corridor's axis). LaserSlam's ICP measurement covariance comes from
  // the matched points' surface normals; along a corridor's axis their information is the noise of
  // the normals, yet, scan after scan, it makes the laser's covariance claim millimetres there while
  // its pose slides with the odometry. With laser_min_constraint > 0 fused SLAM keeps its own
  // covariance of the laser's pose relative to its map (P_l, map frame): the laser's motion model
  // predicts it, and each scan's ICP information I (LaserSlamUpdate::measurement_covariance^-1)
  // updates it in information form, P_l = (P_l^-1 + I')^-1, where I' is I without the weak
  // position directions: an eigenvector v of I's position block whose information per matched point,
  // lambda point_sigma_m^2 / matches, is below laser_min_constraint (the share of the points whose
  // normals would face v; a wall facing v: ~1) constrains nothing. P_l is never below the laser's
  // own covariance. Along the weak directions the laser's drift from its map, d (mean zero after a
  // scan that constrains it), becomes a state the visual fixes estimate: the world pose is
  // start (+) (m - u - d), its covariance P_l + U. 0: off (the laser's covariance, no d).
  double laser_min_constraint = 0;
  // Cells a scan reaches first inherit the laser's drift d and P_l too (the map there is built at the
  // drifted pose) [true | false; without laser_min_constraint nothing changes].
  bool map_inherits_laser_drift = false;
  // Visual fixes whose errors are correlated: the place cells' error at neighbouring poses is alike
  // (their views are), so a run of fixes along a few decimetres does not average it out. An accepted
  // fix updates with its covariance multiplied by (1 + rho) / (1 - rho), rho = exp(-s /
  // fix_correlation_m), s the distance travelled since the previous accepted fix: the variance of the
  // mean of an AR(1) error (the gate tests the fix with its own covariance). [m, 0: off, independent]
  double fix_correlation_m = 0;
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

// A map cell's offset from the world (see the header comment), in the map frame.
struct MapOffset {
  Eigen::Vector2d center;                      // the cell's centre [m]
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // t [m], phi [rad] about the centre
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

class FusedSlam {
 public:
  // Starts at `start` (place-memory frame), its uncertainty start_sigma_*.
  explicit FusedSlam(const FusedSlamOptions& options, const Pose2& start = {});
  // ... or with a given uncertainty of the start (e.g. a visual fix's, widened). Throws
  // std::invalid_argument on invalid options or a non-finite start.
  FusedSlam(const FusedSlamOptions& options, const Pose2& start, const Eigen::Matrix3d& covariance);

  // Odometry increment (robot frame of the previous reading) ending at utime: the laser's EKF
  // prediction; kept max_fix_age_s for late visual measurements. Throws std::invalid_argument on
  // a non-finite increment.
  void Predict(int64_t utime, const Pose2& odometry_delta);
  // One scan (points in the robot frame): the laser's EKF update; the map grows unless protected,
  // new map cells get their offsets, and the robot's offset is the seen cells'.
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot);
  // A visual pose measurement taken at utime (place-memory frame) with its covariance. Throws
  // std::invalid_argument on a non-finite pose or covariance or a negative variance.
  VisualUpdate AddVisual(int64_t utime, const Pose2& z, const Eigen::Matrix3d& covariance);

  // The fused pose and its covariance in the place-memory (world) frame.
  const Pose2& pose() const { return pose_; }
  const Eigen::Matrix3d& covariance() const { return covariance_; }
  // The filter's pose at an earlier time: the current pose moved back by the odometry since then
  // (nullopt when utime is older than the odometry kept).
  std::optional<Pose2> PoseAt(int64_t utime) const;
  // The laser's map, in its own frame (the laser's frame: start pose at the origin).
  const PointGridMap& map() const { return laser_.map(); }
  // The map's points in the world frame: each moved by its cell's offset (unmapped cells: none).
  std::vector<Eigen::Vector2d> WorldMapPoints() const;
  // The laser SLAM inside, in its own frame.
  const LaserSlam& laser() const { return laser_; }
  const Pose2& map_frame() const { return start_; }  // world pose of the laser's origin
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
  // Dynamic points (see dynamic_explain_m): the last scan's share, the points left out so far, and
  // the scans where too many were dynamic to leave any out.
  double occluded_fraction() const { return occluded_fraction_; }
  int64_t dynamic_points() const { return dynamic_points_; }
  int64_t dynamic_overflow_scans() const { return dynamic_overflow_scans_; }
  // The fused pose (and covariance) of the latest rejected measurement and those agreeing with it;
  // none once a measurement is accepted or after relocalising.
  std::optional<std::pair<Pose2, Eigen::Matrix3d>> hypothesis() const;
  // The robot's map offset (map frame, at the robot) and its covariance.
  const Eigen::Vector3d& robot_offset() const { return u_; }
  const Eigen::Matrix3d& robot_offset_covariance() const { return u_cov_; }
  // The laser pose's covariance relative to its map as fused SLAM takes it (laser_min_constraint:
  // its own, P_l; else the laser's), and the laser's estimated drift d from its map (zero when off).
  const Eigen::Matrix3d& laser_covariance() const {
    return options_.laser_min_constraint > 0 ? laser_cov_ : laser_.covariance();
  }
  const Eigen::Vector3d& laser_drift() const { return drift_; }
  // Of the last scan with an ICP measurement: the information per matched point along the weakest
  // position direction (see laser_min_constraint; 0 before one), and whether it was left out.
  double weakest_constraint() const { return weakest_constraint_; }
  bool degenerate() const { return degenerate_; }
  int64_t degenerate_scans() const { return degenerate_scans_; }
  // The offset of the map cell holding the world point p, if a scan has reached it.
  std::optional<MapOffset> MapOffsetAt(const Eigen::Vector2d& p) const;
  size_t map_offset_cells() const { return cells_.size(); }

 private:
  struct Hypothesis {
    Pose2 pose;
    Eigen::Matrix3d covariance;
  };
  // z, r carried from utime to the latest odometry; false when older than the history.
  bool CarryForward(int64_t utime, Pose2* z, Eigen::Matrix3d* r) const;
  uint64_t CellKey(const Eigen::Vector2d& p) const;
  Eigen::Vector2d CellCenter(const Eigen::Vector2d& p) const;
  // Fraction of the last scan's sample within 2 point_sigma_m of the map at the map-frame pose
  // `m`, among the points near mapped parts (`judged`: their share of the sample).
  double ScanFit(const Pose2& m, double* judged) const;
  // The mean offset, carried to m's position, of the cells the last scan's sample falls in at
  // the map-frame pose m; false when none has an offset. `cells` (optional) gets them with their
  // share of the sample.
  bool SeenOffset(const Pose2& m, Eigen::Vector3d* u, Eigen::Matrix3d* cov,
                  std::vector<std::pair<uint64_t, double>>* cells) const;
  // World pose and covariance from the laser's and the robot's offset.
  void Refresh();

  FusedSlamOptions options_;
  Pose2 start_;                 // world pose of the laser's (map frame's) origin
  Eigen::Matrix2d start_rotation_;
  LaserSlam laser_;
  Pose2 pose_;                  // world
  Eigen::Matrix3d covariance_;  // world
  // The robot's offset (map frame) at u_at_ (the robot's map-frame position when it was set).
  Eigen::Vector3d u_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d u_cov_ = Eigen::Matrix3d::Zero();
  Eigen::Vector2d u_at_ = Eigen::Vector2d::Zero();
  std::unordered_map<uint64_t, MapOffset> cells_;     // map cell -> its offset
  std::vector<std::pair<uint64_t, double>> seen_;     // cells the last scan saw, with their share
  std::deque<std::pair<int64_t, Pose2>> history_;  // odometry increments (end utime, delta), oldest first
  int64_t utime_ = 0;
  bool have_time_ = false;
  struct Rejected {
    int64_t utime;
    Pose2 pose;
    Eigen::Matrix3d covariance;
  };
  std::deque<Rejected> rejected_window_;  // recent rejected measurements, carried forward by odometry
  std::deque<int64_t> accepted_window_;   // the times of the measurements accepted in the same window
  size_t EvidenceCap() const;             // rejected measurements kept as evidence (at least 8)
  std::optional<Hypothesis> hypothesis_;
  int hypothesis_count_ = 0;
  int consecutive_rejections_ = 0;
  int64_t accepted_ = 0, rejected_ = 0, relocalizations_ = 0, stale_ = 0, unmapped_scans_ = 0;
  int64_t refused_relocalizations_ = 0, small_disagreements_ = 0;
  // The points of `points` (robot frame) that are dynamic at the laser's map-frame pose m.
  std::vector<bool> DynamicPoints(const Pose2& m, const std::vector<Eigen::Vector2d>& points) const;
  void AgeMap();  // moves the laser map's points older than dynamic_map_age_s into old_map_
  std::deque<std::pair<int64_t, size_t>> map_sizes_;  // (utime, map size) after the recent scans, oldest first
  PointGridMap old_map_;  // the laser map's points at least dynamic_map_age_s old (its first old_added_)
  size_t old_added_ = 0;
  double occluded_fraction_ = 0;
  int64_t dynamic_points_ = 0, dynamic_overflow_scans_ = 0;
  double travelled_since_scan_m_ = 0;  // odometry distance since the last scan [m]
  std::vector<Eigen::Vector2d> last_points_;  // a sample of the last scan (robot frame)
  // laser_min_constraint: P_l and d (map frame; see the option).
  Eigen::Matrix3d laser_cov_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d drift_ = Eigen::Vector3d::Zero();
  double weakest_constraint_ = 0;
  bool degenerate_ = false;
  int64_t degenerate_scans_ = 0;
  double travelled_since_new_cells_m_ = 0;  // odometry distance since the last scan that mapped new cells [m]
  double travelled_since_fix_m_ = 0;  // odometry distance since the last accepted visual fix [m]
  bool have_fix_ = false;
  void UpdateLaserCovariance(const LaserSlamUpdate& u);
};

}  // namespace snapnav::nav
