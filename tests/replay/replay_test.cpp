// replay: a short simulated log through every process node in lockstep. The same log replayed
// twice gives byte-identical output logs (and place-cell memory files); the selection, the
// overrides and a damaged input behave as documented.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include <opencv2/core/utility.hpp>

#include "replay.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/log_reader.hpp"
#include "snapnav/glue/log_writer.hpp"

namespace snapnav::replay {
namespace {

namespace fs = std::filesystem;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class ReplayTest : public ::testing::Test {
 protected:
  // One simulated log for the suite: indoor13, the scripted route, every sensor, event times =
  // message times (as gridgen and the importers write them).
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("snapnav_replay_test_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    log_ = new std::string((*dir_ / "sim.lcmlog").string());
    glue::Bus bus("memq://");
    auto config = processes::SimConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), "");
    config.duration_s = 6.0;
    const auto scene = processes::LoadSceneFile(processes::SceneFilePath("indoor13"));
    glue::LogWriter writer(*log_);
    bus.SubscribeRaw(".*", [&](const void* d, size_t n) {
      const std::string payload(static_cast<const char*>(d), n);
      int64_t utime = 0;  // every snapnav type starts with int64_t utime after the fingerprint
      for (int i = 8; i < 16; ++i) utime = (utime << 8) | static_cast<uint8_t>(payload[i]);
      writer.WriteRaw(bus.current().channel, utime, payload);
    });
    processes::SimNode node(bus, config, scene);
    while (node.Step()) {
      while (bus.HandleOnce(0)) {
      }
    }
    writer.Close();
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete log_;
  }

  ReplayOptions Options(const std::string& out) const {
    ReplayOptions o;
    o.input = *log_;
    o.output = (*dir_ / out).string();
    o.config_dir = SNAPNAV_CONFIG_DIR;
    o.print_config = false;
    o.progress_interval_s = 0;
    return o;
  }
  // Every process, the home from the first frame, place cells exploring into `memory`.
  ReplayOptions ExploreOptions(const std::string& out, const std::string& memory) const {
    ReplayOptions o = Options(out);
    o.sets = {"homing:homing.home=first", "placecells:placecells.mode=explore",
              "placecells:placecells.memory_file=" + (*dir_ / memory).string()};
    return o;
  }

  static fs::path* dir_;
  static std::string* log_;
};
fs::path* ReplayTest::dir_ = nullptr;
std::string* ReplayTest::log_ = nullptr;

TEST_F(ReplayTest, SameLogGivesByteIdenticalOutputsThroughEveryProcess) {
  std::ostringstream log1, log2;
  const ReplayResult a = RunReplay(ExploreOptions("a.lcmlog", "a.mem"), log1);
  const ReplayResult b = RunReplay(ExploreOptions("b.lcmlog", "b.mem"), log2);
  if (std::getenv("SNAPNAV_TEST_VERBOSE")) std::cerr << log1.str();
  ASSERT_EQ(a.nodes.size(), ReplayRegistry().size()) << log1.str();
  EXPECT_TRUE(a.skipped.empty());
  EXPECT_GT(a.outputs, 100);
  EXPECT_EQ(a.outputs, b.outputs);
  EXPECT_EQ(a.damage_count, 0);
  // Every process published: poses, maps, landmark sets, homing vectors, place-cell matches, commands,
  // RatSLAM's pose and experience map, the fused pose, map and status.
  for (const char* ch : {"POSE_DEAD_RECKONING", "POSE_LASER_SLAM", "POINT_MAP", "LANDMARKS_SURF", "HOMING_VECTOR",
                         "PLACE_CELL_MATCH", "DRIVE_COMMAND", "NAVIGATOR_STATUS", "POSE_RATSLAM", "EXPERIENCE_MAP",
                         "POSE_EKF", "POINT_MAP_FUSED", "FUSED_SLAM_STATUS"}) {
    EXPECT_GT(a.outputs_by_channel.count(ch) ? a.outputs_by_channel.at(ch) : 0, 0) << ch << "\n" << log1.str();
  }
  const std::string out_a = ReadFile(*dir_ / "a.lcmlog"), out_b = ReadFile(*dir_ / "b.lcmlog");
  ASSERT_GT(out_a.size(), 10000u);
  EXPECT_TRUE(out_a == out_b) << "output logs differ";
  // OpenCV's parallel loops split the work by the number of threads: one thread, same bytes.
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  std::ostringstream log3;
  RunReplay(ExploreOptions("a1.lcmlog", "a1.mem"), log3);
  cv::setNumThreads(threads);
  EXPECT_TRUE(out_a == ReadFile(*dir_ / "a1.lcmlog")) << "output logs differ with one OpenCV thread";
  const std::string mem_a = ReadFile(*dir_ / "a.mem"), mem_b = ReadFile(*dir_ / "b.mem");
  ASSERT_GT(mem_a.size(), 1000u);
  EXPECT_TRUE(mem_a == mem_b) << "place-cell memories differ";

  // Localizing in that memory (placecells -> navigator and fused-slam: fixes, commands, fused poses)
  // is as repeatable; the place cells without their distance filter, as fused-slam wants them.
  auto localize = [&](const std::string& out) {
    ReplayOptions o = Options(out);
    o.sets = {"placecells:placecells.memory_file=" + (*dir_ / "a.mem").string(),
              "placecells:distance_filter.enabled=false"};
    o.only = {"placecells", "navigator", "fused-slam"};
    std::ostringstream log;
    return RunReplay(o, log);
  };
  const ReplayResult c = localize("c.lcmlog"), d = localize("d.lcmlog");
  auto count = [](const ReplayResult& r, const char* ch) {
    return r.outputs_by_channel.count(ch) ? r.outputs_by_channel.at(ch) : 0;
  };
  EXPECT_GT(count(c, "POSE_PLACE_CELLS"), 0);
  // A fused pose per scan, and one per visual measurement: more than without the place cells.
  EXPECT_GT(count(c, "POSE_EKF"), count(a, "POSE_EKF"));
  EXPECT_TRUE(ReadFile(*dir_ / "c.lcmlog") == ReadFile(*dir_ / "d.lcmlog")) << "localization outputs differ";
}

