// Node tests: the placecells process on memq:// with panoramas of indoor13 rendered by the
// simulator. Explore records cells at the poses of the explore pose channel and saves the memory
// file; localize loads it and names the cell the robot is at; bad input is counted, never fatal.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "placecells_node.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/place_cells.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/place_cell_match_t.hpp"
#include "snapnav/pose_t.hpp"
#include "test_lab.hpp"

namespace snapnav::processes::test {
namespace {

namespace fs = std::filesystem;

constexpr int64_t kStart = 1700000000000000;  // utime of the first message
constexpr int64_t kSecond = 1000000;

std::string MemoryPath(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / "placecells_node";
  fs::create_directories(dir);
  const fs::path path = dir / (name + ".mem");
  fs::remove(path);
  return path.string();
}

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

// The pose a cell is stored at, on the config's explore pose channel (the shipped one:
// POSE_LASER_SLAM, what a robot has while it explores).
pose_t TruthMsg(const nav::Pose2& p, int64_t utime) {
  return glue::ToPoseMsg(utime, "laser_slam", "map", p, Eigen::Matrix3d::Zero());
}

odometry_t OdometryMsg(const nav::Pose2& cumulative, int64_t utime) {
  return glue::ToOdometryMsg(utime, "test", cumulative, {0, 0, 0}, 0.02);
}

// Cells on the indoor13 grid, 0.6 m and more apart, in varied headings.
const std::vector<nav::Pose2> kCellPoses = {
    {2.5, 2.0, 0.0}, {3.5, 2.0, 0.7}, {4.5, 2.0, -1.2}, {2.5, 3.2, 2.5}, {3.5, 3.2, -2.8}, {4.5, 3.2, 1.6},
    {2.5, 4.1, -0.4}, {3.5, 4.1, 1.9}, {4.5, 4.1, 3.0}};

// The shipped config exploring panoramas into `memory_file`, with `overrides`.
PlaceCellsConfig ExploreConfig(const std::string& prefix, std::initializer_list<Override> overrides,
                               const std::string& memory_file) {
  auto config = Config(prefix, overrides);
  config.mode = PlaceCellsMode::kExplore;
  config.raw_input = false;
  config.memory_file = memory_file;
  return config;
}

// Explores kCellPoses (one frame a second, each after its ground-truth pose) into `memory_file`.
std::vector<place_cell_match_t> Explore(const std::string& prefix, const std::string& memory_file,
                                        std::initializer_list<Override> overrides, int64_t* saves = nullptr) {
  const auto config = ExploreConfig(prefix, overrides, memory_file);
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  std::vector<place_cell_match_t> got;
  bus.Subscribe<place_cell_match_t>(prefix + "PLACE_CELL_MATCH", [&](const place_cell_match_t& m) { got.push_back(m); });
  auto& lab = Indoor13::Get();
  for (size_t i = 0; i < kCellPoses.size(); ++i) {
    const int64_t t = kStart + static_cast<int64_t>(i) * kSecond;
    bus.Publish(config.explore_pose_channel, TruthMsg(kCellPoses[i], t - 10000));
    bus.Publish(prefix + "OMNI_PANORAMA", lab.PanoramaFrame(kCellPoses[i], t));
    HandleAll(bus);
  }
  EXPECT_EQ(node.rejected_total(), 0) << log.str();
  node.Save();
  if (saves) *saves = node.saves();
  return got;
}

// Every frame processed (rate limit off), so each explore frame is a candidate cell.
const std::initializer_list<Override> kEveryFrame = {{"placecells", "min_interval_s", "0"},
                                                     {"placecells", "min_travel_m", "0"}};

TEST(PlaceCellsNode, ExploreRecordsNovelViewsAtTheirPosesAndSavesTheFile) {
  const std::string file = MemoryPath("explore");
  int64_t saves = 0;
  const auto got = Explore("E1_", file,
                           {{"placecells", "min_interval_s", "0.5"}, {"placecells", "save_every_cells", "4"}}, &saves);
  ASSERT_EQ(got.size(), kCellPoses.size());
  const double config_threshold = Config("", {}).novelty_threshold;
  // 0.6 m and more apart: each view is novel, each cell is where the ground truth put it.
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].cell_id, static_cast<int>(i));
    EXPECT_EQ(got[i].utime, kStart + static_cast<int64_t>(i) * kSecond);
    EXPECT_EQ(got[i].x_m, kCellPoses[i].x_m);
    EXPECT_EQ(got[i].theta_rad, kCellPoses[i].theta_rad);
    EXPECT_EQ(got[i].ncandidates, static_cast<int>(i));
    if (i > 0) {
      EXPECT_GT(got[i].score, config_threshold) << "novelty of view " << i;
    }
  }
  EXPECT_EQ(saves, 3);  // after cells 4 and 8, and the last one at the end
  const auto memory = glue::LoadPlaceMemory(file);
  ASSERT_EQ(memory.size(), static_cast<int>(kCellPoses.size()));
  EXPECT_EQ(memory.cell(4).pose.y_m, kCellPoses[4].y_m);
}

