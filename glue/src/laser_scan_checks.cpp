#include "snapnav/glue/laser_scan_checks.hpp"

#include <cmath>

#include "snapnav/nav/slam/laser_slam.hpp"

namespace snapnav::glue {
namespace {

bool Finite(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }

}  // namespace

std::optional<ScanProblem> CheckLaserScan(const laser_scan_t& msg) {
  if (msg.ranges_m.empty()) return ScanProblem{"no ranges", "scan has 0 beams"};
  if (msg.ranges_m.size() > kMaxLaserBeams) {
    return ScanProblem{"too many beams", std::to_string(msg.ranges_m.size()) + " beams (at most " +
                                             std::to_string(kMaxLaserBeams) + ")"};
  }
  if (!std::isfinite(msg.angle_min_rad) || !std::isfinite(msg.angle_increment_rad) || msg.angle_increment_rad == 0) {
    return ScanProblem{"bad angles", "angle_min_rad " + std::to_string(msg.angle_min_rad) + ", angle_increment_rad " +
                                         std::to_string(msg.angle_increment_rad) + " (finite, increment != 0)"};
  }
  // NaN fails these tests too. A bound on range_max_m keeps every point's map cell an integer.
  if (!(msg.range_min_m >= 0) || !(msg.range_max_m > msg.range_min_m) || !(msg.range_max_m <= kMaxLaserRangeM)) {
    return ScanProblem{"bad range limits", "range_min_m " + std::to_string(msg.range_min_m) + ", range_max_m " +
                                               std::to_string(msg.range_max_m) + " (0 <= min < max <= " +
                                               std::to_string(kMaxLaserRangeM) + ")"};
  }
  // The mounting is on the robot: within kMaxLaserRangeM of its centre, like every point (larger
  // coordinates overflow the map's integer cells).
  if (!Finite(msg.sensor_x_m, msg.sensor_y_m, msg.sensor_theta_rad) || std::abs(msg.sensor_x_m) > kMaxLaserRangeM ||
      std::abs(msg.sensor_y_m) > kMaxLaserRangeM || std::abs(msg.sensor_theta_rad) > 100) {
    return ScanProblem{"bad sensor pose", "sensor (" + std::to_string(msg.sensor_x_m) + " m, " +
                                              std::to_string(msg.sensor_y_m) + " m, " +
                                              std::to_string(msg.sensor_theta_rad) + " rad): finite, within " +
                                              std::to_string(kMaxLaserRangeM) + " m and 100 rad"};
  }
  return std::nullopt;
}

std::vector<Eigen::Vector2d> LaserScanPoints(const laser_scan_t& msg) {
  return nav::ScanToPoints(msg.ranges_m, msg.angle_min_rad, msg.angle_increment_rad, msg.range_min_m, msg.range_max_m,
                           {msg.sensor_x_m, msg.sensor_y_m, msg.sensor_theta_rad});
}

}  // namespace snapnav::glue
