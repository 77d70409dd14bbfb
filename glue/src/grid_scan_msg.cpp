#include "snapnav/glue/grid_scan_msg.hpp"

namespace snapnav::glue {

nav::GridScan GridScanOf(const laser_scan_t& msg, const nav::Pose2& robot_pose) {
  nav::GridScan g;
  g.utime = msg.utime;
  g.robot_pose = robot_pose;
  g.sensor_on_robot = {msg.sensor_x_m, msg.sensor_y_m, msg.sensor_theta_rad};
  g.angle_min_rad = msg.angle_min_rad;
  g.angle_increment_rad = msg.angle_increment_rad;
  g.range_min_m = msg.range_min_m;
  g.range_max_m = msg.range_max_m;
  g.ranges_m = msg.ranges_m;
  return g;
}

}  // namespace snapnav::glue
