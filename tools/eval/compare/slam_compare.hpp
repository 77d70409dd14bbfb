#pragma once
// The SLAM comparison of issue 8 (thesis 1.2, 5, 6.3.3): dead reckoning, laser-only SLAM
// (nav::LaserSlam), RatSLAM and fused visual + laser SLAM (nav::FusedSlam) on the same simulated
// run with ground truth.
//
//   memory   a place-cell memory explored beforehand in a separate run with its own seed: the
//            scene's route driven once (from the start pose, back to the first waypoint) with a
//            cell every cell_spacing_m of travel, views from raw omni images rendered and
//            unwrapped (the real pipeline). Each cell's pose is what a lab's robot knows while it
//            explores (explore_pose = laser-slam or fused-slam: that SLAM's pose over the
//            exploration's own noisy odometry and scans, as the placecells process stores
//            POSE_LASER_SLAM or POSE_EKF) or, as a labelled upper bound, the true pose (truth: as
//            eval localization's route memory);
//   the run  eval::SimulateSlamLog drives the route with the sim's noise and control error (and
//            an optional kidnapping); dead reckoning and laser SLAM run over its odometry and
//            scans by eval::RunSlam, as eval-slam does; fused SLAM runs beside the simulation on
//            the same odometry and scans, with a place-cell fix every 1 / visual_rate_hz s (the
//            view rendered at the true pose with the scene's people, localized against the
//            memory); beside it the same fused SLAM with no visual measurement (fused_no_vision,
//            the ablation: what the place cells add); RatSLAM gets every frame at ratslam_rate_hz (a grey panorama) and the
//            odometry. The scene's people walk through camera and laser views but do not block the
//            robot (DriveOptions::people_block_robot = false: otherwise robot and people wait for
//            each other for ever).
//   frames   every method's pose at every scan in the scene (place-memory) frame: dead
//            reckoning and laser SLAM start at the origin of their odometry frame and are moved
//            by the true start pose (the sim's odometry starts there); fused SLAM and RatSLAM
//            start at it.
// Errors: ATE after SE(2) alignment (as eval-slam; *_ate_rmse_m) and without (the scene frame),
// RPE over rpe_delta_m of travel, the position error at every scan, and after a kidnapping the
// time until the fused error is back under recovery_error_m for recovery_hold_s.
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slam_sim.hpp"
#include "snapnav/nav/slam/fused_slam.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::eval {

// The methods in table order (summary.json keys start with these names).
// dead_reckoning, laser_slam, ratslam, fused_slam, and the ablation fused_no_vision (fused SLAM given
// no visual measurement: what the place cells add is fused_slam against it).
const std::vector<std::string>& CompareMethodNames();
// Whether this build has RatSLAM (nav::RatSlam, library snapnav_ratslam): it has, since the
// ratslam branch was merged; kept for the summary's "ratslam" entry.
bool RatSlamAvailable();

struct CompareOptions {
  nav::sim::OmniCameraOptions camera;   // the simulator's camera, mirror and panorama
  std::string mask = "none";            // the raw frames' self-occlusion mask (homing_eval.hpp UseMask)
  nav::sim::ImageEffectsOptions effects;
  double visual_rate_hz = 2;            // place-cell fixes per second of simulated time
  double ratslam_rate_hz = 10;          // frames to RatSLAM per second
  bool run_ratslam = true;              // if the build has it
  // The place-cell memory and the localization (the placecells process' options).
  nav::PlaceViewOptions view;
  nav::LocalizerOptions localizer;
  nav::VocabularyOptions vocabulary;
  double cell_spacing_m = 0.25;         // a cell every this much travel of the exploration
  uint64_t explore_seed = 101;          // the exploration run's seed (not the evaluated run's)
  // Where the exploration places its cells: laser-only SLAM's or fused SLAM's pose during the
  // exploration (what a robot without ground truth has; fused SLAM with no memory yet is its laser
  // with the people test, config/fused_slam.ini) or the true pose (an upper bound no robot has).
  enum class ExplorePose { kLaserSlam, kFusedSlam, kTruth };
  ExplorePose explore_pose = ExplorePose::kFusedSlam;
  // Localize with the fused pose as the distance filter's prediction. Off: every fix is a global
  // localization, independent of the filter (after a kidnapping a prediction from the lost pose
  // would deny the cells where the robot really is).
  bool visual_prediction = false;
  nav::RatSlamOptions ratslam;          // RatSLAM (config/ratslam.ini's [ratslam])
  nav::LaserSlamOptions laser;          // laser-only SLAM
  nav::FusedSlamOptions fused;          // fused SLAM
  double rpe_delta_m = 1.0;             // RPE over this much travel [m]
  double recovery_error_m = 0.3;        // kidnapping: recovered once the fused error stays below this [m] ...
  double recovery_hold_s = 5.0;         // ... for this long (or to the end of the run) [s]
  void Validate() const;                // throws std::invalid_argument
};

