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
#include "snapnav/nav/slam/map_matcher.hpp"
#include "snapnav/nav/slam/odometry_calibration.hpp"
#include "snapnav/nav/slam/point_grid_map.hpp"
#include "snapnav/nav/slam/wall_orientations.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// The EKF update with a direct pose measurement z (H = I): K = P (P + R)^-1. The angle
// innovation is wrapped. Returns the updated pose; `covariance` is updated in place.
Pose2 EkfPoseUpdate(const Pose2& pose, Eigen::Matrix3d* covariance, const Pose2& z, const Eigen::Matrix3d& r);

// LaserSlamOptions::stale_fraction applies above this motion per scan, in translation and in heading.
constexpr double kStaleMinMotionM = 0.05;
constexpr double kStaleMinTurnRad = 5 * kRadPerDeg;

// The filter's options; the matcher's (MatcherOptions) are its base.
struct LaserSlamOptions : MatcherOptions {
  // Odometry noise Q of the prediction, over the whole motion between two scans
  // (motion_noise_per_scan): 5 % of the distance, 0.2 rad per radian turned and 2 deg per metre
  // driven, as std. devs. -- wheel odometry of a robot not calibrated for this map (a real robot's
  // turns: CSAIL's heading is off by 7 deg in one in ten 0.3 rad turns).
  DeadReckoningOptions motion = [] {
    DeadReckoningOptions m;
    m.rotation_noise_rad_per_rad = 0.2;
    m.rotation_noise_rad_per_m = 0.035;
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
  double turn_noise_rad_per_rad = 0;
  // Odometry's error per scan interval whatever its length, added to the prediction when odometry
  // moved (std. devs.): odometry read at another moment than the scan (CSAIL: +-5 cm and +-2 deg
  // between a scan's odometry and where the scans put it, even on short intervals).
  double interval_sigma_xy_m = 0.03;
  double interval_sigma_theta_rad = 1.5 * kRadPerDeg;
  // ... in full from an interval of this much travel or turn, in proportion below it (the robot
  // moved that much less in the moment odometry is off; a 10 Hz log's 3 cm intervals would
  // otherwise gain 3 cm of noise per scan, a random walk that outweighs odometry along a
  // corridor). 0 and 0: in full whatever the interval.
  double interval_full_m = 0.3;
  double interval_full_rad = 15 * kRadPerDeg;
  // The prediction's noise: from the whole motion between two scans (true: its distance and turn,
  // one error however many odometry messages it came in, as wheel odometry's systematic errors
  // grow), or summed over the odometry increments (false: thesis 5.3.1, the EKF predicting each
  // reading; its covariance then shrinks as the odometry rate grows).
  bool motion_noise_per_scan = true;
  // Stale odometry (what a frozen or lagging odometry stands for): when odometry reports no motion
  // at all since the last scan, or translates less than stale_fraction of the last scan-to-scan
  // motion (when that was at least kStaleMinMotionM) while the robot was moving, odometry may have
  // stopped reporting (CSAIL: the same odometry pose for up to 5 scans while the robot turns, then
  // a jump of 0.5 m and 85 deg) -- or the robot stopped, or turned on the spot (a keyframe log).
  // The scan decides: the last scan-to-scan motion is searched as a second prediction beside
  // odometry's, and taken when it scores better by hypothesis_margin. After such scans, when
  // odometry moves again, its increment less the motion the scans tracked meanwhile (the catch-up
  // of a frozen reading) is the second prediction. false: odometry's prediction only.
  bool stale_odometry = true;
  double stale_fraction = 0.25;
  // A second prediction (stale odometry, catch-up) is tried when its search's best is this many
  // times more probable than the default prediction's (posteriors: kernel and prior, in nats of
  // search_prior_weight kernel points).
  double hypothesis_odds = 10;
  // The map's own local error (walls placed a few cm off by earlier scans, 5 cm cells): the pose is
  // known relative to the world no better than this after a match, however well the scan fits the
  // map (ICP's covariance from its residuals treats every point as independent). A floor of the
  // covariance after each update (std. devs.; scaled as the interval noise, interval_full_*), so
  // the next prediction and its gate allow for it.
  double match_sigma_xy_m = 0.02;
  double match_sigma_theta_rad = 0.75 * kRadPerDeg;
  // The gate: a match is a measurement only when the squared Mahalanobis distance of its
  // innovation (ICP pose - prediction, covariance prediction + measurement) is below this
  // (chi-square, 3 degrees of freedom: 16.27 for 99.9 %). Beyond it the filter coasts on the
  // prediction and the scan does not map. 0: no gate.
  double gate_mahalanobis2 = 16.27;
  // A weak match's gate: a match that explains less than gate_full_fit of the scan (its fit) gets
  // the gate scaled by fit / gate_full_fit: the less of the scan it explains, the closer to the
  // prediction it must lie (a fifth of a scan far from a sparse map is weak evidence against the
  // odometry; outlier_min_fit's 0.8, the fit of a strong match). 0: the gate is gate_mahalanobis2
  // at every fit.
  double gate_full_fit = 0.8;
  // Adaptive odometry noise: the prediction's noise (motion and interval) is scaled by a factor
  // that follows the innovations of the matches (their squared Mahalanobis distance per degree of
  // freedom, a running mean over about adaptive_window_scans scans), within [adaptive_scale_min,
  // adaptive_scale_max] (std. devs.): good odometry earns the weight it deserves (the laser does not
  // spoil it), poor odometry is not trusted beyond what the scans show.
  bool adaptive_motion_noise = false;
  double adaptive_window_scans = 20;
  double adaptive_scale_min = 0.1;
  double adaptive_scale_max = 3;
  // Odometry's heavy tails (read at another moment than the scan, a wheel slipping: CSAIL's
  // odometry puts 15 deg of a turn in the wrong interval): a match beyond the gate that fits at
  // least outlier_min_fit of the scan and is unambiguous is still a measurement if it lies inside
  // the gate of the prediction widened outlier_scale times (in std. devs.); the prediction is then
  // widened so, and the update follows the scan. 1: off.
  double outlier_scale = 4;
  double outlier_min_fit = 0.8;
  // Ambiguity: when another of the ICP results (from the search's other maxima), distinct from the
  // best (more than 2 search_sigma_m or 5 search steps away) and inside the gate too, is at least
  // this probable relative to the best (posteriors: kernel and prior), the match is ambiguous: no
  // measurement, no mapping [0-1; 1: off].
  double max_ambiguity = 0.5;
  // An ambiguous match still measures what its alternatives agree on (along a corridor: the heading
  // and the position across it): the update takes the mixture of the best and its distinct
  // alternatives, weighted by their probabilities relative to the best, its mean and covariance
  // (the measurement's plus their spread); no mapping. false: no measurement (coasting).
  bool ambiguous_update = true;
  // The walls' directions as a heading measurement (WallOrientations): after the match, the scan's
  // wall normals, turned by the heading, are aligned with the histogram of the whole map's within
  // +-wall_window_deg (each map direction spread by wall_kernel_deg); the offset is a heading
  // measurement of std. dev. wall_sigma_deg, taken when the alignment's contrast (its score over the
  // mean across the window) is at least wall_min_contrast, the map holds wall_min_map_points points,
  // and its squared Mahalanobis distance is within wall_gate_mahalanobis2 (1 degree of freedom).
  // And where the walls agree with the prediction (within that gate, the prediction's heading known
  // to half the window), a match whose heading differs from the walls' beyond the gate (against the
  // match's own heading variance plus wall_sigma_deg's) is gated: LaserSlamUpdate::wall_gated.
  // A building's walls stay parallel over a floor: the local map's small turns scan by scan do not
  // add up. The map's histogram is built from the scans' points as they join the map (ResetMap keeps
  // it; SeedMap adds none: localization in a saved map runs without it). false: off. (GraphSlam's
  // front end uses it as the EKF does.)
  bool wall_orientation = true;
  double wall_window_rad = 10 * kRadPerDeg;
  double wall_kernel_rad = 1 * kRadPerDeg;
  double wall_sigma_rad = 1 * kRadPerDeg;
  double wall_min_contrast = 1.5;
  double wall_min_map_points = 500;
  double wall_gate_mahalanobis2 = 10.83;
  // A match that explains less than this fraction of the scan (its fit) is too weak to be a
  // measurement: the scan sees mostly what the map does not hold (new ground, a wrong place).
  // The filter coasts; the scan maps (new ground must join the map) [0-1, 0: off].
  double min_fit = 0.15;
  // A scan is this much older than its utime (a laser on a slow serial line stamps it when it has
  // arrived: CSAIL's SICK, its odometry pose half a scan interval ahead of the scan). The scan is
  // matched at its utime minus this, odometry interpolated (LaserSlam's timed Predict / Update).
  // 0 (the default): stamped at acquisition, as laser-hokuyo and the simulator do; a latency set
  // for such a laser puts pose() that much odometry ahead of the truth.
  double scan_latency_s = 0;
  // After ICP, a fit (fraction of the points within match_distance_m / 2 of the map) below this
  // searches the largest window (search_window_max_deg, search_window_xy_m) around the prediction,
  // its prior kept, and aligns again; the better fit is the match (and must pass the gate).
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
  // Odometry's systematic errors (heading drift per metre, turn and distance scale) estimated
  // online from stretches of good matches (OdometryCalibration), always (LaserSlamUpdate's
  // odometry_* fields); with `apply` the prediction uses odometry corrected by them. Evidence:
  // stretches whose every scan was accepted from odometry's prediction with a fit of at least
  // outlier_min_fit.
  OdometryCalibrationOptions odometry_calibration;
  void Validate() const;                    // throws std::invalid_argument
};

// The motion noise model's heading variance over a stretch of odometry (its rotation noise per
// radian turned and per metre driven): what OdometryCalibration weighs corrected odometry against.
double MotionHeadingVariance(const DeadReckoningOptions& motion, double path_m, double turn_rad);

// The thesis' own procedure (5.3.1) on `base`'s map settings: point-to-point ICP at one match
// distance (0.25 m) from the odometry prediction, no search, dead reckoning's odometry noise summed
// per increment, the exact nearest map point, every match an update (no gate, no stale odometry,
// no turn noise, no update check).
LaserSlamOptions ThesisLaserSlamOptions(const LaserSlamOptions& base);

// What became of a scan's match (LaserSlamUpdate::outcome).
enum class MatchOutcome {
  kMapStart,   // the first scan: it starts the map
  kAccepted,   // the match passed the gate: an EKF update
  kGated,      // the match is inconsistent with the prediction (beyond the gate): coasting, not mapped
  kAmbiguous,  // another, distinct match fits nearly as well: not mapped; the alternatives' mixture is the
               // measurement (ambiguous_update), or coasting
  kNoMatch,    // too few points matched the map, or fewer than min_fit of them (new ground, or an empty
               // scan): coasting, mapped
};
const char* MatchOutcomeName(MatchOutcome o);
// Which prediction the scan was matched from (LaserSlamUpdate::prediction).
enum class PredictionSource {
  kOdometry,  // odometry since the last scan
  kStale,     // the last scan-to-scan motion: odometry looked stale (frozen or lagging)
  kCatchUp,   // odometry's increment since it went stale, less the motion the scans tracked
};
const char* PredictionSourceName(PredictionSource p);

struct LaserSlamUpdate {
  MatchOutcome outcome = MatchOutcome::kNoMatch;
  PredictionSource prediction = PredictionSource::kOdometry;
  bool measured = false;       // the scan gave a pose measurement (outcome kAccepted, or kAmbiguous with
                               // ambiguous_update: the alternatives' mixture)
  int points = 0, matches = 0, added = 0, iterations = 0;
  double fit = 0;              // fraction of the points within match_distance_m / 2 of the map after ICP
  double kernel = 0;           // the match's kernel score per point (0-1: how well the scan fits the map there)
  double ambiguity = 0;        // the best distinct other match's probability relative to this one's (0: none)
  double mahalanobis2 = 0;     // squared Mahalanobis distance of the innovation (gate_mahalanobis2)
  int predictions = 1;         // predictions searched (odometry's; a stale or catch-up one)
  int searches = 0;            // 1 if the heading was searched before ICP
  int starts = 0;              // ICP runs from the search's maxima (refine_starts; a recovery's included)
  int pruned = 0;              // ... of them ended early as clearly worse (refine_prune_iterations)
  int recoveries = 0;          // 1 if a poor fit started a wider search
  bool stale_odometry = false; // predicted from the last motion (prediction kStale)
  bool widened = false;        // the update scored below the ICP pose: the prediction was widened
  int64_t coasting = 0;        // scans since the last accepted match (0: this one was accepted)
  double motion_noise_scale = 1;  // the odometry noise scale after this scan (adaptive_motion_noise, odometry_calibration_noise)
  bool wall_measured = false;  // the walls' directions measured the heading (wall_orientation)
  bool wall_gated = false;     // ... and gated the match, which turned the heading away from them
  double wall_offset_rad = 0;  // ... the alignment's offset (the heading innovation), 0 without one
  double wall_contrast = 0;    // ... its contrast (0: no alignment)
  // The odometry calibration after this scan (LaserSlamOptions::odometry_calibration; 0: none).
  double odometry_drift_rad_per_m = 0, odometry_turn_scale = 0, odometry_distance_scale = 0;
  int odometry_calibration_stretches = 0;  // stretches in the calibration so far
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
  const OdometryCalibration& odometry_calibration() const { return calibration_; }

