#pragma once
// RatSLAM on the simulator, with ground truth (library snapnav_ratslam_eval; eval-ratslam is its
// thin binary, `./snapnav eval ratslam`).
//
// RunSimulatedSensors drives a scene's route with the sim process's physics, odometry, laser and
// camera, and hands every reading to a SimSensorSink in time order: odometry increments at the
// odometry rate, laser scans at the laser rate and grey panoramas at the camera rate. It is the
// evaluations' simulation harness (sim_harness.hpp) as eval::SimulateSlamLog drives it (same
// options, same seed: the same odometry, scans and truth), with the camera added, so a comparison
// can run laser SLAM, RatSLAM and dead reckoning on one run.
//
// EvaluateRatSlam feeds RatSlam (and dead reckoning) from such a run and measures both against the
// truth at every frame: ATE after SE(2) alignment (and without: all start at the true start pose),
// RPE, loop closures, templates, experiences, the time per update; WriteRatSlamEvaluation writes
// summary.json, the experience map over the ground truth and the error plot.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slam_sim.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::eval {

struct SimCameraOptions {
  SimSlamOptions sim;                    // scene, route, laps, seed, rates, robot, laser
  double camera_rate_hz = 10;            // must divide sim.physics_rate_hz
  nav::sim::OmniCameraOptions camera;    // camera geometry; its panorama model is the panorama's
  nav::sim::ImageEffectsOptions effects; // blur, noise, illumination (applied to the rendered image)
  // Render the raw catadioptric image and unwrap it (what the ratslam process sees on OMNI_FRAME)
  // instead of rendering the panorama directly (OMNI_PANORAMA). Slower, blurrier. Required by the
  // realistic camera (camera.optics.enabled), whose optics act on the raw image; FromSimConfig sets it then.
  bool raw_frames = false;
  bool people = true;                    // the scene's walking people (if any) occlude the camera
  cv::Mat raw_mask;                      // the raw image's mask (SimFrameOptions::raw_mask); raw frames only
  bool truth_mask = false;               // ... or the renderer's robot parts
  void Validate() const;                 // throws std::invalid_argument
  // From the sim process's configuration (config/sim.ini): SimSlamOptions::FromSimConfig plus the
  // camera rate, geometry and effects.
  static SimCameraOptions FromSimConfig(const processes::SimConfig& sim);
};

// Readings in publishing order. Truth is in the frame of the true start pose (the frame dead
// reckoning, laser SLAM and RatSLAM start in), as SimulatedSlamLog's reference.
class SimSensorSink {
 public:
  virtual ~SimSensorSink() = default;
  // An odometry increment (robot frame of the previous reading) over dt_s, as the ODOMETRY message;
  // from the second reading on (the first only fixes the start, as in the processes).
  virtual void OnOdometry(int64_t /*utime*/, const nav::Pose2& /*delta*/, double /*dt_s*/, const nav::Pose2& /*truth*/) {}
  virtual void OnScan(int64_t /*utime*/, const laser_scan_t& /*scan*/) {}
  // A grey panorama (CV_8UC1, the camera's panorama model: columns over 360 degrees).
  virtual void OnPanorama(int64_t /*utime*/, const cv::Mat& /*gray*/, const nav::Pose2& /*truth*/) {}
  // The panoramas' self-occlusion mask (non-zero usable), before the first panorama, when there is one.
  virtual void OnPanoramaMask(const cv::Mat& /*mask*/) {}
};

// The drive: scene, route, start, laps, simulated time, distance, readings (odometry counts the
// first reading, which the sink does not get), time spent rendering.
using SimCameraRun = SimDriveResult;

// Runs the simulation; `progress` (may be empty) gets the simulated time and the laps done about
// once per simulated 10 s. Throws as SimulateSlamLog.
SimCameraRun RunSimulatedSensors(const SimCameraOptions& options, SimSensorSink& sink,
                                 const std::function<void(double, int)>& progress = {});

