// The demo deployment's config variants (config/deploy/demo/*.ini) parse with their programs'
// parsers, like every config in config/ (tests/glue/config_files_test.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>
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

TEST(DemoConfigs, PlaceCellExplorationKeepsAViewEvery20CmAtLaserSlamsPose) {
  // The demo explores as a robot does: the drive's views every 0.2 m (the grid's spacing), each a
  // cell, at laser SLAM's pose; never at the ground truth.
  const auto c = processes::PlaceCellsConfig::FromIni(glue::IniFile::Load(kDemoDir / "placecells_explore.ini"), "");
  EXPECT_EQ(c.mode, processes::PlaceCellsMode::kExplore);
  EXPECT_EQ(c.min_interval_s, 0);
  EXPECT_DOUBLE_EQ(c.min_travel_m, 0.2);
  EXPECT_EQ(c.novelty_threshold, 0);
  EXPECT_EQ(c.explore_pose_channel, "POSE_LASER_SLAM");
}

TEST(DemoConfigs, TheTruePoseExplorationKeepsEveryGridView) {
  // The labelled upper bound: every grid view a cell at its true pose.
  const auto c =
      processes::PlaceCellsConfig::FromIni(glue::IniFile::Load(kDemoDir / "placecells_explore_truth.ini"), "");
  EXPECT_EQ(c.mode, processes::PlaceCellsMode::kExplore);
  EXPECT_EQ(c.min_interval_s, 0);
  EXPECT_EQ(c.min_travel_m, 0);
  EXPECT_EQ(c.explore_pose_channel, "POSE_GROUND_TRUTH");
}

TEST(DemoConfigs, PlaceCellLocalizationGivesGlobalFixes) {
  // One instance for the navigator and fused-slam: without the distance filter (config/fused_slam.ini).
  const auto c = processes::PlaceCellsConfig::FromIni(glue::IniFile::Load(kDemoDir / "placecells.ini"), "");
  EXPECT_EQ(c.mode, processes::PlaceCellsMode::kLocalize);
  EXPECT_FALSE(c.localizer.filter.enabled);
}

TEST(DemoConfigs, Navigator) {
  EXPECT_NO_THROW(processes::NavigatorConfig::FromIni(glue::IniFile::Load(kDemoDir / "navigator.ini"), ""));
}

TEST(DemoConfigs, EveryDemoIniIsKnown) {
  const std::set<std::string> known{"sim.ini", "placecells_explore.ini", "placecells_explore_truth.ini", "placecells.ini",
                                    "navigator.ini"};
  for (const auto& entry : std::filesystem::directory_iterator(kDemoDir)) {
    if (entry.path().extension() == ".ini") {
      EXPECT_TRUE(known.count(entry.path().filename().string())) << "untested config " << entry.path();
    }
  }
}

// Each variant is its base config with the keys whose line says `demo:` changed: the same sections
// and keys, and every other value the base's (so a change to the base cannot be missed here).
TEST(DemoConfigs, VariantsDifferFromTheirBaseOnlyInDemoKeys) {
  const std::filesystem::path base_dir = SNAPNAV_CONFIG_DIR;
  const std::vector<std::pair<std::string, std::string>> variants = {{"sim.ini", "sim.ini"},
                                                                     {"placecells_explore.ini", "placecells.ini"},
                                                                     {"placecells_explore_truth.ini", "placecells.ini"},
                                                                     {"placecells.ini", "placecells.ini"},
                                                                     {"navigator.ini", "navigator.ini"}};
  for (const auto& [variant, base] : variants) {
    const auto v = glue::IniFile::Load(kDemoDir / variant);
    const auto b = glue::IniFile::Load(base_dir / base);
    std::vector<std::string> lines;
    {
      std::ifstream in(kDemoDir / variant);
      for (std::string line; std::getline(in, line);) lines.push_back(line);
    }
    EXPECT_EQ(v.Sections(), b.Sections()) << variant;
    int demo_keys = 0;
    for (const auto& section : b.Sections()) {
      EXPECT_EQ(v.Keys(section), b.Keys(section)) << variant << " [" << section << "]";
      for (const auto& key : v.Keys(section)) {
        if (!b.Has(section, key)) continue;
        const int line = v.KeyLine(section, key);
        const bool demo = line >= 1 && line <= static_cast<int>(lines.size()) &&
                          lines[static_cast<size_t>(line - 1)].find("demo:") != std::string::npos;
        demo_keys += demo;
        if (!demo) {
          EXPECT_EQ(v.GetString(section, key), b.GetString(section, key))
              << variant << ":" << line << ": [" << section << "] " << key << " differs from " << base
              << " without a `demo:` note";
        }
      }
    }
    EXPECT_GT(demo_keys, 0) << variant << ": no key marked demo:";
  }
}

}  // namespace
}  // namespace snapnav