TEST_F(ReplayTest, OutputEventsCarryTheCausingInputsTimeAndInputsAreOptional) {
  ReplayOptions o = Options("dr.lcmlog");
  o.only = {"dead-reckoning"};
  o.with_inputs = true;
  std::ostringstream text;
  const ReplayResult r = RunReplay(o, text);
  EXPECT_EQ(r.nodes, std::vector<std::string>{"dead-reckoning"});
  glue::LogReader in(*log_), out(o.output);
  glue::LogEvent e, f;
  int64_t odometry = 0, events = 0;
  while (in.Next(&e)) ++events;
  // Each input is followed by what it caused: ODOMETRY -> POSE_DEAD_RECKONING at the same time.
  while (out.Next(&f)) {
    if (f.channel != "ODOMETRY") continue;
    ++odometry;
    ASSERT_TRUE(out.Next(&e));
    EXPECT_EQ(e.channel, "POSE_DEAD_RECKONING");
    EXPECT_EQ(e.timestamp_us, f.timestamp_us);
  }
  EXPECT_GT(odometry, 100);
  EXPECT_EQ(r.outputs, odometry);
  EXPECT_EQ(r.written, events + odometry);  // every input, and one pose per odometry message
}

TEST_F(ReplayTest, RecordedOutputsAreRegeneratedNotFedTwice) {
  // A log that already holds dead-reckoning poses (as a recording of the live run does).
  ReplayOptions first = Options("with_poses.lcmlog");
  first.only = {"dead-reckoning"};
  first.with_inputs = true;
  std::ostringstream text;
  const ReplayResult r1 = RunReplay(first, text);
  ReplayOptions second = Options("again.lcmlog");
  second.input = first.output;
  second.only = {"dead-reckoning"};
  second.with_inputs = true;
  const ReplayResult r2 = RunReplay(second, text);
  EXPECT_EQ(r2.dropped, r1.outputs);
  EXPECT_EQ(r2.outputs, r1.outputs);
  EXPECT_TRUE(ReadFile(first.output) == ReadFile(second.output));
}

