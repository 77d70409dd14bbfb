#pragma once
// A laser scan at a known pose, as the occupancy grid (occupancy_grid.hpp) takes it; its own header
// so that glue converts messages to it without MRPT's headers.
#include <cstdint>
#include <vector>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// One scan as the laser measured it, and the robot's pose when it did.
struct GridScan {
  int64_t utime = 0;
  Pose2 robot_pose;            // in the map frame
  Pose2 sensor_on_robot;       // the laser's mount on the robot
  float angle_min_rad = 0;     // bearing of the first beam in the sensor frame
  float angle_increment_rad = 0;
  float range_min_m = 0, range_max_m = 0;  // readings outside [min, max) are no return
  std::vector<float> ranges_m;
};

}  // namespace snapnav::nav
