// Every shipped config file parses with its program's parser: a broken config fails CI.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "dead_reckoning_node.hpp"
#include "fused_slam_node.hpp"
#include "laser_slam_node.hpp"
#include "snapnav/glue/ini.hpp"
#include "support/config_errors.hpp"

namespace snapnav {
namespace {

const std::filesystem::path kConfigDir = SNAPNAV_CONFIG_DIR;

TEST(ConfigFiles, DeadReckoning) {
  EXPECT_NO_THROW(processes::DeadReckoningConfig::FromIni(glue::IniFile::Load(kConfigDir / "dead_reckoning.ini"), ""));
}

TEST(ConfigFiles, BusCheck) {
  const auto ini = glue::IniFile::Load(kConfigDir / "bus_check.ini");
  for (const char* key : {"probe", "ping", "pong", "soak_frame", "soak_scan"}) EXPECT_FALSE(ini.GetString("channels", key).empty());
  EXPECT_NO_THROW(ini.CheckAllUsed());
}

TEST(ConfigFiles, FusedSlam) {
  const auto c = processes::FusedSlamConfig::FromIni(glue::IniFile::Load(kConfigDir / "fused_slam.ini"), "");
  EXPECT_EQ(c.pose_channel, "POSE_EKF");
  EXPECT_EQ(c.visual_channel, "POSE_PLACE_CELLS");
}

// A value the options' check refuses names the file, the line, the section and the key (it said
// "dead reckoning noise parameters must be finite and non-negative", nothing else).
TEST(ConfigFiles, NegativeNoiseNamesFileLineAndKey) {
  const std::string path = kConfigDir / "dead_reckoning.ini";
  glue::IniFile ini = glue::IniFile::Load(path);
  ini.Set("dead_reckoning", "rotation_noise_rad_per_m", "-0.01", "test");
  try {
    processes::DeadReckoningConfig::FromIni(ini, "");
    FAIL() << "no error";
  } catch (const glue::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":" +
                                         std::to_string(ini.KeyLine("dead_reckoning", "rotation_noise_rad_per_m")) +
                                         ": [dead_reckoning] rotation_noise_rad_per_m = '-0.01': dead reckoning: "
                                         "rotation_noise_rad_per_m must be finite and non-negative");
  }
}

// Every number of these configs made negative or NaN: each error names its file, line and key.
TEST(ConfigFiles, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(
                kConfigDir / "dead_reckoning.ini",
                [](const glue::IniFile& ini) { processes::DeadReckoningConfig::FromIni(ini, ""); }),
            0);
  EXPECT_GT(test_support::ExpectBadNumbersNamed(
                kConfigDir / "fused_slam.ini",
                [](const glue::IniFile& ini) { processes::FusedSlamConfig::FromIni(ini, ""); }),
            0);
  EXPECT_GT(test_support::ExpectBadNumbersNamed(
                kConfigDir / "laser_slam.ini",
                [](const glue::IniFile& ini) { processes::LaserSlamConfig::FromIni(ini, ""); }),
            0);
}

// Every .ini under config/ is covered by a test above.
TEST(ConfigFiles, EveryShippedIniIsKnown) {
  // Configs with heavy dependencies are tested in their own test executables
  // (tests/drivers/): omni_camera.ini, laser_hokuyo.ini; (tests/homing/homing_node_test.cpp): homing.ini,
  // landmarks.ini.
  // laser_slam.ini: tests/slam/laser_slam_node_test.cpp; placecells.ini: tests/placecells/place_cells_glue_test.cpp;
  // navigator.ini: tests/navigator/; viewer.ini: tests/viewer/viewer_test.cpp; ratslam.ini:
  // tests/ratslam/ratslam_node_test.cpp; slam_suite.ini, slam_suite_heldout.ini, slam_suite_sparse.ini,
  // slam_suite_unseen.ini (eval-slam --suite):
  // tests/eval/slam_suite_file_test.cpp. Deployment files (config/deploy/*.deploy) and the demo's
  // config variants (config/deploy/demo/*.ini): tests/launch/.
  const std::set<std::string> known{"dead_reckoning.ini", "bus_check.ini", "sim.ini", "omni_camera.ini",
                                    "laser_hokuyo.ini", "homing.ini", "laser_slam.ini", "landmarks.ini",
                                    "placecells.ini", "navigator.ini", "viewer.ini", "ratslam.ini", "fused_slam.ini",
                                    "slam_suite.ini", "slam_suite_heldout.ini", "slam_suite_sparse.ini",
                                    "slam_suite_unseen.ini"};
  for (const auto& entry : std::filesystem::directory_iterator(kConfigDir)) {
    if (entry.path().extension() == ".ini") {
      EXPECT_TRUE(known.count(entry.path().filename().string())) << "untested config " << entry.path();
    }
  }
}

}  // namespace
}  // namespace snapnav
