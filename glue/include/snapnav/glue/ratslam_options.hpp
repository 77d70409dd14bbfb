#pragma once
// RatSLAM's options declared once (options.hpp): the [ratslam] section, OpenRatSLAM's keys
// (unit-suffixed where the value has a unit; config/ratslam.ini, docs/ratslam.md).
#include <iosfwd>
#include <string>

#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"

namespace snapnav::glue {

const OptionTable<nav::RatSlamOptions>& RatSlamOptionTable();
// Every key required; invalid values are ConfigError naming file, line, section and key.
nav::RatSlamOptions ReadRatSlamOptions(const IniFile& ini, const std::string& section = "ratslam");
// The section ReadRatSlamOptions reads back (header line included).
void PrintRatSlamOptions(std::ostream& out, const nav::RatSlamOptions& options, const std::string& section = "ratslam");

}  // namespace snapnav::glue
