#include "snapnav/nav/pose2.hpp"

#include <cmath>

namespace snapnav::nav {

double WrapAngle(double angle_rad) {
  double a = std::fmod(angle_rad + M_PI, 2.0 * M_PI);
  if (a < 0) a += 2.0 * M_PI;
  return a - M_PI;
}

Pose2 Pose2::Compose(const Pose2& delta) const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {x_m + c * delta.x_m - s * delta.y_m, y_m + s * delta.x_m + c * delta.y_m,
          WrapAngle(theta_rad + delta.theta_rad)};
}

Pose2 Pose2::Inverse() const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {-c * x_m - s * y_m, s * x_m - c * y_m, WrapAngle(-theta_rad)};
}

Pose2 Pose2::Between(const Pose2& other) const { return Inverse().Compose(other); }

Eigen::Vector2d Pose2::Transform(const Eigen::Vector2d& point) const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {x_m + c * point.x() - s * point.y(), y_m + s * point.x() + c * point.y()};
}

}  // namespace snapnav::nav
