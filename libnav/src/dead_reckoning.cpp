#include "snapnav/nav/dead_reckoning.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace snapnav::nav {

void DeadReckoningOptions::Validate() const {
  const auto noise = [](double v, const char* name) {
    if (!(v >= 0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("dead reckoning: ") + name + " must be finite and non-negative");
    }
  };
  noise(translation_noise_m_per_m, "translation_noise_m_per_m");
  noise(rotation_noise_rad_per_rad, "rotation_noise_rad_per_rad");
  noise(rotation_noise_rad_per_m, "rotation_noise_rad_per_m");
}

DeadReckoning::DeadReckoning(const DeadReckoningOptions& options, const Pose2& start)
    : options_(options), pose_(start) {
  options_.Validate();
}

Eigen::Matrix3d MotionCovariance(const DeadReckoningOptions& noise, const Pose2& from,
                                 const Eigen::Matrix3d& covariance, const Pose2& motion, double path_m,
                                 double turn_rad) {
  const double c = std::cos(from.theta_rad), s = std::sin(from.theta_rad);
  Eigen::Matrix3d jx = Eigen::Matrix3d::Identity();
  jx(0, 2) = -s * motion.x_m - c * motion.y_m;
  jx(1, 2) = c * motion.x_m - s * motion.y_m;
  Eigen::Matrix3d ju;
  ju << c, -s, 0, s, c, 0, 0, 0, 1;
  const double st = noise.translation_noise_m_per_m * path_m;
  const double sr = noise.rotation_noise_rad_per_rad * turn_rad + noise.rotation_noise_rad_per_m * path_m;
  const Eigen::Vector3d q(st * st, st * st, sr * sr);
  return jx * covariance * jx.transpose() + ju * q.asDiagonal() * ju.transpose();
}

void PredictWithOdometry(const DeadReckoningOptions& noise, const Pose2& delta, Pose2* pose,
                         Eigen::Matrix3d* covariance) {
  if (!std::isfinite(delta.x_m) || !std::isfinite(delta.y_m) || !std::isfinite(delta.theta_rad)) {
    throw std::invalid_argument("odometry increment is not finite");
  }
  *covariance = MotionCovariance(noise, *pose, *covariance, delta, std::hypot(delta.x_m, delta.y_m),
                                 std::abs(delta.theta_rad));
  *pose = pose->Compose(delta);
}

void DeadReckoning::AddOdometry(const Pose2& delta) {
  PredictWithOdometry(options_, delta, &pose_, &covariance_);
  distance_m_ += std::hypot(delta.x_m, delta.y_m);
}

}  // namespace snapnav::nav