// A view close to a stored cell is not novel: no new cell, the match names that cell. An
// existing file is extended.
TEST(PlaceCellsNode, ExploreKnownPlaceAddsNoCellAndExtendsTheFile) {
  const std::string file = MemoryPath("extend");
  Explore("E2_", file, kEveryFrame);
  const auto config = ExploreConfig("E2b_", kEveryFrame, file);
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  ASSERT_EQ(node.memory().size(), static_cast<int>(kCellPoses.size())) << log.str();
  std::vector<place_cell_match_t> got;
  bus.Subscribe<place_cell_match_t>("E2b_PLACE_CELL_MATCH", [&](const place_cell_match_t& m) { got.push_back(m); });
  auto& lab = Indoor13::Get();
  const nav::Pose2 near_cell_4{3.53, 3.22, -2.5};  // 4 cm from cell 4, turned by 0.3 rad
  const nav::Pose2 new_place{3.0, 2.6, 0.0};        // 0.6 m and more from every cell
  bus.Publish(config.explore_pose_channel, TruthMsg(near_cell_4, kStart));
  bus.Publish("E2b_OMNI_PANORAMA", lab.PanoramaFrame(near_cell_4, kStart));
  bus.Publish(config.explore_pose_channel, TruthMsg(new_place, kStart + kSecond));
  bus.Publish("E2b_OMNI_PANORAMA", lab.PanoramaFrame(new_place, kStart + kSecond));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].cell_id, 4);
  EXPECT_LT(got[0].score, config.novelty_threshold);
  EXPECT_EQ(got[1].cell_id, static_cast<int>(kCellPoses.size()));
  EXPECT_GT(got[1].score, config.novelty_threshold);
  EXPECT_EQ(node.new_cells(), 1);
  EXPECT_TRUE(node.Save());
  EXPECT_FALSE(node.Save());  // nothing new since
  EXPECT_EQ(glue::LoadPlaceMemory(file).size(), static_cast<int>(kCellPoses.size()) + 1);
}

struct LocalizeRun {
  std::vector<place_cell_match_t> matches;
  std::vector<pose_t> poses;
};

