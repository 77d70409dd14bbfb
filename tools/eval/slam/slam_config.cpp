#include "slam_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ostream>
#include <sstream>

#include "laser_slam_node.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/slam_options.hpp"

namespace snapnav::eval {

namespace {

processes::LaserSlamConfig LoadConfig(const LaserSlamConfigChoice& choice) {
  glue::IniFile ini = glue::IniFile::Load(choice.path);
  for (const std::string& o : choice.overrides) {
    const size_t eq = o.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw glue::ConfigError("override '" + o + "': expected KEY=VALUE (a key of [laser_slam] in " + choice.path +
                              ")");
    }
    const auto trim = [](std::string s) {
      const size_t b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
      return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    };
    ini.Set("laser_slam", trim(o.substr(0, eq)), trim(o.substr(eq + 1)), "override " + o);
  }
  return processes::LaserSlamConfig::FromIni(ini, "");
}

}  // namespace

nav::LaserSlamOptions LoadLaserSlamOptions(const LaserSlamConfigChoice& choice) { return LoadConfig(choice).options; }

SlamBackendChoice LoadSlamBackend(const LaserSlamConfigChoice& choice) {
  const processes::LaserSlamConfig c = LoadConfig(choice);
  SlamBackendChoice b;
  b.graph = c.backend == processes::SlamBackend::kGraph;
  b.options = c.graph;
  return b;
}

void AddOverride(LaserSlamConfigChoice* choice, const std::string& key, const std::string& value) {
  if (!value.empty()) choice->overrides.push_back(key + "=" + value);
}

void PrintLaserSlamOptions(std::ostream& out, const nav::LaserSlamOptions& options, const std::string& indent) {
  std::ostringstream s;
  glue::PrintLaserSlamOptions(s, options);
  std::istringstream lines(s.str());
  std::string line;
  while (std::getline(lines, line)) out << indent << line << "\n";
}

}  // namespace snapnav::eval
