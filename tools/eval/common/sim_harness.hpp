#pragma once
// One simulation harness for the evaluations: the sim process's drive loop without the bus. A
// scene's route (or a given one) is driven with the sim's physics, control error and odometry
// noise; odometry, laser scans and (when wanted) camera frames are made at their rates, in the
// order the sim process publishes them, and handed to a SimDriveSink. A frame is rendered only
// when the sink wants frames: a laser-only evaluation pays nothing for the camera, and since the
// scans are drawn either way, a run with frames has the same odometry, scans and truth as one
// without.
//
// eval::SimulateSlamLog (slam_sim.hpp: the laser SLAM inputs and the written log) and
// eval::RunSimulatedSensors (ratslam_eval.hpp: RatSLAM's odometry and panoramas) both drive
// through it.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/sim/world.hpp"
#include "snapnav/odometry_t.hpp"

namespace snapnav::eval {

// What is driven, and how long.
struct SimDriveOptions {
  std::string scene = "corridor";             // name (config/scenes/NAME.scene) or path, as for sim
  std::vector<Eigen::Vector2d> route;         // waypoints [m]; empty: the scene's route
  int laps = 2;                               // stop after this many laps of the route; 0: no limit
  double duration_s = 0;                      // stop after this much simulated time [s]; 0: no limit
  uint64_t seed = 1;
  int64_t start_utime = 1'700'000'000'000'000;  // utime of the first message [us]
  double physics_rate_hz = 100;               // motion step; the sensor rates must divide it
  double odometry_rate_hz = 50;
  double laser_rate_hz = 10;
  double route_speed_mps = 0.3;
  double route_tolerance_m = 0.1;             // a waypoint is reached this close
  nav::sim::DriveOptions drive;               // control error and odometry noise
  nav::sim::LaserOptions laser;
  nav::sim::KidnapOptions kidnap;             // a kidnapping (World::SetKidnap); the route goes on from the
                                              // nearest waypoint ahead (RouteDriver::Restart)
};

// The camera, for sinks that want frames.
struct SimFrameOptions {
  double rate_hz = 10;                    // must divide the physics rate
  nav::sim::OmniCameraOptions camera;     // camera geometry; its panorama model is the frames'
  nav::sim::ImageEffectsOptions effects;  // blur, noise, illumination (applied to the rendered image)
  // Render the raw catadioptric image and unwrap it (what a process sees on OMNI_FRAME) instead
  // of rendering the panorama directly (OMNI_PANORAMA). Slower, blurrier.
  bool raw_frames = false;
  bool people = true;                     // the scene's walking people (if any) occlude the camera
  // The raw image's self-occlusion mask (raw frames only; image_mask.hpp: non-zero usable, the raw
  // image's size; empty: none), or truth_mask: the renderer's robot parts grown by 2 px. Unwrapped
  // as the processes do (masked panorama pixels filled); the sink gets the panorama's mask.
  cv::Mat raw_mask;
  bool truth_mask = false;
};

// What the drive emits, in publishing order. Poses are true poses in the scene.
class SimDriveSink {
 public:
  virtual ~SimDriveSink() = default;
  // Before the first step: the scene and the true start pose.
  virtual void OnStart(const nav::sim::Scene& /*scene*/, const nav::Pose2& /*start*/) {}
  // Every ODOMETRY message, the first (which only fixes the start) included.
  virtual void OnOdometry(const odometry_t& /*msg*/, const nav::Pose2& /*truth*/) {}
  virtual void OnScan(const laser_scan_t& /*scan*/) {}
  // Frames are rendered only for a sink that wants them (and a drive given SimFrameOptions).
  virtual bool WantsFrames() const { return false; }
  // A grey panorama (CV_8UC1, the camera's panorama model: columns over 360 degrees).
  virtual void OnFrame(int64_t /*utime*/, const cv::Mat& /*gray*/, const nav::Pose2& /*truth*/) {}
  // With a mask (SimFrameOptions), before the first frame: the panorama's mask (non-zero usable).
  virtual void OnPanoramaMask(const cv::Mat& /*mask*/) {}
  // Every physics step after its sensors, before the robot moves (time, the world).
  virtual void OnStep(int64_t /*utime*/, const nav::sim::World& /*world*/) {}
};

struct SimDriveResult {
  std::string scene_name;
  std::vector<Eigen::Vector2d> route;  // the route driven
  nav::Pose2 start;                    // true start pose in the scene [m, rad]
  int laps = 0;                        // laps completed
  double duration_s = 0;               // simulated time [s]
  double distance_m = 0;               // travelled by the robot (truth) [m]
  int collisions = 0;                  // physics steps blocked by an obstacle
  int64_t odometry = 0, scans = 0, frames = 0;  // readings made [count]
  double render_s = 0;                 // wall time spent rendering frames [s]
};

// Drives the simulation (options as validated by the caller; `frames` may be null: no camera).
// `what` begins the error of a robot that cannot finish its laps ("slam sim"); `progress` (may be
// empty) gets the simulated time and the laps done about once per simulated 10 s. Throws
// std::runtime_error for a scene that cannot be loaded or has no route (and none is given), or a
// robot that cannot finish its laps in three times the expected time plus a minute.
SimDriveResult DriveSimulation(const SimDriveOptions& options, const SimFrameOptions* frames, SimDriveSink& sink,
                               const std::string& what, const std::function<void(double, int)>& progress = {});

// Physics steps per sensor reading; throws std::invalid_argument unless `rate_hz` divides the
// physics rate (`what` names the sensor in the message).
int EveryNSteps(double physics_hz, double rate_hz, const char* what);
// The length of a closed route (back from the last waypoint to the first) [m].
double RouteLength(const std::vector<Eigen::Vector2d>& route);

}  // namespace snapnav::eval