// A place-cell memory explored along a scene's route.
const char* ExplorePoseName(CompareOptions::ExplorePose p);  // "laser-slam", "fused-slam", "truth"

struct RouteMemory {
  std::unique_ptr<nav::PlaceCellMemory> memory;
  std::vector<nav::Pose2> cell_poses;  // true poses of the cells (scene frame)
  std::vector<nav::Pose2> cell_estimates;  // the poses stored in the memory (= cell_poses with explore_pose truth)
  // The stored poses' error against the truth [m]: mean and max (0 with explore_pose truth).
  double cell_error_mean_m = 0, cell_error_max_m = 0;
  double seconds = 0;                  // rendering, views and index
  double ms_per_view = 0;              // rendering + MakePlaceView per cell
  cv::Mat raw_mask;  // the raw frames' mask its views were made with (options.mask; empty: none): the runs' too
};
// Explores `scene`'s route (see the header comment) with the robot, laser and rates of `sim`
// (its seed, stop condition and kidnapping are replaced: options.explore_seed, one lap, none).
// Throws std::runtime_error for a scene without a route.
RouteMemory ExploreRouteMemory(const nav::sim::Scene& scene, const CompareOptions& options, const SimSlamOptions& sim);

// One method's result on one run.
struct MethodResult {
  std::string name;                   // as CompareMethodNames()
  bool ran = false;                   // false: `note` says why not
  std::string note;
  std::vector<nav::Pose2> poses;      // at every scan, scene frame
  TrajectoryErrors errors;
  std::vector<double> error_m;        // position error at every scan (no alignment) [m]
  int64_t updates = 0;                // calls of its main update (odometry, scans, frames)
  std::string update_unit;            // "odometry message", "scan", "frame"
  double ms_per_update = 0;           // mean wall time of the main update [ms]
  double ms_per_frame = 0;            // all of its work per 10 Hz period (total / scans) [ms]
  double ms_max_update = 0;           // slowest main update [ms]
};

struct CompareRunOptions {
  std::string name;                   // run name (output folder, key prefix): "corridor", "corridor_kidnap"
  SimSlamOptions sim;                 // the simulated run (scene, seed, noise, laps or duration, kidnapping)
};

