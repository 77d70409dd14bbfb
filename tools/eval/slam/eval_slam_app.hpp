#pragma once
// eval-slam (./snapnav eval slam) as an app: dead reckoning and laser SLAM over an LCM log against a
// reference, MRPT's icp-slam beside it (--icp-slam), the sensitivity sweep (--sweep) and the real-data
// suite (--suite, slam_suite.hpp).
#include <string>
#include <vector>

#include "icp_slam.hpp"
#include "slam_config.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"

namespace snapnav::eval {

class EvalSlamApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // The suite (--suite) or one log: 0, 2 when a suite run misses its bound, 3 when the log is damaged.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string log_path, reference_path, out_dir, icp_input;
  nav::LaserSlamOptions options;
  IcpSlamOptions icp_options;
  LaserSlamConfigChoice config;
  std::vector<std::string> sets;
  std::string match_distance, icp_iterations, map_resolution, add_distance, scan_step;
  bool sweep = false;
  std::string suite_path;
  std::vector<std::string> only;
};

}  // namespace snapnav::eval
