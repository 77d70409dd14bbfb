#pragma once
// What an evaluation takes from a --sim-config file. The evaluations render their views
// themselves (no bus, no robot clock, no laser), so they use part of the simulator's config: a
// file's value they do not use must not be silently ignored (issue 21: eval homing once dropped
// [effects] while eval localization applied them). RefuseUnusedSimKeys throws a ConfigError
// naming file, line and key for every value that differs from the shipped config/sim.ini in a
// key the evaluation does not use.

#include <set>
#include <string>
#include <utility>

#include "sim_node.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav::eval {

struct SimConfigUse {
  std::string tool;                                       // "eval homing"
  std::set<std::string> sections;                         // used whole: "mirror", "effects"
  std::set<std::pair<std::string, std::string>> keys;     // used one by one: {"camera", "preset"}
  bool Uses(const std::string& section, const std::string& key) const {
    return sections.count(section) || keys.count({section, key});
  }
};

// The sim-config keys eval homing and eval localization use (the camera that renders the views,
// its effects, the seed of its noise; localization also the robot's motion and odometry noise).
SimConfigUse HomingSimConfigUse();
SimConfigUse LocalizationSimConfigUse();

// Throws glue::ConfigError "FILE:LINE: [section] key = value: TOOL does not use it (...)" for the
// first key of `file` that `use` does not use and whose value differs from `shipped`'s (or that
// `shipped` does not have). The shipped file itself always passes.
void RefuseUnusedSimKeys(const glue::IniFile& file, const glue::IniFile& shipped, const SimConfigUse& use);

// An evaluation's --sim-config: the file read as the sim process reads it, then refused as above
// against the shipped config/sim.ini.
processes::SimConfig LoadSimConfigFor(const std::string& path, const SimConfigUse& use);

// --camera PRESET (clean | realistic) over the config's [camera] preset; "" leaves `camera` as it
// is. The preset's noise is seeded from the evaluation's --seed, so that one seed fixes every
// random part of a run. An unknown preset is a glue::FlagError that names --camera.
void ApplyCameraFlag(const std::string& preset, uint64_t seed, nav::sim::OmniCameraOptions* camera);

}  // namespace snapnav::eval