TEST(PlaceCellsNode, LocalizeNamesTheCellTheRobotIsAtAndPublishesAPose) {
  const std::string file = MemoryPath("localize");
  Explore("L1_", file, kEveryFrame);
  auto config = Config("L1b_", kEveryFrame);
  config.raw_input = false;
  config.memory_file = file;
  ASSERT_EQ(config.mode, PlaceCellsMode::kLocalize);
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  // The index is built when the node starts, not on the first frame (which would hold the frames after it).
  EXPECT_TRUE(node.memory().vocabulary().trained());
  EXPECT_NE(log.str().find("placecells: index of " + std::to_string(node.memory().size()) + " cells built in "),
            std::string::npos)
      << log.str();
  LocalizeRun run;
  bus.Subscribe<place_cell_match_t>("L1b_PLACE_CELL_MATCH",
                                    [&](const place_cell_match_t& m) { run.matches.push_back(m); });
  bus.Subscribe<pose_t>("L1b_POSE_PLACE_CELLS", [&](const pose_t& m) { run.poses.push_back(m); });
  auto& lab = Indoor13::Get();
  // Near cells 1, 5 and 6, in other headings.
  const std::vector<std::pair<int, nav::Pose2>> visits = {
      {1, {3.54, 2.03, 2.0}}, {5, {4.47, 3.15, -0.5}}, {6, {2.52, 4.06, 1.0}}};
  for (size_t i = 0; i < visits.size(); ++i) {
    bus.Publish("L1b_OMNI_PANORAMA", lab.PanoramaFrame(visits[i].second, kStart + static_cast<int64_t>(i) * kSecond));
  }
  HandleAll(bus);
  ASSERT_EQ(run.matches.size(), visits.size()) << log.str();
  ASSERT_EQ(run.poses.size(), visits.size());
  EXPECT_EQ(node.localized(), static_cast<int64_t>(visits.size()));
  for (size_t i = 0; i < visits.size(); ++i) {
    const auto& [cell, truth] = visits[i];
    const auto& m = run.matches[i];
    const auto& p = run.poses[i];
    EXPECT_EQ(m.cell_id, cell) << "visit " << i;
    EXPECT_EQ(m.utime, kStart + static_cast<int64_t>(i) * kSecond);
    EXPECT_EQ(m.distance_measure, place_cell_match_t::BEARING_DIFFERENCE);
    EXPECT_EQ(m.x_m, kCellPoses[cell].x_m);
    EXPECT_GE(m.ncandidates, 1);
    EXPECT_EQ(p.estimator, "place_cells");
    EXPECT_EQ(p.frame, "map");
    EXPECT_EQ(p.utime, m.utime);
    const double error = std::hypot(p.x_m - truth.x_m, p.y_m - truth.y_m);
    EXPECT_LT(error, 0.15) << "visit " << i << " at (" << p.x_m << ", " << p.y_m << ")";
    EXPECT_LT(std::abs(nav::WrapAngle(p.theta_rad - truth.theta_rad)), 0.05) << "visit " << i;
    // A covariance: symmetric, positive variances, at least the configured floor.
    EXPECT_GE(p.covariance[0], 0.06 * 0.06 * 0.99);
    EXPECT_GE(p.covariance[4], 0.06 * 0.06 * 0.99);
    EXPECT_GT(p.covariance[8], 0);
    EXPECT_DOUBLE_EQ(p.covariance[1], p.covariance[3]);
  }
}

// Raw catadioptric frames are unwrapped like the landmarks and homing processes do.
TEST(PlaceCellsNode, LocalizesRawFrames) {
  const std::string file = MemoryPath("raw");
  Explore("R1_", file, kEveryFrame);
  auto config = Config("R1b_", kEveryFrame);  // input = raw in the shipped config
  config.memory_file = file;
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  std::vector<place_cell_match_t> got;
  bus.Subscribe<place_cell_match_t>("R1b_PLACE_CELL_MATCH", [&](const place_cell_match_t& m) { got.push_back(m); });
  bus.Publish("R1b_OMNI_FRAME", Indoor13::Get().RawFrame({4.52, 2.02, 0.5}, kStart));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 1u) << log.str();
  EXPECT_EQ(got[0].cell_id, 2);
}

