#include "snapnav/glue/conversions.hpp"

#include <cmath>

namespace snapnav::glue {

nav::Pose2 OdometryDelta(const odometry_t& msg) { return {msg.delta_x_m, msg.delta_y_m, msg.delta_theta_rad}; }

odometry_t ToOdometryMsg(int64_t utime, const std::string& sensor_name, const nav::Pose2& cumulative,
                         const nav::Pose2& delta, double dt_s) {
  odometry_t o{};
  o.utime = utime;
  o.sensor_name = sensor_name;
  o.x_m = cumulative.x_m;
  o.y_m = cumulative.y_m;
  o.theta_rad = cumulative.theta_rad;
  o.delta_x_m = delta.x_m;
  o.delta_y_m = delta.y_m;
  o.delta_theta_rad = delta.theta_rad;
  o.delta_t_s = dt_s;
  o.linear_velocity_mps = dt_s > 0 ? std::hypot(delta.x_m, delta.y_m) / dt_s : 0;
  o.angular_velocity_radps = dt_s > 0 ? delta.theta_rad / dt_s : 0;
  return o;
}

nav::Pose2 OdometryPose(const odometry_t& msg) { return {msg.x_m, msg.y_m, msg.theta_rad}; }

point_map_t ToPointMapMsg(int64_t utime, const std::string& estimator, double resolution_m,
                          const std::vector<Eigen::Vector2d>& points) {
  point_map_t m{};
  m.utime = utime;
  m.estimator = estimator;
  m.resolution_m = static_cast<float>(resolution_m);
  m.npoints = static_cast<int32_t>(points.size());
  m.x_m.reserve(points.size());
  m.y_m.reserve(points.size());
  for (const auto& p : points) {
    m.x_m.push_back(static_cast<float>(p.x()));
    m.y_m.push_back(static_cast<float>(p.y()));
  }
  return m;
}

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

namespace snapnav::glue {

std::string OdometryStartProblem(const odometry_t& m) {
  if (!(std::isfinite(m.x_m) && std::isfinite(m.y_m) && std::isfinite(m.theta_rad))) {
    return "cumulative pose is not finite";
  }
  if (std::abs(m.x_m) > kMaxPositionM || std::abs(m.y_m) > kMaxPositionM) {
    return "cumulative position (" + std::to_string(m.x_m) + ", " + std::to_string(m.y_m) + ") m is beyond " +
           std::to_string(kMaxPositionM) + " m";
  }
  return "";
}

std::string OdometryProblem(const odometry_t& m, bool cumulative) {
  if (cumulative) {
    if (std::string problem = OdometryStartProblem(m); !problem.empty()) return problem;
  }
  if (!(std::isfinite(m.delta_x_m) && std::isfinite(m.delta_y_m) && std::isfinite(m.delta_theta_rad))) {
    return "increment is not finite";
  }
  if (std::abs(m.delta_x_m) > kMaxOdometryStepM || std::abs(m.delta_y_m) > kMaxOdometryStepM ||
      std::abs(m.delta_theta_rad) > kMaxOdometryStepRad) {
    return "increment (" + std::to_string(m.delta_x_m) + " m, " + std::to_string(m.delta_y_m) + " m, " +
           std::to_string(m.delta_theta_rad) + " rad) exceeds " + std::to_string(kMaxOdometryStepM) + " m or " +
           std::to_string(kMaxOdometryStepRad) + " rad";
  }
  return "";
}

}  // namespace snapnav::glue
