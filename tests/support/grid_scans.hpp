#pragma once
// The simulated laser's scan at `pose`, as the occupancy grid takes it (tests of map export and of
// localization in a saved map).
#include "snapnav/nav/slam/grid_scan.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::test_support {

inline nav::GridScan SimGridScan(nav::sim::World& world, const nav::sim::LaserOptions& laser, const nav::Pose2& pose) {
  world.SetTruePose(pose);
  nav::GridScan g;
  g.robot_pose = pose;
  g.sensor_on_robot = {laser.mount_x_m, 0, 0};
  g.angle_min_rad = static_cast<float>(laser.angle_min_rad);
  g.angle_increment_rad = static_cast<float>(laser.AngleIncrement());
  g.range_min_m = static_cast<float>(laser.range_min_m);
  g.range_max_m = static_cast<float>(laser.range_max_m);
  g.ranges_m = world.Scan();
  return g;
}

}  // namespace snapnav::test_support