 private:
  MapMatcher matcher() const { return MapMatcher(map_, options_); }

  LaserSlamOptions options_;
  Pose2 pose_;
  Eigen::Matrix3d covariance_;
  PointGridMap map_;
  WallOrientations walls_;  // the map's wall directions (wall_orientation)
  // The walls' directions (wall_orientation) for a scan (WallOrientations::Direction of its wall
  // normals in the robot frame) at a pose: the heading offset that aligns them with the map's;
  // `aligned` when the alignment's contrast is at least wall_min_contrast.
  struct WallMeasurement {
    bool aligned = false;
    bool trusted = false;  // the heading is known to half the window (2 std. devs.): the alignment can be no other
    double offset_rad = 0, contrast = 0;
  };
  WallMeasurement AlignWalls(const std::vector<double>& directions_robot, const Pose2& pose,
                             const Eigen::Matrix3d& covariance) const;
  // The offset as a heading measurement (wall_sigma_rad): an EKF update of the pose and its
  // covariance, unless beyond wall_gate_mahalanobis2 (false).
  bool ApplyWalls(double offset_rad, Pose2* pose, Eigen::Matrix3d* covariance) const;
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
  Pose2 odometry_since_scan_;         // odometry's motion since the last scan (corrected)
  // The prediction from one increment of odometry already corrected by the calibration.
  void PredictCorrected(const Pose2& odometry_delta);
  // One raw increment of odometry: added to the calibration's stretch; returned corrected.
  Pose2 TakeOdometry(const Pose2& raw);
  // The odometry calibration and its current stretch: the scan pose it started at (after a good
  // match) and odometry's raw motion since (composed, signed path, summed turn).
  OdometryCalibration calibration_;
  std::optional<Pose2> stretch_start_;
  Pose2 stretch_raw_;
  double stretch_path_m_ = 0, stretch_turn_rad_ = 0;
  void ObserveStretch(LaserSlamUpdate* u, bool good);
  // The covariance's anchor: the pose's covariance at the last scan (or external update), and
  // odometry's motion since (motion_noise_per_scan: the prediction's noise from it as a whole).
  Eigen::Matrix3d anchor_covariance_;
  Pose2 anchor_motion_;
  double anchor_path_m_ = 0, anchor_turn_rad_ = 0;
  // The covariance after `motion` from `from` (covariance `covariance`): the motion noise of its path
  // and turn, and the interval's own (interval_sigma_*) when it moved at all.
  Eigen::Matrix3d IntervalCovariance(const Pose2& from, const Eigen::Matrix3d& covariance, const Pose2& motion,
                                     double path_m, double turn_rad) const;
  void Reanchor();
  // The share of the interval noise (interval_sigma_*, match_sigma_*) an interval of this travel
  // and turn gets: in proportion up to interval_full_m or interval_full_rad, then 1.
  double IntervalShare(double path_m, double turn_rad) const;
  int64_t coasting_ = 0;              // scans since the last accepted match
  double motion_scale2_ = 1;          // the odometry noise scale, squared (adaptive_motion_noise)
  double previous_odometry_turn_rad_ = 0;  // odometry's heading change over the interval before
  std::optional<Pose2> last_scan_pose_;    // the pose after the last scan
  Pose2 last_motion_;                  // the estimate's motion between the last two scans
  std::optional<Pose2> stale_since_;   // the pose at the last scan before odometry went stale
  Pose2 odometry_since_stale_;         // odometry's motion since then

