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

}  // namespace snapnav::eval
