#pragma once
// Checks of a laser_scan_t before libnav sees it, shared by the processes that take scans
// (laser-slam, fused-slam): a malformed scan is counted with its reason, never a crash.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snapnav/laser_scan_t.hpp"

namespace snapnav::glue {

// Scans with more beams than this are rejected as garbage (real scanners have a few thousand).
inline constexpr size_t kMaxLaserBeams = 100000;
// Scans whose range_max_m exceeds this are rejected as garbage [m].
inline constexpr double kMaxLaserRangeM = 10000.0;

struct ScanProblem {
  std::string reason;  // "no ranges", "too many beams", "bad angles", "bad range limits", "bad sensor pose"
  std::string detail;  // the values at fault
};
// The first problem of a malformed scan, or nullopt when libnav can take it. (ranges_m.size() ==
// nranges after decoding; the intensities are not used, so their count does not matter.)
std::optional<ScanProblem> CheckLaserScan(const laser_scan_t& msg);
// The valid points of a checked scan in the robot frame (nav::ScanToPoints with the message's
// angles, range limits and sensor pose).
std::vector<Eigen::Vector2d> LaserScanPoints(const laser_scan_t& msg);

}  // namespace snapnav::glue