  // ---- For filters built on this one (nav::FusedSlam).
 public:
  // Replaces the pose and its covariance (relocalisation); the map stays as it is.
  void ResetPose(const Pose2& pose, const Eigen::Matrix3d& covariance);
  // Map protection: with add_points false no scan point joins the map; with min_fit > 0 a scan
  // whose ICP fit (LaserSlamUpdate::fit) is below min_fit adds none either (the first scan, which
  // builds the map, always does). Defaults: true, 0 (every scan maps, as before).
  void SetMapping(bool add_points, double min_fit = 0);
  bool adding_points() const { return add_points_; }
  // Localization in a saved map (MapLocalizer): these points (with unit normals, or none) join the
  // map as a scan's would, one per cell; the first scan then matches instead of starting the map.
  void SeedMap(const std::vector<Eigen::Vector2d>& points, const std::vector<Eigen::Vector2d>& normals = {}) {
    for (size_t i = 0; i < points.size(); ++i) map_.Add(points[i], i < normals.size() ? normals[i] : Eigen::Vector2d::Zero());
  }
  // Replaces the map by these points (map frame) with their unit normals (zero: unknown), each
  // kept unless a point already kept lies within add_distance_m (as scans add theirs); the pose
  // stays. The graph back end (GraphSlam) rebuilds its front end's map so from the optimized keyframes.
  void ResetMap(const std::vector<Eigen::Vector2d>& points, const std::vector<Eigen::Vector2d>& normals);
  // The same with a map built elsewhere (MakeMap, points added as ResetMap adds them: AddMapPoint),
  // e.g. on another thread.
  void ResetMap(PointGridMap map) { map_ = std::move(map); }
  static PointGridMap MakeMap(const LaserSlamOptions& options);
  // Adds p to the map unless a point already kept lies within options' add_distance_m (ResetMap's rule).
  static void AddMapPoint(const LaserSlamOptions& options, const Eigen::Vector2d& p, const Eigen::Vector2d& normal,
                          PointGridMap* map);

 private:
  bool MayAddPoints(const LaserSlamUpdate& u) const;
  bool add_points_ = true;
  double min_add_fit_ = 0;
};

}  // namespace snapnav::nav
