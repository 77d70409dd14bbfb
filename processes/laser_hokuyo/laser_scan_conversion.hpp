#pragma once
// MRPT CObservation2DRangeScan -> laser_scan_t.

#include <cstdint>
#include <string>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/system/datetime.h>

#include "snapnav/laser_scan_t.hpp"

namespace snapnav::processes {

struct LaserScanOptions {
  std::string sensor_name = "hokuyo";
  // Sensor mounting on the robot (x forward, y left, counter-clockwise heading).
  double sensor_x_m = 0;
  double sensor_y_m = 0;
  double sensor_theta_rad = 0;
  // Readings below this are invalid (CHokuyoURG marks readings under 20 mm invalid).
  double range_min_m = 0.02;
  // 0: publish every beam; otherwise only the beams within +-fov_deg/2 of straight ahead.
  double fov_deg = 0;

  void Validate() const;  // throws std::invalid_argument
};

// Microseconds since the Unix epoch of an MRPT timestamp; throws std::invalid_argument
// for INVALID_TIMESTAMP.
int64_t MrptTimestampToUtime(mrpt::system::TTimeStamp timestamp);

// Converts a scan:
//   utime        from scan.timestamp
//   beams        in counter-clockwise order (a clockwise MRPT scan is reversed), beam i at
//                angle_min_rad + i * angle_increment_rad, following MRPT's geometry:
//                beams spread evenly over `aperture`, the first and last at +-aperture/2
//   range_max_m  scan.maxRange; invalid (or non-finite) readings are published as range_max_m
//   range_min_m, sensor pose and name from `options` (the scan's sensorPose is not used)
//   intensities  copied when the scan has them
// Throws std::invalid_argument for fewer than 2 beams (after the fov_deg crop), a
// non-positive aperture or maxRange, or an invalid timestamp.
laser_scan_t RangeScanToLaserScan(const mrpt::obs::CObservation2DRangeScan& scan, const LaserScanOptions& options);

}  // namespace snapnav::processes
