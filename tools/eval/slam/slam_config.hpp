#pragma once
// The laser SLAM options the evaluations and benchmarks run: those of a laser-slam config file
// (by default the shipped config/laser_slam.ini), read by the function the laser-slam process
// reads it with (processes::LaserSlamConfig::FromIni), with command-line overrides of single
// [laser_slam] keys. So eval-slam, slam-sim-eval and bench-slam measure what ships.
#include <iosfwd>
#include <string>
#include <vector>

#include "snapnav/nav/slam/graph_slam.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"

namespace snapnav::eval {

constexpr const char* kShippedLaserSlamConfig = SNAPNAV_CONFIG_DIR "/laser_slam.ini";

struct LaserSlamConfigChoice {
  std::string path = kShippedLaserSlamConfig;  // a laser-slam config ([channels], [laser_slam])
  std::vector<std::string> overrides;          // "key=value" of [laser_slam], applied in order
};

// The [laser_slam] options of the file after the overrides. A missing or unknown key, a bad
// value, or an override of a key the file does not have is a glue::ConfigError naming the file
// (or the override).
nav::LaserSlamOptions LoadLaserSlamOptions(const LaserSlamConfigChoice& choice);

// The back end of the same file and overrides (`backend`, the graph_* keys): whether it is the graph
// back end, and the graph back end's options (read whatever the backend, as laser-slam reads them).
struct SlamBackendChoice {
  bool graph = false;
  nav::GraphSlamOptions options;
};
SlamBackendChoice LoadSlamBackend(const LaserSlamConfigChoice& choice);

// "--set" overrides from flags given as values: `key` = `value` for each non-empty value.
void AddOverride(LaserSlamConfigChoice* choice, const std::string& key, const std::string& value);

// The options as the config file writes them ([laser_slam] keys, one per line, each prefixed with
// `indent`).
void PrintLaserSlamOptions(std::ostream& out, const nav::LaserSlamOptions& options, const std::string& indent = "  ");


}  // namespace snapnav::eval
