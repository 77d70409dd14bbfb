#pragma once
// laser-slam's back end choice (`[laser_slam] backend = ekf | graph`) and the graph back end's
// keys (`graph_*` in [laser_slam]; nav::GraphSlamOptions, docs/laser_slam.md). Angles in degrees
// in the file.
#include <iosfwd>
#include <optional>
#include <string>

#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/slam/graph_slam.hpp"

namespace snapnav::processes {

enum class SlamBackend {
  kEkf,    // the thesis' EKF with the robust front end (nav::LaserSlam)
  kGraph,  // that front end with keyframes, loop closure and MRPT's graph SLAM (nav::GraphSlam)
};
const char* SlamBackendName(SlamBackend b);
std::optional<SlamBackend> ParseSlamBackend(const std::string& name);

// The graph_* keys of `section`: every key required, invalid values are glue::ConfigError.
nav::GraphSlamOptions ReadGraphSlamOptions(const glue::IniFile& ini, const std::string& section);
// Those keys as ReadGraphSlamOptions reads them, one per line.
void PrintGraphSlamOptions(std::ostream& out, const nav::GraphSlamOptions& options);

}  // namespace snapnav::processes
