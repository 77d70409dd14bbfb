#include "laser_scan_conversion.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <mrpt/core/Clock.h>

namespace snapnav::processes {

void LaserScanOptions::Validate() const {
  if (sensor_name.empty()) throw std::invalid_argument("sensor_name must not be empty");
  for (const auto& [v, name] : {std::pair<double, const char*>{sensor_x_m, "sensor_x_m"},
                                {sensor_y_m, "sensor_y_m"},
                                {sensor_theta_rad, "sensor_theta_rad"}}) {
    if (!std::isfinite(v)) {
      throw std::invalid_argument(std::string("the sensor pose's ") + name + " must be a finite number");
    }
  }
  if (!std::isfinite(range_min_m) || range_min_m < 0) throw std::invalid_argument("range_min_m must be >= 0");
  if (!std::isfinite(fov_deg) || fov_deg < 0 || fov_deg > 360) {
    throw std::invalid_argument("fov_deg must be in 0..360 (0: every beam), got " + std::to_string(fov_deg));
  }
}

int64_t MrptTimestampToUtime(mrpt::system::TTimeStamp timestamp) {
  if (timestamp == INVALID_TIMESTAMP) throw std::invalid_argument("scan has no timestamp");
  // MRPT counts 100 ns ticks from its own epoch; Clock::fromDouble(0) is the Unix epoch.
  const int64_t unix_epoch_ticks = mrpt::Clock::fromDouble(0.0).time_since_epoch().count();
  const int64_t ticks = timestamp.time_since_epoch().count() - unix_epoch_ticks;
  return ticks >= 0 ? ticks / 10 : -((-ticks + 9) / 10);  // floor to whole microseconds
}

laser_scan_t RangeScanToLaserScan(const mrpt::obs::CObservation2DRangeScan& scan, const LaserScanOptions& options) {
  options.Validate();
  const size_t n = scan.getScanSize();
  if (n < 2) throw std::invalid_argument("scan has " + std::to_string(n) + " beams; at least 2 are needed");
  if (!(scan.aperture > 0) || !std::isfinite(scan.aperture)) {
    throw std::invalid_argument("scan aperture must be positive, got " + std::to_string(scan.aperture));
  }
  if (!(scan.maxRange > 0) || !std::isfinite(scan.maxRange)) {
    throw std::invalid_argument("scan maxRange must be positive, got " + std::to_string(scan.maxRange));
  }
  laser_scan_t msg{};
  msg.utime = MrptTimestampToUtime(scan.timestamp);
  msg.sensor_name = options.sensor_name;
  msg.sensor_x_m = static_cast<float>(options.sensor_x_m);
  msg.sensor_y_m = static_cast<float>(options.sensor_y_m);
  msg.sensor_theta_rad = static_cast<float>(options.sensor_theta_rad);
  msg.time_increment_s = 0;  // the driver does not report the time between beams
  msg.range_min_m = static_cast<float>(options.range_min_m);
  msg.range_max_m = scan.maxRange;

  // MRPT: beam k at -aperture/2 + k * aperture/(n-1), mirrored when scanning clockwise.
  const double increment = static_cast<double>(scan.aperture) / static_cast<double>(n - 1);
  const double first_angle = -0.5 * static_cast<double>(scan.aperture);
  auto mrpt_index = [&](size_t i) { return scan.rightToLeft ? i : n - 1 - i; };  // counter-clockwise order

  // Beams kept: all, or those within +-fov/2 (slack of a thousandth of a beam: aperture is a float).
  size_t begin = 0, end = n;
  if (options.fov_deg > 0) {
    const double half_fov = 0.5 * options.fov_deg * M_PI / 180.0 + 1e-3 * increment;
    while (begin < n && first_angle + begin * increment < -half_fov) ++begin;
    while (end > begin && first_angle + (end - 1) * increment > half_fov) --end;
    if (end - begin < 2) {
      throw std::invalid_argument("fov_deg " + std::to_string(options.fov_deg) + " keeps " +
                                  std::to_string(end - begin) + " beams; at least 2 are needed");
    }
  }
  msg.angle_min_rad = static_cast<float>(first_angle + begin * increment);
  msg.angle_increment_rad = static_cast<float>(increment);
  msg.nranges = static_cast<int32_t>(end - begin);
  msg.ranges_m.reserve(end - begin);
  const bool has_intensity = scan.hasIntensity();
  for (size_t i = begin; i < end; ++i) {
    const size_t k = mrpt_index(i);
    const float r = scan.getScanRange(k);
    msg.ranges_m.push_back(scan.getScanRangeValidity(k) && std::isfinite(r) ? r : msg.range_max_m);
    if (has_intensity) msg.intensities.push_back(static_cast<float>(scan.getScanIntensity(k)));
  }
  msg.nintensities = static_cast<int32_t>(msg.intensities.size());
  return msg;
}

}  // namespace snapnav::processes
