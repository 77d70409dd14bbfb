// The demo deployment's config variants (config/deploy/demo/*.ini) parse with their programs'
// parsers, like every config in config/ (tests/config_files_test.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "navigator_node.hpp"
#include "placecells_node.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav {
namespace {

const std::filesystem::path kDemoDir = std::filesystem::path(SNAPNAV_CONFIG_DIR) / "deploy" / "demo";

TEST(DemoConfigs, SimDrivesByCommandsInRealTime) {
  const auto c = processes::SimConfig::FromIni(glue::IniFile::Load(kDemoDir / "sim.ini"), "");
  EXPECT_EQ(c.drive, "commands");
  EXPECT_TRUE(c.realtime);
}

TEST(DemoConfigs, PlaceCellExplorationKeepsEveryGridView) {
  const auto c = processes::PlaceCellsConfig::FromIni(glue::IniFile::Load(kDemoDir / "placecells_explore.ini"), "");
  EXPECT_EQ(c.mode, processes::PlaceCellsMode::kExplore);
  EXPECT_EQ(c.min_interval_s, 0);
  EXPECT_EQ(c.min_travel_m, 0);
}

TEST(DemoConfigs, Navigator) {
  EXPECT_NO_THROW(processes::NavigatorConfig::FromIni(glue::IniFile::Load(kDemoDir / "navigator.ini"), ""));
}

TEST(DemoConfigs, EveryDemoIniIsKnown) {
  const std::set<std::string> known{"sim.ini", "placecells_explore.ini", "navigator.ini"};
  for (const auto& entry : std::filesystem::directory_iterator(kDemoDir)) {
    if (entry.path().extension() == ".ini") {
      EXPECT_TRUE(known.count(entry.path().filename().string())) << "untested config " << entry.path();
    }
  }
}

}  // namespace
}  // namespace snapnav
