#include "snapnav/glue/conversions.hpp"

namespace snapnav::glue {

nav::Pose2 OdometryDelta(const odometry_t& msg) { return {msg.delta_x_m, msg.delta_y_m, msg.delta_theta_rad}; }

nav::Pose2 OdometryPose(const odometry_t& msg) { return {msg.x_m, msg.y_m, msg.theta_rad}; }

pose_t ToPoseMsg(int64_t utime, const std::string& estimator, const std::string& frame, const nav::Pose2& pose,
                 const Eigen::Matrix3d& covariance) {
  pose_t msg;
  msg.utime = utime;
  msg.estimator = estimator;
  msg.frame = frame;
  msg.x_m = pose.x_m;
  msg.y_m = pose.y_m;
  msg.theta_rad = pose.theta_rad;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) msg.covariance[3 * r + c] = covariance(r, c);
  }
  return msg;
}

nav::Pose2 FromPoseMsg(const pose_t& msg) { return {msg.x_m, msg.y_m, msg.theta_rad}; }

Eigen::Matrix3d CovarianceOf(const pose_t& msg) {
  Eigen::Matrix3d cov;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cov(r, c) = msg.covariance[3 * r + c];
  }
  return cov;
}

}  // namespace snapnav::glue
