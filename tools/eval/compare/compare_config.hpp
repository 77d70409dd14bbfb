#pragma once
// The options of the SLAM comparison from the shipped configs (eval-compare and bench-compare):
// the simulator's camera and effects (config/sim.ini), laser-only SLAM's [laser_slam]
// (config/laser_slam.ini), fused SLAM's [laser_slam] and [fused_slam] (config/fused_slam.ini), and
// the place cells' view, localizer and vocabulary (config/placecells.ini), RatSLAM's [ratslam]
// (config/ratslam.ini).
#include <iosfwd>
#include <string>

#include "sim_node.hpp"
#include "slam_compare.hpp"

namespace snapnav::eval {

struct CompareConfigPaths {
  std::string sim = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string fused = SNAPNAV_CONFIG_DIR "/fused_slam.ini";
  std::string laser = SNAPNAV_CONFIG_DIR "/laser_slam.ini";
  std::string placecells = SNAPNAV_CONFIG_DIR "/placecells.ini";
  std::string ratslam = SNAPNAV_CONFIG_DIR "/ratslam.ini";
};

// Fills `options` (the rest keeps its values) and returns the simulator's config. Throws
// glue::ConfigError naming the file for a bad config.
processes::SimConfig LoadCompareConfigs(const CompareConfigPaths& paths, CompareOptions* options);

// One paragraph of the effective options, for the start-up print and the report.
void PrintCompareOptions(std::ostream& out, const CompareConfigPaths& paths, const CompareOptions& options);

}  // namespace snapnav::eval
