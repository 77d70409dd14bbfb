#pragma once
// Planar rigid-body poses (x, y, theta) and their composition.

#include <Eigen/Core>

namespace snapnav::nav {

// Wraps an angle to [-pi, pi).
double WrapAngle(double angle_rad);

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;

  // this (+) delta: applies `delta`, expressed in this pose's frame.
  Pose2 Compose(const Pose2& delta) const;
  // The pose that undoes this one: Compose(Inverse()) is the identity.
  Pose2 Inverse() const;
  // `other` expressed in this pose's frame: Compose(Between(other)) == other.
  Pose2 Between(const Pose2& other) const;
  // A point given in this pose's frame, in the parent frame.
  Eigen::Vector2d Transform(const Eigen::Vector2d& point) const;
};

// `v` rotated by the angle whose cosine and sine are c and s (computed once for many points).
inline Eigen::Vector2d RotateBy(double c, double s, const Eigen::Vector2d& v) {
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

}  // namespace snapnav::nav