// At most one frame per min_interval_s of message time, unless the odometry travelled min_travel_m.
TEST(PlaceCellsNode, RateLimitByMessageTimeAndTravel) {
  const std::string file = MemoryPath("rate");
  Explore("T1_", file, kEveryFrame);
  auto config = Config("T1b_", {{"placecells", "min_interval_s", "0.5"},
                                {"placecells", "min_travel_m", "0.1"},
                                {"placecells", "stats_interval_s", "1"}});
  config.raw_input = false;
  config.memory_file = file;
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  int matches = 0;
  bus.Subscribe<place_cell_match_t>("T1b_PLACE_CELL_MATCH", [&](const place_cell_match_t&) { ++matches; });
  const auto frame = Indoor13::Get().PanoramaFrame({3.5, 2.0, 0.7}, 0);
  auto at = [&](int64_t utime) {
    auto f = frame;
    f.utime = utime;
    return f;
  };
  // 10 frames at 10 Hz, standing still: t = 0 and 0.5 s are processed.
  bus.Publish("T1b_ODOMETRY", OdometryMsg({0, 0, 0}, kStart));
  for (int i = 0; i < 10; ++i) bus.Publish("T1b_OMNI_PANORAMA", at(kStart + i * kSecond / 10));
  HandleAll(bus);
  EXPECT_EQ(node.processed(), 2);
  // 0.12 m of travel 0.1 s later: processed before the interval is over.
  bus.Publish("T1b_ODOMETRY", OdometryMsg({0.12, 0, 0}, kStart + 10 * kSecond / 10));
  bus.Publish("T1b_OMNI_PANORAMA", at(kStart + 10 * kSecond / 10));
  bus.Publish("T1b_OMNI_PANORAMA", at(kStart + 11 * kSecond / 10));
  HandleAll(bus);
  EXPECT_EQ(node.processed(), 3);
  EXPECT_EQ(matches, 3);
  EXPECT_EQ(node.skipped().at("rate limit"), 9);
  // One stats line: 1 s of message time after the first frame.
  EXPECT_NE(log.str().find("placecells: t 1700000001.0 s: frames 11, processed 2"), std::string::npos) << log.str();
}

// Odometry moves the last fix: the distance filter then prefers the cell near the prediction.
TEST(PlaceCellsNode, OdometryPredictionFeedsTheDistanceFilter) {
  const std::string file = MemoryPath("filter");
  Explore("F1_", file, kEveryFrame);
  auto config = Config("F1b_", {{"placecells", "min_interval_s", "0"}, {"placecells", "min_travel_m", "0"},
                                {"distance_filter", "gate_m", "0.5"}});
  config.raw_input = false;
  config.memory_file = file;
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  std::vector<place_cell_match_t> got;
  bus.Subscribe<place_cell_match_t>("F1b_PLACE_CELL_MATCH", [&](const place_cell_match_t& m) { got.push_back(m); });
  auto& lab = Indoor13::Get();
  // A fix at cell 0; odometry says the robot drove 1 m along its heading (0: +x) to cell 1's place.
  bus.Publish("F1b_ODOMETRY", OdometryMsg({10, 10, 0}, kStart));
  bus.Publish("F1b_OMNI_PANORAMA", lab.PanoramaFrame({2.5, 2.0, 0.0}, kStart));
  HandleAll(bus);
  bus.Publish("F1b_ODOMETRY", OdometryMsg({11, 10, 0}, kStart + kSecond));
  // The view at cell 0 again: the gate around the prediction (cell 1's place) leaves cell 1.
  bus.Publish("F1b_OMNI_PANORAMA", lab.PanoramaFrame({2.5, 2.0, 0.0}, kStart + kSecond));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 2u) << log.str();
  EXPECT_EQ(got[0].cell_id, 0);
  EXPECT_EQ(got[1].cell_id, 1);
}