struct RatSlamEvalOptions {
  SimCameraOptions run;
  nav::RatSlamOptions ratslam;
  double rpe_delta_m = 1.0;  // RPE over this much travel [m]
  std::string mask = "none";  // where run's mask came from, for the reports: none | calibrated | truth | a file
};

struct RatSlamEvaluation {
  SimCameraRun run;
  nav::sim::Scene scene;  // for the figures (walls)
  // At every frame, in the start frame: the truth, RatSLAM's pose, the current experience's pose
  // (OpenRatSLAM's output; the previous one before the first), dead reckoning.
  std::vector<int64_t> utime;
  std::vector<nav::Pose2> truth, ratslam, experience, dead_reckoning;
  // What each frame did: the view template (new or not, its difference, -1: none compared), the
  // heading offset of the view, the current experience and the pose-cell peak [cells].
  struct FrameTrace {
    int template_id = -1;
    bool new_template = false;
    double difference = -1, relative_rad = 0;
    int experience = -1;
    double pc_x = 0, pc_y = 0, pc_th = 0;
  };
  std::vector<FrameTrace> trace;
  TrajectoryErrors ratslam_errors, experience_errors, dead_reckoning_errors;
  // The final experience map and counts.
  std::vector<nav::Experience> experiences;
  std::vector<nav::ExperienceLink> links;
  int loop_closures = 0, switches = 0, templates = 0, injections = 0;
  std::vector<double> loop_closure_travel_m;  // distance travelled at each loop closure [m]
  // The true pose (start frame) where each experience was created, and for each loop-closure link
  // the true distance between its two experiences [m]: a correct loop closure joins places close
  // together, a false one (perceptual aliasing) far-apart places.
  std::vector<nav::Pose2> experience_truth;
  std::vector<double> loop_closure_true_distance_m;
  int false_loop_closures(double max_distance_m = 1.0) const;
  // Links whose odometry distance differs from the true distance between their experiences by
  // more than `tolerance_m` (a loop closure to the wrong place, or a move to a wrong experience).
  int inconsistent_links(double tolerance_m = 0.5) const;
  // Wall time per call (median over all calls; mean beside it) [ms].
  double odometry_ms_median = 0, odometry_ms_mean = 0, image_ms_median = 0, image_ms_mean = 0;
  double odometry_rate_hz = 0, camera_rate_hz = 0;
  // The share of one core RatSLAM needs at these rates: ms per second of sensor data / 1000.
  double core_load() const { return (odometry_ms_mean * odometry_rate_hz + image_ms_mean * camera_rate_hz) / 1000.0; }
};

// Runs the simulation with RatSlam (started at the origin of the start frame) and dead reckoning
// on it. Throws std::runtime_error if fewer than 2 frames were seen.
RatSlamEvaluation EvaluateRatSlam(const RatSlamEvalOptions& options,
                                  const std::function<void(double, int)>& progress = {});
// The same with several RatSLAM configurations on one simulated run (rendered once): one
// evaluation per entry of `variants` (options.ratslam is not used).
std::vector<RatSlamEvaluation> EvaluateRatSlamVariants(const RatSlamEvalOptions& options,
                                                       const std::vector<nav::RatSlamOptions>& variants,
                                                       const std::function<void(double, int)>& progress = {});

// The experience map (links grey, loop-closure links red, experiences blue) over the ground truth
// (green) and dead reckoning (grey), with the scene's walls, in the scene frame.
cv::Mat DrawExperienceMap(const RatSlamEvaluation& e, const std::string& title);

// summary.json (flat keys: ratslam_ate_rmse_m, dead_reckoning_ate_rmse_m, ratslam_loop_closures,
// ratslam_ms_per_odometry, ...), experience_map.png, errors.png and trajectories.csv in `dir`
// (created). Throws std::runtime_error naming a file that cannot be written.
void WriteRatSlamEvaluation(const RatSlamEvaluation& e, const RatSlamEvalOptions& options, const std::string& dir);

// The evaluation's figures, one line each, for the terminal.
void PrintRatSlamEvaluation(std::ostream& out, const RatSlamEvaluation& e);

}  // namespace snapnav::eval
