#pragma once
// laser-slam --mode localize's part of laser_slam.ini: [channels] localization_status and the
// [localize] section (nav::MapLocalizerOptions less the tracker's, which are [laser_slam]'s).
#include <iosfwd>
#include <string>

#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/slam/map_localizer.hpp"

namespace snapnav::processes {

struct LocalizeConfig {
  std::string status_channel;     // localization_status_t out
  nav::MapLocalizerOptions options;  // options.tracking is set from [laser_slam] by the caller

  // Every key required; bad values are glue::ConfigError naming the file.
  static LocalizeConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  // The [localize] keys (no header), as FromIni reads them.
  void Print(std::ostream& out) const;
};

}  // namespace snapnav::processes
