#pragma once
// The simulated robot in its scene: differential-drive motion with control
// error, wheel odometry with noise, a planar laser rangefinder, and moving
// people. Time is a parameter (sim time), randomness comes from one seeded engine.

#include <random>
#include <string>
#include <vector>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::nav::sim {

struct DriveOptions {
  double max_linear_mps = 0.5;
  double max_angular_radps = 1.5;
  double heading_drift_deg_per_m = 0.3;  // control error: heading change per metre forward (thesis 5.3.1)
  double linear_noise_frac = 0.01;       // std. dev. of true speed around the command, fraction of it
  double angular_noise_radps = 0.005;    // std. dev. of true turn rate around the command
  double odometry_linear_noise_frac = 0.01;   // wheel odometry: std. dev. per step, fraction of the motion
  double odometry_angular_noise_frac = 0.01;  // wheel odometry: std. dev. per step, fraction of the turn
  double robot_radius_m = 0.2;           // for collisions
  double obstacle_min_height_m = 0.05;   // lower things are driven over
  // People block the robot (and it them). false: they occlude the camera and the laser but the
  // robot drives on (a robot without obstacle avoidance and people who wait for it deadlock);
  // they still do not walk into it.
  bool people_block_robot = true;
  void Validate() const;
};

// A real laser's faults (the `realistic` laser preset; the clean laser has none).
struct LaserFaults {
  bool enabled = false;
  double range_scale = 1.006;             // every return is range_scale x the true range + range_bias_m
  double range_bias_m = 0.012;
  double mixed_pixel_jump_m = 0.25;       // at a depth edge deeper than this, the beam on the far side...
  double mixed_pixel_probability = 0.5;   // ...returns a range between the two surfaces with this probability
  double dark_grey = 45;                  // surfaces darker than this (their texture's mean grey) absorb...
  double dark_dropout_probability = 0.6;  // ...the beam: no return, with this probability
  double dropout_probability = 0.003;     // a beam without a return anywhere
  bool legs = true;                       // people are two legs at the scan height, not one body
  double leg_radius_m = 0.06;
  double leg_spacing_m = 0.24;            // between the legs' centres
  void Validate() const;                  // throws std::invalid_argument
};
// "clean" (no faults) or "realistic" (the values above). Throws std::invalid_argument on another name.
LaserFaults LaserFaultsPreset(const std::string& name);

struct LaserOptions {
  int beams = 681;                     // Hokuyo URG-04LX
  double angle_min_rad = -2.0943951;   // -120 deg
  double angle_max_rad = 2.0943951;    // +120 deg
  double range_min_m = 0.02;
  double range_max_m = 5.6;
  double range_noise_m = 0.01;         // std. dev. of Gaussian range noise
  double mount_height_m = 0.3;         // scan plane height: lower objects are not seen
  double mount_x_m = 0.1;              // position on the robot, forward
  LaserFaults faults;                  // clean by default
  void Validate() const;
  double AngleIncrement() const { return (angle_max_rad - angle_min_rad) / (beams - 1); }
};

// A kidnapping: at simulated time at_s the robot is carried to `to` (odometry does not see it).
struct KidnapOptions {
  double at_s = 0;  // simulated time of the kidnapping [s]; <= 0: none
  Pose2 to;         // where the robot is put [m, rad]
  bool enabled() const { return at_s > 0; }
  void Validate() const;  // throws std::invalid_argument on a non-finite time or pose
};

// Odometry increment measured by the wheels since the previous reading.
struct OdometryReading {
  Pose2 delta;        // in the robot frame of the previous reading
  Pose2 cumulative;   // integrated odometry pose
  double dt_s = 0;
};

class World {
 public:
  World(const Scene& scene, const DriveOptions& drive, const LaserOptions& laser, uint64_t seed);

  // Advances the simulation by dt_s with the commanded velocities (clamped to the limits).
  void Step(double linear_mps, double angular_radps, double dt_s);
  // Teleports the robot (kidnapping); odometry does not see it.
  void SetTruePose(const Pose2& pose) { true_pose_ = pose; }

  const Pose2& true_pose() const { return true_pose_; }
  double time_s() const { return time_s_; }
  const std::vector<Cylinder>& people() const { return people_; }
  int collisions() const { return collisions_; }
  double distance_m() const { return distance_m_; }

  // Wheel odometry accumulated since the previous call.
  OdometryReading TakeOdometry();
  // One laser sweep from the current true pose (ranges in metres; range_max_m where nothing is hit).
  std::vector<float> Scan();

  std::mt19937_64& rng() { return rng_; }

  // Schedules a kidnapping: the first Step at or after kidnap.at_s starts by carrying the robot
  // to kidnap.to (odometry does not see it). Throws std::invalid_argument for invalid options or
  // a destination where the robot does not fit (closer than its radius to an obstacle).
  void SetKidnap(const KidnapOptions& kidnap);
  bool kidnapped() const { return kidnapped_; }  // the scheduled kidnapping has happened
  double kidnapped_at_s() const { return kidnapped_at_s_; }

 private:
  void MovePeople(double dt_s);

  const Scene& scene_;
  DriveOptions drive_;
  LaserOptions laser_;
  std::mt19937_64 rng_;
  Pose2 true_pose_;
  Pose2 odom_pose_;
  Pose2 odom_at_last_take_;
  double time_s_ = 0;
  double time_at_last_take_ = 0;
  double distance_m_ = 0;
  int collisions_ = 0;
  std::vector<Cylinder> people_;
  std::vector<Eigen::Vector2d> people_goals_;
  std::vector<double> texture_grey_;  // mean grey of each scene texture (the laser's dark surfaces)
  KidnapOptions kidnap_;
  bool kidnapped_ = false;
  double kidnapped_at_s_ = 0;
};

// Steers towards the next waypoint of a route (pure pursuit on the true pose):
// the simulator's scripted driver. Returns the (linear, angular) command.
class RouteDriver {
 public:
  RouteDriver(std::vector<Eigen::Vector2d> route, double speed_mps, double tolerance_m, bool loop);
  Eigen::Vector2d Command(const Pose2& pose);
  bool finished() const { return finished_; }
  int laps() const { return laps_; }
  size_t next_index() const { return next_; }
  // After the robot was carried off (a kidnapping): heads for the nearest waypoint ahead of
  // `pose` (within 90 degrees of its heading; the nearest of all if none is) and goes on with the
  // route from there. Laps keep counting.
  void Restart(const Pose2& pose);

 private:
  std::vector<Eigen::Vector2d> route_;
  double speed_mps_;
  double tolerance_m_;
  bool loop_;
  size_t next_ = 0;
  int laps_ = 0;
  bool finished_ = false;
};

}  // namespace snapnav::nav::sim
