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

std::vector<std::string> LaserSlamOptionDifferences(const nav::LaserSlamOptions& a, const nav::LaserSlamOptions& b) {
  // Compare the printed keys: every option the config has, in its units.
  const auto parse = [](const nav::LaserSlamOptions& o) {
    std::ostringstream s;
    s.precision(17);
    glue::PrintLaserSlamOptions(s, o);
    std::vector<std::pair<std::string, std::string>> kv;
    std::istringstream lines(s.str());
    std::string line;
    while (std::getline(lines, line)) {
      const size_t eq = line.find(" = ");
      if (eq != std::string::npos) kv.emplace_back(line.substr(0, eq), line.substr(eq + 3));
    }
    return kv;
  };
  const auto ka = parse(a), kb = parse(b);
  std::vector<std::string> diff;
  for (size_t i = 0; i < ka.size() && i < kb.size(); ++i) {
    if (ka[i].second == kb[i].second) continue;
    char* end_a = nullptr;
    char* end_b = nullptr;
    const double va = std::strtod(ka[i].second.c_str(), &end_a), vb = std::strtod(kb[i].second.c_str(), &end_b);
    const bool numbers = *end_a == '\0' && *end_b == '\0';
    if (numbers && std::abs(va - vb) <= 1e-9 * std::max({1.0, std::abs(va), std::abs(vb)})) continue;
    diff.push_back(ka[i].first + ": " + ka[i].second + " vs " + kb[i].second);
  }
  return diff;
}

}  // namespace snapnav::eval
