#pragma once
// Dead reckoning: integrates odometry increments into a pose and propagates
// its covariance with a motion noise that grows with distance and rotation.

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct DeadReckoningOptions {
  double translation_noise_m_per_m = 0.05;      // std. dev. of translation per metre driven
  double rotation_noise_rad_per_rad = 0.05;     // std. dev. of heading per radian turned
  double rotation_noise_rad_per_m = 0.0052;     // heading drift per metre (thesis 5.3.1: 0.3 deg)
  void Validate() const;                        // throws std::invalid_argument
};

// One odometry increment (robot frame of `pose`) applied to a pose and its covariance: the
// prediction step of every odometry-driven filter here. Throws std::invalid_argument on a
// non-finite increment (nothing changes).
void PredictWithOdometry(const DeadReckoningOptions& noise, const Pose2& delta, Pose2* pose,
                         Eigen::Matrix3d* covariance);

// The covariance after a motion `motion` (robot frame of `from`) from a pose `from` of covariance
// `covariance`, the motion's noise from the distance driven and the angle turned along it (path_m,
// turn_rad: at least the motion's own; more where it went back and forth). One call for a whole
// interval treats its errors as one (the systematic errors of wheel odometry grow with the
// distance, not with the number of messages it came in); PredictWithOdometry is the case of one
// increment.
Eigen::Matrix3d MotionCovariance(const DeadReckoningOptions& noise, const Pose2& from,
                                 const Eigen::Matrix3d& covariance, const Pose2& motion, double path_m,
                                 double turn_rad);

class DeadReckoning {
 public:
  explicit DeadReckoning(const DeadReckoningOptions& options, const Pose2& start = {});

  // Applies one odometry increment given in the robot frame of the current pose.
  // Throws std::invalid_argument on a non-finite increment (the pose is unchanged).
  void AddOdometry(const Pose2& delta);

  const Pose2& pose() const { return pose_; }
  const Eigen::Matrix3d& covariance() const { return covariance_; }
  double distance_m() const { return distance_m_; }

 private:
  DeadReckoningOptions options_;
  Pose2 pose_;
  Eigen::Matrix3d covariance_ = Eigen::Matrix3d::Zero();
  double distance_m_ = 0.0;
};

}  // namespace snapnav::nav