struct CompareRun {
  std::string name, scene;
  double duration_s = 0, distance_m = 0;
  int64_t scans = 0, odometry = 0, frames = 0, collisions = 0, people = 0;
  std::vector<int64_t> utime;         // of every scan
  std::vector<double> time_s;         // since the start, of every scan
  std::vector<nav::Pose2> truth;      // at every scan, scene frame
  std::vector<MethodResult> methods;  // CompareMethodNames() order
  std::vector<Eigen::Vector3d> fused_sigma;  // fused SLAM's std. dev. of x [m], y [m], theta [rad] at every scan
  std::vector<Eigen::Matrix3d> fused_covariance;  // ... its covariance (scene frame)
  // Fused SLAM's estimate of its laser map's offset from the world at the robot (x, y in the scene
  // frame's axes [m], heading [rad]) and the std. devs., at every scan.
  std::vector<Eigen::Vector3d> fused_map_offset, fused_map_offset_sigma;
  // Consistency of fused SLAM's covariance: the mean normalised estimation error squared
  // (e^T P^-1 e over x, y, theta at every scan; 3 for a consistent filter) and the share of scans
  // where it is within the chi-square 95 % bound (7.81).
  double fused_nees_mean = 0, fused_nees_within_95 = 0;
  // The same of the ablation (fused SLAM without visual fixes: its laser and its map-offset model
  // alone), with its covariance at every scan; and both NEES at every scan (trajectories.csv).
  std::vector<Eigen::Matrix3d> no_vision_covariance;
  double no_vision_nees_mean = 0, no_vision_nees_within_95 = 0;
  std::vector<double> fused_nees, no_vision_nees;
  // Fused SLAM's laser part (its covariance relative to its own map, scene frame's axes): std. devs. at every scan.
  std::vector<Eigen::Vector3d> fused_laser_sigma;
  // Its laser's information per matched point along the weakest position direction (see
  // nav::FusedSlamOptions::laser_min_constraint) at every scan, and the scans where it was left out.
  std::vector<double> fused_weakest_constraint;
  int64_t fused_degenerate_scans = 0;
  std::vector<Eigen::Vector2d> map;   // fused SLAM's map at the end
  int memory_cells = 0;
  double memory_cell_error_mean_m = 0, memory_cell_error_max_m = 0;  // the cells' stored poses against the truth
  std::string memory_explore_pose;    // ExplorePoseName of the exploration
  // Visual measurements of fused SLAM.
  int64_t visual_queries = 0, visual_no_answer = 0;
  int64_t visual_accepted = 0, visual_rejected = 0, relocalizations = 0, visual_stale = 0, unmapped_scans = 0;
  int64_t relocalizations_refused = 0;
  double visual_error_mean_m = 0, visual_error_median_m = 0;  // place-cell fixes against the truth
  double ms_per_view = 0, ms_per_localize = 0, ms_per_fix_filter = 0;  // view, Localize, FusedSlam::AddVisual
  std::vector<nav::Pose2> fixes;      // place-cell fixes (scene frame)
  std::vector<std::string> fix_outcomes;
  std::vector<double> fix_time_s;
  // Per fix: the true pose then, its Mahalanobis distance^2 against the filter, the last scan's
  // occluded fraction (FusedSlam::occluded_fraction) and the distance to the nearest person (NaN
  // without people) [m].
  std::vector<double> fused_occluded_fraction;  // per scan: FusedSlam::occluded_fraction
  std::vector<nav::Pose2> fix_truth;
  std::vector<double> fix_mahalanobis2, fix_occluded_fraction, fix_nearest_person_m;
  int64_t dynamic_points = 0, dynamic_overflow_scans = 0;  // FusedSlam's
  std::vector<double> relocalization_time_s;
  // Kidnapping.
  bool kidnapped = false;
  double kidnap_at_s = 0;
  double recovery_s = std::numeric_limits<double>::quiet_NaN();     // NaN: not recovered
  double first_under_s = std::numeric_limits<double>::quiet_NaN();  // first scan back under the bound
  double recovery_error_m = 0;
  int64_t ratslam_loop_closures = 0, ratslam_experiences = 0;
  double seconds = 0;                 // wall time of the run
  const MethodResult& method(const std::string& name) const;
};

// Simulates the run and runs the four methods (see the header comment). `progress` gets text
// lines. Throws std::runtime_error when the simulation fails.
CompareRun RunComparison(const nav::sim::Scene& scene, const RouteMemory& memory, const CompareRunOptions& run,
                         const CompareOptions& options, const std::function<void(const std::string&)>& progress = {});

// Laser methods on a recorded log (eval-slam's inputs: LoadSlamLog, LoadReference, RunSlam):
// dead reckoning and laser SLAM; RatSLAM and fused SLAM need frames the logs do not have.
struct LogComparison {
  std::string log, reference;
  int64_t scans = 0;
  bool has_reference = false;
  MethodResult dead_reckoning, laser_slam;  // errors against the reference (aligned ATE)
};
LogComparison CompareOnLog(const std::string& log_path, const std::string& reference_path,
                           const nav::LaserSlamOptions& laser, double rpe_delta_m);

// Outputs of one run into `dir`: summary.json (flat keys: <method>_ate_rmse_m ..., see
// SummaryKeys), trajectories.png (every method with the truth over fused SLAM's map),
// errors.png (position error over time), timing.png (ms per 10 Hz frame), trajectories.csv,
// fixes.csv.
void WriteCompareRun(const CompareRun& run, const std::string& dir);
// The flat summary keys of a run (name, value), values in the units their names carry; a method
// that did not run has NaN values (written as null).
std::vector<std::pair<std::string, double>> SummaryKeys(const CompareRun& run);
// The table of several runs (markdown, and CSV with one row per run and method).
std::string CompareTableMarkdown(const std::vector<CompareRun>& runs, const std::vector<LogComparison>& logs);
std::string CompareTableCsv(const std::vector<CompareRun>& runs, const std::vector<LogComparison>& logs);

// Issue 8's targets on a run: fused SLAM's ATE is the lowest of the methods that ran; after a
// kidnapping it recovered within `max_recovery_s`. Lines describing what missed (empty: met).
std::vector<std::string> MissedTargets(const CompareRun& run, double max_recovery_s = 10.0);

}  // namespace snapnav::eval