// Frames that cannot be used, odometry and poses with NaN are counted by reason; the node goes on.
TEST(PlaceCellsNode, MalformedInputIsCountedNotFatal) {
  const std::string file = MemoryPath("malformed");
  Explore("M1_", file, kEveryFrame);
  auto config = Config("M1b_", kEveryFrame);
  config.raw_input = false;
  config.memory_file = file;
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  std::vector<place_cell_match_t> got;
  bus.Subscribe<place_cell_match_t>("M1b_PLACE_CELL_MATCH", [&](const place_cell_match_t& m) { got.push_back(m); });
  auto& lab = Indoor13::Get();
  auto small = lab.PanoramaFrame({3.5, 2.0, 0}, kStart);
  small.width = 360;  // the pixels no longer fit either
  bus.Publish("M1b_OMNI_PANORAMA", small);
  auto garbled = lab.PanoramaFrame({3.5, 2.0, 0}, kStart + 1);
  garbled.data.resize(100);
  garbled.data_size = 100;
  bus.Publish("M1b_OMNI_PANORAMA", garbled);
  const char junk[] = "not an omni frame at all";
  bus.PublishRaw("M1b_OMNI_PANORAMA", junk, sizeof(junk));
  bus.Publish("M1b_ODOMETRY", OdometryMsg({NAN, 0, 0}, kStart + 2));
  bus.Publish("M1b_OMNI_PANORAMA", lab.PanoramaFrame({3.52, 2.01, 0.2}, kStart + 3));
  HandleAll(bus);
  EXPECT_EQ(node.rejected().at("wrong size"), 1) << log.str();
  EXPECT_EQ(node.rejected().at("bad odometry"), 1);
  EXPECT_GE(node.rejected_total(), 3);
  EXPECT_GE(bus.stats().at("M1b_OMNI_PANORAMA").decode_errors, 3u);  // the junk payload among them
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].cell_id, 1);
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("rejected (wrong size): 1"), std::string::npos) << report.str();
}

TEST(PlaceCellsNode, ExploreWithoutAPoseSkipsTheFrame) {
  const auto config = ExploreConfig("X1_", kEveryFrame, MemoryPath("nopose"));
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  auto& lab = Indoor13::Get();
  bus.Publish("X1_OMNI_PANORAMA", lab.PanoramaFrame({3.5, 2.0, 0}, kStart));  // no pose yet
  bus.Publish(config.explore_pose_channel, TruthMsg({3.5, 2.0, 0}, kStart + 5 * kSecond));
  bus.Publish("X1_OMNI_PANORAMA", lab.PanoramaFrame({3.5, 2.0, 0}, kStart + kSecond));  // 4 s from it
  HandleAll(bus);
  EXPECT_EQ(node.skipped().at("no explore pose"), 2);
  EXPECT_EQ(node.memory().size(), 0);
  EXPECT_FALSE(node.Save());
  EXPECT_FALSE(fs::exists(config.memory_file));
}

