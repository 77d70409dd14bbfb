#pragma once
// laser_scan_t -> nav::GridScan: the scan as the occupancy grid takes it (its geometry and mount),
// at the robot's pose. One conversion for laser-slam's live grid and map-export's file.
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/grid_scan.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::glue {

nav::GridScan GridScanOf(const laser_scan_t& msg, const nav::Pose2& robot_pose = {});

}  // namespace snapnav::glue
