#pragma once
// laser-slam's back end choice (`[laser_slam] backend = ekf | graph`). The graph back end's keys
// (`graph_*` in [laser_slam]) are declared in glue/slam_options.hpp.
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

}  // namespace snapnav::processes