// Explore at a pose source that corrects its past (laser-slam's graph back end closing a loop): the
// poses of the last cells came drifted; a correction table for the explore pose channel moves the
// cells placed on them back, the next cell is placed corrected, the file is written again. A table
// of another channel is another estimator's (ignored); a malformed one is counted, not applied.
TEST(PlaceCellsNode, ExploredCellsMoveWithTheCorrectionsOfTheirPoseSource) {
  const auto config = ExploreConfig("X2_", kEveryFrame, MemoryPath("corrected"));
  glue::Bus bus("memq://");
  std::ostringstream log;
  PlaceCellsNode node(bus, config, log);
  auto& lab = Indoor13::Get();
  const nav::Pose2 drift{0.12, -0.08, 0.05};   // what the pose source got wrong from cell 4 on
  const auto time_of = [](size_t i) { return kStart + static_cast<int64_t>(i) * kSecond; };
  const auto explore = [&](size_t i, const nav::Pose2& published) {
    bus.Publish(config.explore_pose_channel, TruthMsg(published, time_of(i) - 10000));
    bus.Publish("X2_OMNI_PANORAMA", lab.PanoramaFrame(kCellPoses[i], time_of(i)));
    HandleAll(bus);
  };
  for (size_t i = 0; i < 7; ++i) explore(i, i < 4 ? kCellPoses[i] : drift.Compose(kCellPoses[i]));
  ASSERT_EQ(node.memory().size(), 7);
  EXPECT_NEAR(node.memory().cell(5).pose.x_m, drift.Compose(kCellPoses[5]).x_m, 1e-12);
  EXPECT_TRUE(node.Save());

  // The table: from cell 4's pose on, the drift undone.
  const nav::PoseCorrectionTable table = {{time_of(0) - 10000, {}}, {time_of(4) - 10000, drift.Inverse()}};
  bus.Publish("X2_LASER_SLAM_CORRECTION", glue::ToPoseCorrectionMsg(time_of(7), "OTHER_POSE", 1, {{0, drift}}));
  pose_correction_t broken = glue::ToPoseCorrectionMsg(time_of(7), config.explore_pose_channel, 1, table);
  broken.theta_rad[1] = std::nan("");
  bus.Publish("X2_LASER_SLAM_CORRECTION", broken);
  HandleAll(bus);
  EXPECT_EQ(node.corrections(), 0);
  EXPECT_EQ(node.rejected().at("bad pose correction"), 1);
  EXPECT_NEAR(node.memory().cell(5).pose.x_m, drift.Compose(kCellPoses[5]).x_m, 1e-12);

  bus.Publish("X2_LASER_SLAM_CORRECTION", glue::ToPoseCorrectionMsg(time_of(7), config.explore_pose_channel, 1, table));
  HandleAll(bus);
  EXPECT_EQ(node.corrections(), 1);
  EXPECT_EQ(node.cells_moved(), 3);  // cells 4, 5, 6
  // The next pose still comes drifted (published before the source's correction reached it): placed corrected.
  explore(7, drift.Compose(kCellPoses[7]));
  ASSERT_EQ(node.memory().size(), 8);
  for (int i = 0; i < 8; ++i) {
    const nav::Pose2& p = node.memory().cell(i).pose;
    EXPECT_NEAR(p.x_m, kCellPoses[i].x_m, 1e-9) << "cell " << i;
    EXPECT_NEAR(p.y_m, kCellPoses[i].y_m, 1e-9) << "cell " << i;
    EXPECT_NEAR(p.theta_rad, kCellPoses[i].theta_rad, 1e-9) << "cell " << i;
  }
  // The same table again moves nothing; the file holds the corrected cells.
  bus.Publish("X2_LASER_SLAM_CORRECTION", glue::ToPoseCorrectionMsg(time_of(8), config.explore_pose_channel, 1, table));
  HandleAll(bus);
  EXPECT_EQ(node.cells_moved(), 3);
  EXPECT_TRUE(node.Save());
  const auto memory = glue::LoadPlaceMemory(config.memory_file);
  ASSERT_EQ(memory.size(), 8);
  EXPECT_NEAR(memory.cell(5).pose.x_m, kCellPoses[5].x_m, 1e-9);
  EXPECT_NE(log.str().find("moved 3 of 7 cells"), std::string::npos) << log.str();
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("corrections of " + config.explore_pose_channel + " taken 2 (cells moved 3)"),
            std::string::npos)
      << report.str();
}

TEST(PlaceCellsNode, LocalizeRefusesAMissingOrCorruptOrMismatchedMemory) {
  auto config = Config("C1_", {});
  config.memory_file = MemoryPath("absent");
  glue::Bus bus("memq://");
  std::ostringstream log;
  try {
    PlaceCellsNode node(bus, config, log);
    FAIL() << "no error";
  } catch (const glue::PlaceMemoryError& e) {
    EXPECT_NE(std::string(e.what()).find(config.memory_file), std::string::npos) << e.what();
  }
  std::ofstream(config.memory_file) << "SNAPNAV-PLACECELLS but not really";
  try {
    PlaceCellsNode node(bus, config, log);
    FAIL() << "no error";
  } catch (const glue::PlaceMemoryError& e) {
    EXPECT_NE(std::string(e.what()).find(config.memory_file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at byte"), std::string::npos) << e.what();
  }
  // A memory of other views (SURF, another signature) is not compared with SIFT views.
  const std::string file = MemoryPath("surf");
  Explore("C1x_", file, {{"landmarks", "method", "surf"}, {"placecells", "min_interval_s", "0"}});
  config.memory_file = file;
  try {
    PlaceCellsNode node(bus, config, log);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("[landmarks] method: surf in the file, sift in the config"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace snapnav::processes::test
