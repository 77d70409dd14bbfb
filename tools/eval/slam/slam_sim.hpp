#pragma once
// Laser SLAM inputs from the simulator, with ground truth: drives a scene's route (or a given
// one) with the sim process's physics, sensors and noise, and returns what eval-slam reads
// from a log (odometry increments and scans as points, an eval::SlamLog) plus the true
// trajectory (an eval::Reference by time). Optionally writes the same messages the sim process
// publishes (LASER_SCAN, ODOMETRY, POSE_GROUND_TRUTH; no camera frames) to an LCM log, so a run
// can be replayed on the bus or read by eval-slam.
//
// The steps are made from the encoded messages exactly as eval::LoadSlamLog makes them from a
// log, so the in-memory log and the written one give the same SLAM run. The drive is the
// evaluations' simulation harness (sim_harness.hpp), without the camera.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim_harness.hpp"
#include "sim_node.hpp"
#include "slam_log.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/world.hpp"
#include "snapnav/nav/trajectory.hpp"

namespace snapnav::eval {

// The drive (scene, route, stop condition, seed, rates, robot, laser, kidnapping: SimDriveOptions)
// and what is done with its readings.
struct SimSlamOptions : SimDriveOptions {
  std::string log_path;                       // non-empty: also write the messages to this LCM log
  // Observers, for methods that run beside the simulation (eval compare): each odometry or scan
  // step as it joins the log, and every physics step after its sensors (time, the world).
  std::function<void(const SlamStep&)> on_sensor;
  std::function<void(int64_t utime, const nav::sim::World&)> on_step;
  // Channels of the written log (the sim's defaults).
  std::string scan_channel = channels::kLaserScan;
  std::string odometry_channel = channels::kOdometry;
  std::string ground_truth_channel = channels::kPoseGroundTruth;

  // Throws std::invalid_argument: no stop condition (laps and duration both 0), bad rates
  // (physics must be a whole number of microseconds, each sensor rate must divide it), a
  // non-positive speed or tolerance, or invalid drive or laser options.
  void Validate() const;
  // Takes seed, rates, start time, route speed and tolerance, robot and laser from the sim
  // process's configuration (config/sim.ini), the scene and the kidnapping too; the route and
  // stop condition keep their defaults.
  static SimSlamOptions FromSimConfig(const processes::SimConfig& sim);
};

struct SimulatedSlamLog {
  SlamLog log;                    // odometry increments and scans, in publishing order
  // The true pose at every odometry message (scans come at odometry times), in the frame of
  // the start pose: the frame dead reckoning and laser SLAM start in (eval::RunSlam starts both
  // at the origin), so errors can be read with or without alignment.
  Reference reference;
  nav::Pose2 start;               // the true start pose in the scene [m, rad]
  std::string scene_name;
  std::vector<Eigen::Vector2d> route;  // the route driven
  int laps = 0;                   // laps completed
  double duration_s = 0;          // simulated time
  double distance_m = 0;          // travelled by the robot (truth)
  int collisions = 0;             // physics steps blocked by an obstacle
  int64_t log_events = 0;         // messages written to options.log_path
};

// Runs the simulation. Throws std::runtime_error for a scene that cannot be loaded or has no
// route (and none is given), or an LCM log that cannot be written; std::invalid_argument for
// invalid options.
SimulatedSlamLog SimulateSlamLog(const SimSlamOptions& options);

// The errors of one estimator against the ground truth, at every scan.
struct TrajectoryErrors {
  nav::AteResult ate;          // no alignment: estimators and truth share the start pose
  nav::AteResult ate_aligned;  // after the best SE(2) alignment of the whole run (as eval-slam)
  nav::RpeResult rpe;          // over rpe_delta_m of travel
};

struct SimSlamEvaluation {
  SlamRun run;                    // dead reckoning and laser SLAM at every scan (eval::RunSlam)
  std::vector<nav::Pose2> truth;  // the true pose at every scan, start frame
  TrajectoryErrors laser_slam, dead_reckoning;
};

// Runs dead reckoning and laser SLAM over the simulated log (eval::RunSlam) and measures both
// against the ground truth. Throws std::runtime_error if fewer than 2 scans have a true pose.
SimSlamEvaluation EvaluateSimulatedSlam(const SimulatedSlamLog& sim, const nav::LaserSlamOptions& options,
                                        double rpe_delta_m = 1.0);

}  // namespace snapnav::eval
