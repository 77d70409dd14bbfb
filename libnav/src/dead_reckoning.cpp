#include "snapnav/nav/dead_reckoning.hpp"

#include <cmath>
#include <stdexcept>

namespace snapnav::nav {

void DeadReckoningOptions::Validate() const {
  if (!(translation_noise_m_per_m >= 0) || !(rotation_noise_rad_per_rad >= 0) || !(rotation_noise_rad_per_m >= 0)) {
    throw std::invalid_argument("dead reckoning noise parameters must be finite and non-negative");
  }
}

DeadReckoning::DeadReckoning(const DeadReckoningOptions& options, const Pose2& start)
    : options_(options), pose_(start) {
  options_.Validate();
}

void PredictWithOdometry(const DeadReckoningOptions& noise, const Pose2& delta, Pose2* pose,
                         Eigen::Matrix3d* covariance) {
  if (!std::isfinite(delta.x_m) || !std::isfinite(delta.y_m) || !std::isfinite(delta.theta_rad)) {
    throw std::invalid_argument("odometry increment is not finite");
  }
  const double c = std::cos(pose->theta_rad), s = std::sin(pose->theta_rad);
  Eigen::Matrix3d jx = Eigen::Matrix3d::Identity();
  jx(0, 2) = -s * delta.x_m - c * delta.y_m;
  jx(1, 2) = c * delta.x_m - s * delta.y_m;
  Eigen::Matrix3d ju;
  ju << c, -s, 0, s, c, 0, 0, 0, 1;
  const double d = std::hypot(delta.x_m, delta.y_m);
  const double st = noise.translation_noise_m_per_m * d;
  const double sr = noise.rotation_noise_rad_per_rad * std::abs(delta.theta_rad) + noise.rotation_noise_rad_per_m * d;
  const Eigen::Vector3d q(st * st, st * st, sr * sr);
  *covariance = jx * *covariance * jx.transpose() + ju * q.asDiagonal() * ju.transpose();
  *pose = pose->Compose(delta);
}

void DeadReckoning::AddOdometry(const Pose2& delta) {
  PredictWithOdometry(options_, delta, &pose_, &covariance_);
  distance_m_ += std::hypot(delta.x_m, delta.y_m);
}

}  // namespace snapnav::nav