TEST_F(ReplayTest, SelectionAndOverrideErrorsNameTheProblem) {
  std::ostringstream text;
  ReplayOptions o = Options("x.lcmlog");
  o.only = {"ratslam-typo"};
  try {
    RunReplay(o, text);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no process 'ratslam-typo'"), std::string::npos) << e.what();
  }
  o.only = {"homing"};
  o.sets = {"homing:homing.no_such_key=1"};
  try {
    RunReplay(o, text);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no key 'no_such_key' in section [homing]"), std::string::npos) << e.what();
  }
  o.sets = {"navigator:route.route=none"};
  EXPECT_THROW(RunReplay(o, text), std::runtime_error);  // navigator is not selected
  // An override of a key the config lacks is an error also for a process picked by default (it was a
  // warning, and the process left out), with the nearest key; nothing is written.
  o.only.clear();
  o.output = (*dir_ / "override-errors.lcmlog").string();
  for (const char* set : {"homing:homing.hom=first", "dead-reckoning:dead_reckonin.rotation_noise_rad_per_m=0"}) {
    o.sets = {set};
    try {
      RunReplay(o, text);
      FAIL() << set;
    } catch (const glue::ConfigError& e) {
      EXPECT_NE(
          std::string(e.what()).find(std::string("--set ") + std::string(set).substr(0, std::string(set).find('='))),
          std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("did you mean"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(o.output)) << set;
  }
  o.sets = {"homing:homing.home=first"};
  o.only = {"homming"};
  try {
    RunReplay(o, text);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no process 'homming' (did you mean 'homing'?)"), std::string::npos)
        << e.what();
  }
  o.only = {"homing"};
  EXPECT_THROW(ParseOverride("homing.home=first"), std::invalid_argument);
  const ConfigOverride p = ParseOverride("laser-slam:laser_slam.match_distance_m=0.5");
  EXPECT_EQ(p.process, "laser-slam");
  EXPECT_EQ(p.section, "laser_slam");
  EXPECT_EQ(p.key, "match_distance_m");
  EXPECT_EQ(p.value, "0.5");
  // A process picked by name that cannot start is an error; picked by default it is left out.
  o.sets = {"placecells:placecells.memory_file=" + (*dir_ / "missing.mem").string()};
  o.only = {"placecells"};
  EXPECT_THROW(RunReplay(o, text), std::runtime_error);
  o.only.clear();
  o.sets.push_back("homing:homing.home=first");
  const ReplayResult r = RunReplay(o, text);
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_NE(r.skipped[0].find("placecells"), std::string::npos);
  EXPECT_NE(r.skipped[0].find("missing.mem"), std::string::npos) << r.skipped[0];
}

TEST_F(ReplayTest, DamagedLogIsReplayedUpToAndAfterTheDamage) {
  // Overwrite the sync word of an event a third of the way in, and cut the last event in half.
  std::vector<uint64_t> offsets;
  {
    glue::LogReader intact(*log_);
    glue::LogEvent e;
    while (intact.Next(&e)) offsets.push_back(e.offset);
  }
  const auto all = static_cast<int64_t>(offsets.size());
  std::string bytes = ReadFile(*log_);
  const uint64_t hit = offsets[offsets.size() / 3];
  for (size_t i = 0; i < 4; ++i) bytes[hit + i] = '\x55';
  bytes.resize(offsets.back() + (bytes.size() - offsets.back()) / 2);
  const fs::path damaged = *dir_ / "damaged.lcmlog";
  std::ofstream(damaged, std::ios::binary) << bytes;
  ReplayOptions o = Options("from_damaged.lcmlog");
  o.input = damaged.string();
  o.only = {"dead-reckoning"};
  std::ostringstream text;
  const ReplayResult r = RunReplay(o, text);
  EXPECT_EQ(r.damage_count, 2) << text.str();
  EXPECT_EQ(r.input_events, all - 2);
  EXPECT_NE(text.str().find("damaged.lcmlog: byte " + std::to_string(hit) + ": no event sync word; skipped"),
            std::string::npos)
      << text.str();
  EXPECT_NE(text.str().find("damaged.lcmlog: byte "), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("truncated"), std::string::npos) << text.str();

  // The binary exits with 3 and says so; the effective configuration is printed only when asked for
  // (it came first, about 500 lines for every process, before the damage warning).
  const std::string cmd = std::string(SNAPNAV_BIN_DIR) + "/replay --only dead-reckoning " + damaged.string() +
                          " --out " + (*dir_ / "bin.lcmlog").string() + " 2> " + (*dir_ / "err.txt").string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  const std::string err = ReadFile(*dir_ / "err.txt");
  EXPECT_NE(err.find("is damaged"), std::string::npos) << err;
  EXPECT_EQ(err.find("[dead_reckoning]"), std::string::npos) << err;
  const int printed = std::system((cmd + " --print-config").c_str());
  ASSERT_TRUE(WIFEXITED(printed));
  EXPECT_EQ(WEXITSTATUS(printed), 3);
  const std::string with_config = ReadFile(*dir_ / "err.txt");
  EXPECT_NE(with_config.find("[dead_reckoning]\ntranslation_noise_m_per_m = "), std::string::npos) << with_config;
}

// A file that is not an LCM log at all is an error naming it, before anything runs (it replayed
// nothing, reported "damage" over the whole file and exited 3).
TEST_F(ReplayTest, NotAnLcmLogIsAnError) {
  const fs::path junk = *dir_ / "photo.jpg";
  std::string bytes = "\xff\xd8\xff\xe0";
  for (int i = 0; i < 5000; ++i) bytes.push_back(static_cast<char>((i * 37 + 11) % 251));
  std::ofstream(junk, std::ios::binary) << bytes;
  ReplayOptions o = Options("junk-out.lcmlog");
  o.input = junk.string();
  std::ostringstream text;
  try {
    RunReplay(o, text);
    FAIL() << text.str();
  } catch (const glue::LogError& e) {
    EXPECT_NE(std::string(e.what()).find(junk.string() + " is not an LCM log: byte 0"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(o.output));
  const std::string cmd = std::string(SNAPNAV_BIN_DIR) + "/replay " + junk.string() + " --out " + o.output + " 2> " +
                          (*dir_ / "junk-err.txt").string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string err = ReadFile(*dir_ / "junk-err.txt");
  EXPECT_NE(err.find("replay: error: " + junk.string() + " is not an LCM log"), std::string::npos) << err;
  EXPECT_LE(std::count(err.begin(), err.end(), '\n'), 3) << err;
}

}  // namespace
}  // namespace snapnav::replay
