#pragma once
// The laser SLAM options, declared once (options.hpp): nav::LaserSlamOptions, the keys of
// [laser_slam] in laser_slam.ini and fused_slam.ini (the EKF and its robust front end), and
// nav::GraphSlamOptions, the graph_* keys of laser_slam.ini's [laser_slam] (the pose-graph back
// end). Angles in degrees in the file. docs/laser_slam.md explains each key.
#include <iosfwd>
#include <string>

#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/nav/slam/graph_slam.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"

namespace snapnav::glue {

const OptionTable<nav::LaserSlamOptions>& LaserSlamOptionTable();
const OptionTable<nav::GraphSlamOptions>& GraphSlamOptionTable();

// Every key of `section` required; unknown names and invalid values are ConfigError naming file,
// line, section and key.
nav::LaserSlamOptions ReadLaserSlamOptions(const IniFile& ini, const std::string& section);
nav::GraphSlamOptions ReadGraphSlamOptions(const IniFile& ini, const std::string& section);
// Those keys as they are read, one "key = value" per line (no section header).
void PrintLaserSlamOptions(std::ostream& out, const nav::LaserSlamOptions& options);
void PrintGraphSlamOptions(std::ostream& out, const nav::GraphSlamOptions& options);

}  // namespace snapnav::glue
