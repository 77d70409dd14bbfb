// The sim process on memq://: determinism, message contents, shipped scenes and config.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "../support/config_errors.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/time.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {
namespace {

SimConfig ShippedConfig(const std::string& prefix) {
  return SimConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), prefix);
}

// Runs the sim for `seconds` and returns every (channel, payload) it published, in order.
std::vector<std::pair<std::string, std::string>> Record(uint64_t seed, double seconds, const std::string& prefix) {
  glue::Bus bus("memq://");
  auto config = ShippedConfig(prefix);
  config.seed = seed;
  config.duration_s = seconds;
  config.publish_panorama = true;
  const auto scene = LoadSceneFile(SceneFilePath("people11"));
  std::vector<std::pair<std::string, std::string>> got;
  bus.SubscribeRaw(prefix + ".*", [&](const void* d, size_t n) {
    got.emplace_back(bus.current().channel, std::string(static_cast<const char*>(d), n));
  });
  SimNode node(bus, config, scene);
  while (node.Step()) {
    while (bus.HandleOnce(0)) {
    }
  }
  return got;
}

TEST(SimNode, SameSeedGivesByteIdenticalMessages) {
  const auto a = Record(7, 1.0, "D1_");
  const auto b = Record(7, 1.0, "D1_");
  const auto c = Record(8, 1.0, "D1_");
  ASSERT_GT(a.size(), 50u);
  EXPECT_TRUE(a == b);
  EXPECT_FALSE(a == c);
}

TEST(SimNode, PublishesEverySensorWithConsistentTimes) {
  glue::Bus bus("memq://");
  auto config = ShippedConfig("S1_");
  config.duration_s = 1.0;
  config.publish_panorama = true;
  const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
  std::vector<omni_frame_t> raw, pano;
  std::vector<laser_scan_t> scans;
  std::vector<odometry_t> odo;
  std::vector<pose_t> truth;
  bus.Subscribe<omni_frame_t>("S1_OMNI_FRAME", [&](const omni_frame_t& m) { raw.push_back(m); });
  bus.Subscribe<omni_frame_t>("S1_OMNI_PANORAMA", [&](const omni_frame_t& m) { pano.push_back(m); });
  bus.Subscribe<laser_scan_t>("S1_LASER_SCAN", [&](const laser_scan_t& m) { scans.push_back(m); });
  bus.Subscribe<odometry_t>("S1_ODOMETRY", [&](const odometry_t& m) { odo.push_back(m); });
  bus.Subscribe<pose_t>("S1_POSE_GROUND_TRUTH", [&](const pose_t& m) { truth.push_back(m); });
  SimNode node(bus, config, scene);
  while (node.Step()) {
    while (bus.HandleOnce(0)) {
    }
  }
  ASSERT_EQ(raw.size(), 10u);
  ASSERT_EQ(pano.size(), 10u);
  ASSERT_EQ(scans.size(), 10u);
  ASSERT_EQ(odo.size(), 50u);
  ASSERT_EQ(truth.size(), 50u);
  EXPECT_EQ(raw[3].utime - raw[2].utime, 100000);
  EXPECT_EQ(raw[0].width, 640);
  EXPECT_EQ(raw[0].height, 480);
  EXPECT_EQ(raw[0].encoding, omni_frame_t::JPEG);  // the shipped default: compact frames on the bus and in logs
  EXPECT_LT(raw[0].data_size, 640 * 480 * 3 / 8);
  EXPECT_EQ(glue::FrameToImage(raw[0]).size(), cv::Size(640, 480));
  // The calibration the frames carry: the camera's (the shipped realistic camera's is off by a few px
  // from the 230 px mirror it renders, as a real calibration is).
  EXPECT_FLOAT_EQ(raw[0].mirror_outer_radius_px, static_cast<float>(config.camera.ReportedMirror().outer_radius_px));
  EXPECT_NEAR(raw[0].mirror_outer_radius_px, 230.f, 3.f);
  EXPECT_EQ(pano[0].kind, omni_frame_t::PANORAMA);
  EXPECT_EQ(pano[0].width, 720);
  EXPECT_EQ(glue::FrameToImage(pano[0]).cols, 720);
  EXPECT_EQ(scans[0].nranges, 681);
  for (float r : scans[0].ranges_m) {
    EXPECT_GE(r, scans[0].range_min_m);
    EXPECT_LE(r, scans[0].range_max_m);
  }
  EXPECT_EQ(truth[0].estimator, "ground_truth");
  // The robot moves along its route; odometry increments add up to about the true motion.
  double odo_dist = 0;
  for (const auto& o : odo) odo_dist += std::hypot(o.delta_x_m, o.delta_y_m);
  const double true_dist = std::hypot(truth.back().x_m - truth.front().x_m, truth.back().y_m - truth.front().y_m);
  EXPECT_GT(true_dist, 0.1);
  EXPECT_NEAR(odo_dist, true_dist, 0.05);
}

TEST(SimNode, FollowsDriveCommands) {
  glue::Bus bus("memq://");
  auto config = ShippedConfig("S2_");
  config.duration_s = 2.0;
  config.drive = "commands";
  config.realtime = true;  // do not wait for a controller per frame
  config.camera_rate_hz = 1;
  config.command_watchdog_s = 0;  // one command, obeyed for the whole run
  const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
  pose_t last{};
  bus.Subscribe<pose_t>("S2_POSE_GROUND_TRUTH", [&](const pose_t& m) { last = m; });
  SimNode node(bus, config, scene);
  drive_command_t cmd{};
  cmd.utime = config.start_utime;
  cmd.source = "test";
  cmd.linear_velocity_mps = 0.0;
  cmd.angular_velocity_radps = 0.5;
  bus.Publish("S2_DRIVE_COMMAND", cmd);
  while (node.Step()) {
  }
  while (bus.HandleOnce(0)) {
  }
  EXPECT_EQ(node.commands(), 1);
  EXPECT_NEAR(last.theta_rad, 0.5 * 2.0, 0.1);  // turned in place for 2 s
  EXPECT_NEAR(last.x_m, scene.start_pose.x(), 0.01);
}

// Drives by commands in real-time mode (no per-frame wait), publishing each command (0.2 m/s
// forward) at its time of the run [s] stamped with the robot's clock plus its offset [s].
struct DriveRun {
  std::vector<pose_t> truth;  // 50 Hz
  int64_t accepted = 0, stale = 0, watchdog_stops = 0;
};
DriveRun DriveWith(SimConfig config, const std::vector<std::pair<double, double>>& commands, double seconds = 2.0) {
  glue::Bus bus("memq://");
  config.duration_s = seconds;
  config.drive = "commands";
  config.realtime = true;
  config.camera_rate_hz = 1;
  const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
  DriveRun run;
  bus.Subscribe<pose_t>("W_POSE_GROUND_TRUTH", [&](const pose_t& m) { run.truth.push_back(m); });
  SimNode node(bus, config, scene);
  size_t next = 0;
  for (int step = 0;; ++step) {
    const double t = step / config.physics_rate_hz;
    for (; next < commands.size() && commands[next].first <= t; ++next) {
      drive_command_t cmd{};
      cmd.utime = node.utime() + std::llround(commands[next].second * 1e6);
      cmd.source = "test";
      cmd.linear_velocity_mps = 0.2;
      bus.Publish("W_DRIVE_COMMAND", cmd);
    }
    if (!node.Step()) break;
  }
  while (bus.HandleOnce(0)) {
  }
  run.accepted = node.commands();
  run.stale = node.stale_commands();
  run.watchdog_stops = node.watchdog_stops();
  return run;
}

TEST(SimNode, WatchdogStopsTheRobotWhenCommandsStop) {
  auto config = ShippedConfig("W_");
  ASSERT_GT(config.command_watchdog_s, 0);
  // Commands every 0.1 s for the first 0.5 s, then none: the robot stops command_watchdog_s later.
  std::vector<std::pair<double, double>> commands;
  for (double t = 0; t < 0.5; t += 0.1) commands.emplace_back(t, 0.0);
  const DriveRun run = DriveWith(config, commands);
  ASSERT_EQ(run.accepted, 5);
  EXPECT_EQ(run.watchdog_stops, 1);
  const auto x_at = [&](double t) { return run.truth.at(static_cast<size_t>(t * config.odometry_rate_hz)).x_m; };
  const double stop_s = 0.4 + config.command_watchdog_s + 0.05;
  const auto dist = [&](double t0, double t1) {
    const auto& a = run.truth.at(static_cast<size_t>(t0 * config.odometry_rate_hz));
    const auto& b = run.truth.at(static_cast<size_t>(t1 * config.odometry_rate_hz));
    return std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
  };
  EXPECT_GT(dist(0.0, stop_s), 0.12);  // 0.2 m/s for about 0.9 s
  EXPECT_NEAR(run.truth.back().x_m, x_at(stop_s), 0.01);  // then still
  EXPECT_NEAR(dist(stop_s, 1.98), 0.0, 0.01);
  // Off: the last command holds for the whole run.
  config.command_watchdog_s = 0;
  const DriveRun free_run = DriveWith(config, commands);
  EXPECT_EQ(free_run.watchdog_stops, 0);
  EXPECT_GT(std::hypot(free_run.truth.back().x_m - free_run.truth.front().x_m,
                       free_run.truth.back().y_m - free_run.truth.front().y_m), 0.3);
}

TEST(SimNode, IgnoresCommandsStampedFarFromItsClock) {
  auto config = ShippedConfig("W_");
  ASSERT_DOUBLE_EQ(config.command_max_age_s, 1.0);
  // Stamped 2 s behind and 2 s ahead (another clock, a replayed log): ignored, the robot stays.
  DriveRun run = DriveWith(config, {{0.0, -2.0}, {0.1, 2.0}, {0.2, -2.0}});
  EXPECT_EQ(run.accepted, 0);
  EXPECT_EQ(run.stale, 3);
  EXPECT_NEAR(run.truth.back().x_m, run.truth.front().x_m, 1e-6);
  // Stamped within the limit: obeyed.
  run = DriveWith(config, {{0.0, -0.5}, {0.1, 0.0}}, 0.5);
  EXPECT_EQ(run.accepted, 2);
  EXPECT_EQ(run.stale, 0);
  EXPECT_GT(std::hypot(run.truth.back().x_m - run.truth.front().x_m, run.truth.back().y_m - run.truth.front().y_m), 0.05);
}

TEST(SimNode, ClockOffsetShiftsEveryUtimeAndNothingElse) {
  auto config = ShippedConfig("C_");
  config.duration_s = 0.5;
  const auto record = [&](int64_t offset_us) {
    glue::Bus bus("memq://");
    config.clock_offset_us = offset_us;
    const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
    std::vector<std::pair<int64_t, std::vector<double>>> got;  // utime, pose or first ranges
    bus.Subscribe<pose_t>("C_POSE_GROUND_TRUTH", [&](const pose_t& m) { got.push_back({m.utime, {m.x_m, m.y_m, m.theta_rad}}); });
    bus.Subscribe<laser_scan_t>("C_LASER_SCAN", [&](const laser_scan_t& m) {
      got.push_back({m.utime, std::vector<double>(m.ranges_m.begin(), m.ranges_m.begin() + 5)});
    });
    SimNode node(bus, config, scene);
    while (node.Step()) {
      while (bus.HandleOnce(0)) {
      }
    }
    return got;
  };
  const auto a = record(0), b = record(2'000'000);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 20u);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].first - a[i].first, 2'000'000);
    EXPECT_EQ(b[i].second, a[i].second);
  }
}

// sim --frame-times: one line per omni frame (not per panorama), its utime as published and the wall
// clock when it was handed to the bus, after it was encoded (the two-host test times the link from it).
TEST(SimNode, FrameTimesNameEveryOmniFrameAndWhenItWasPublished) {
  glue::Bus bus("memq://");
  auto config = ShippedConfig("F_");
  config.duration_s = 0.5;
  config.publish_panorama = true;
  config.clock_offset_us = 2'000'000;  // the utime as published, the robot's clock, against the wall clock
  const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
  std::vector<int64_t> published;
  bus.Subscribe<omni_frame_t>("F_OMNI_FRAME", [&](const omni_frame_t& m) { published.push_back(m.utime); });
  std::ostringstream times;
  SimNode node(bus, config, scene);
  node.LogFramePublishTimes(&times);
  const int64_t wall_before = glue::WallUtime();
  while (node.Step()) {
    while (bus.HandleOnce(0)) {
    }
  }
  const int64_t wall_after = glue::WallUtime();
  ASSERT_EQ(published.size(), 5u);
  std::istringstream in(times.str());
  std::string line;
  std::vector<int64_t> logged;
  int64_t last_wall = wall_before;
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    ASSERT_NE(comma, std::string::npos) << line;
    logged.push_back(std::stoll(line.substr(0, comma)));
    const int64_t wall = std::stoll(line.substr(comma + 1));
    EXPECT_GE(wall, last_wall);
    EXPECT_LE(wall, wall_after);
    last_wall = wall;
  }
  EXPECT_EQ(logged, published);
}

TEST(SimNode, KidnappingMovesTheTruthNotTheOdometry) {
  // The corridor's robot drives down the left wing from (1, 8); at 2 s it is carried to the
  // mirrored place in the right wing. The ground truth jumps 28 m, the odometry does not, and the
  // route goes on from the nearest waypoint ahead, (29, 1): down the right wing.
  glue::Bus bus("memq://");
  auto config = ShippedConfig("K1_");
  config.duration_s = 4.0;
  config.camera_rate_hz = 1;
  config.kidnap.at_s = 2.0;
  config.kidnap.to = {29.0, 7.4, -M_PI / 2};
  const auto scene = LoadSceneFile(SceneFilePath("corridor"));
  std::vector<pose_t> truth;
  std::vector<odometry_t> odo;
  bus.Subscribe<pose_t>("K1_POSE_GROUND_TRUTH", [&](const pose_t& m) { truth.push_back(m); });
  bus.Subscribe<odometry_t>("K1_ODOMETRY", [&](const odometry_t& m) { odo.push_back(m); });
  SimNode node(bus, config, scene);
  while (node.Step()) {
    while (bus.HandleOnce(0)) {
    }
  }
  ASSERT_EQ(truth.size(), 200u);
  ASSERT_EQ(odo.size(), 200u);
  double largest_jump = 0, largest_odometry_step = 0;
  for (size_t i = 1; i < truth.size(); ++i) {
    largest_jump = std::max(largest_jump, std::hypot(truth[i].x_m - truth[i - 1].x_m, truth[i].y_m - truth[i - 1].y_m));
    largest_odometry_step = std::max(largest_odometry_step, std::hypot(odo[i].delta_x_m, odo[i].delta_y_m));
  }
  EXPECT_GT(largest_jump, 27.0);
  EXPECT_LT(largest_odometry_step, 0.02);
  EXPECT_NEAR(truth.front().x_m, 1.0, 0.01);
  EXPECT_NEAR(truth.back().x_m, 29.0, 0.05);
  EXPECT_LT(truth.back().y_m, 7.4 - 0.3);  // still going down, now in the right wing
  EXPECT_NEAR(odo.back().x_m, 1.0, 0.05);  // odometry believes it is in the left wing
  EXPECT_TRUE(node.world().kidnapped());
  // A destination inside a wall is refused.
  config.kidnap.to = {0.05, 5.0, 0.0};
  glue::Bus bus2("memq://");
  EXPECT_THROW(SimNode(bus2, config, scene), std::invalid_argument);
}

TEST(SimNode, GridDriveVisitsEveryGridNodeOnceAndEnds) {
  // drive = grid (the demo's exploration drive): every node of the scene's grid, row by row, each
  // row the other way round; the run ends when the last node is reached, whatever duration_s says.
  glue::Bus bus("memq://");
  auto config = ShippedConfig("G1_");
  config.drive = "grid";
  config.duration_s = 0;
  config.camera_rate_hz = 1;
  const auto scene = LoadSceneFile(SceneFilePath("outdoor11"));
  std::vector<pose_t> truth;
  bus.Subscribe<pose_t>("G1_POSE_GROUND_TRUTH", [&](const pose_t& m) { truth.push_back(m); });
  SimNode node(bus, config, scene);
  int steps = 0;
  while (node.Step() && ++steps < 100000) {
    while (bus.HandleOnce(0)) {
    }
  }
  ASSERT_LT(steps, 100000) << "the drive did not end";
  const auto& g = scene.grid;
  int visited = 0;
  double worst = 0;
  for (int iy = 0; iy < g.ny; ++iy) {
    for (int ix = 0; ix < g.nx; ++ix) {
      const Eigen::Vector2d node_xy = g.Position(ix, iy);
      double nearest = 1e9;
      for (const pose_t& p : truth) nearest = std::min(nearest, std::hypot(p.x_m - node_xy.x(), p.y_m - node_xy.y()));
      visited += nearest <= config.route_tolerance_m + 0.01;  // (switched at the step it came within)
      worst = std::max(worst, nearest);
    }
  }
  std::cout << "grid drive: " << truth.size() << " poses, " << visited << " of " << g.nx * g.ny
            << " nodes within " << config.route_tolerance_m << " m, the farthest " << worst << " m\n";
  EXPECT_EQ(visited, g.nx * g.ny);
  // It ends at the last row's far end: an odd number of rows ends on the right.
  const Eigen::Vector2d last = g.Position(g.ny % 2 == 1 ? g.nx - 1 : 0, g.ny - 1);
  EXPECT_LT(std::hypot(truth.back().x_m - last.x(), truth.back().y_m - last.y()), config.route_tolerance_m + 0.01);
  config.drive = "gridd";
  glue::Bus bus2("memq://");
  EXPECT_THROW(SimNode(bus2, config, scene), std::invalid_argument);
}

TEST(SceneFiles, EveryShippedSceneLoadsAndHasAGrid) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(SNAPNAV_CONFIG_DIR "/scenes")) {
    if (e.path().extension() != ".scene") continue;
    const auto scene = LoadSceneFile(e.path().string());
    EXPECT_GT(scene.grid.nx, 0) << e.path();
    EXPECT_FALSE(scene.route.empty()) << e.path();
    ++n;
  }
  EXPECT_GE(n, 5);
  EXPECT_EQ(LoadSceneFile(SceneFilePath("indoor13")).grid.nx, 13);
}

TEST(SceneFiles, ErrorsNameFileAndLine) {
  const std::string path = testing::TempDir() + "/bad.scene";
  std::ofstream(path) << "name bad\ntexture a pattern bricks 1,2,3 1 1 1\nwall 0 0 1 oops 2 a\n";
  try {
    LoadSceneFile(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.scene:3"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "texture a photo does-not-exist.jpg 1 1\n";
  try {
    LoadSceneFile(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("does-not-exist.jpg"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LoadSceneFile("/nonexistent.scene"), std::runtime_error);
}

// Print writes the config in the file's form: read back, it gives the same options, the realistic
// presets and a kidnapping included.
TEST(SimConfig, PrintReadsBackAsTheSameConfig) {
  std::string text;
  {
    std::ifstream in(SNAPNAV_CONFIG_DIR "/sim.ini");
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  auto ini = glue::IniFile::Parse(text, "sim.ini");
  ini.Set("camera", "preset", "realistic", "test");
  ini.Set("laser", "preset", "realistic", "test");
  ini.Set("robot", "kidnap_at_s", "12.5", "test");
  ini.Set("sim", "start_time_s", "1700000000.5", "test");
  ini.Set("sim", "clock_offset_s", "-0.75", "test");
  const SimConfig c = SimConfig::FromIni(ini, "");
  std::ostringstream printed;
  c.Print(printed);
  EXPECT_NE(printed.str().find("[sim]\nscene = indoor13\n"), std::string::npos) << printed.str();
  EXPECT_NE(printed.str().find("; the realistic camera:"), std::string::npos) << printed.str();
  const SimConfig again = SimConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  std::ostringstream printed_again;
  again.Print(printed_again);
  EXPECT_EQ(printed_again.str(), printed.str());
  EXPECT_EQ(again.start_utime, c.start_utime);
  EXPECT_EQ(again.clock_offset_us, -750000);
  EXPECT_EQ(again.seed, c.seed);
  EXPECT_EQ(again.encoding, c.encoding);
  EXPECT_DOUBLE_EQ(again.kidnap.at_s, 12.5);
  EXPECT_NEAR(again.kidnap.to.theta_rad, c.kidnap.to.theta_rad, 1e-12);
  EXPECT_DOUBLE_EQ(again.laser.angle_min_rad, c.laser.angle_min_rad);
  EXPECT_TRUE(again.camera.optics.enabled);
  EXPECT_TRUE(again.laser.faults.enabled);
}

TEST(SimConfig, ShippedConfigLoadsAndBadValuesAreErrors) {
  EXPECT_NO_THROW(ShippedConfig(""));
  EXPECT_THROW(SimConfig::FromIni(glue::IniFile::Parse("[sim]\nscene = x\n", "t.ini"), ""), glue::ConfigError);
  auto c = ShippedConfig("");
  c.command_watchdog_s = -1;
  EXPECT_THROW(c.Validate(), std::invalid_argument);
  for (double factor : {0.0, -1.0, 1000.0, std::nan("")}) {
    c = ShippedConfig("");
    c.realtime_factor = factor;
    EXPECT_THROW(c.Validate(), std::invalid_argument) << factor;
  }
}

// realtime_factor paces simulated time against the wall clock (0.5: half as fast as life) and changes
// nothing else: the messages are those of factor 1, byte for byte.
TEST(SimNode, RealtimeFactorPacesTheRunAndChangesNoMessage) {
  const auto run = [](double factor, double* wall_s) {
    glue::Bus bus("memq://");
    auto config = ShippedConfig("RT_");
    config.realtime = true;
    config.realtime_factor = factor;
    config.duration_s = 0.3;
    const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
    std::vector<std::string> got;
    bus.SubscribeRaw("RT_.*", [&](const void* d, size_t n) {
      got.push_back(bus.current().channel + std::string(static_cast<const char*>(d), n));
    });
    SimNode node(bus, config, scene);
    const int64_t start = glue::MonotonicUtime();
    node.Run(nullptr);
    *wall_s = (glue::MonotonicUtime() - start) * 1e-6;
    while (bus.HandleOnce(0)) {
    }
    return got;
  };
  double wall_half = 0, wall_fast = 0;
  const auto half = run(0.5, &wall_half);
  const auto fast = run(4.0, &wall_fast);
  ASSERT_GT(half.size(), 30u);  // 3 frames, 3 scans, 15 odometry and 15 ground-truth poses
  EXPECT_TRUE(half == fast);
  // 0.3 s of simulated time at half speed: at least 0.6 s of wall time (the last step is due at 0.59 s).
  EXPECT_GE(wall_half, 0.58);
}

TEST(SimConfig, StartTimeNowStampsWithTheWallClockPlusTheOffset) {
  glue::Bus bus("memq://");
  auto config = ShippedConfig("N_");
  config.start_at_wall_clock = true;
  config.clock_offset_us = 2'000'000;
  const auto scene = LoadSceneFile(SceneFilePath("indoor13"));
  const int64_t before = glue::WallUtime();
  SimNode node(bus, config, scene);
  const int64_t after = glue::WallUtime();
  EXPECT_GE(node.start_utime(), before + 2'000'000);
  EXPECT_LE(node.start_utime(), after + 2'000'000);
}

// Every number of the shipped sim.ini made negative or NaN: each error names the file, the line and the
// key.
TEST(SimConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(SNAPNAV_CONFIG_DIR "/sim.ini",
                                                [](const glue::IniFile& ini) { SimConfig::FromIni(ini, ""); }),
            0);
}

// The realistic sensors on the bus: the camera's own JPEG with its (slightly wrong) calibration,
// the same bytes for the same seed, and the faulty laser.
TEST(SimNode, RealisticSensorsPublishTheCamerasJpegAndAFaultyScan) {
  auto run = [](uint64_t seed) {
    glue::Bus bus("memq://");
    glue::IniFile ini = glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini");
    ini.Set("camera", "preset", "realistic", "test");
    ini.Set("laser", "preset", "realistic", "test");
    auto config = SimConfig::FromIni(ini, "R1_");
    config.seed = seed;
    config.duration_s = 0.5;
    const auto scene = LoadSceneFile(SceneFilePath("people11"));
    std::vector<omni_frame_t> raw;
    std::vector<laser_scan_t> scans;
    bus.Subscribe<omni_frame_t>("R1_OMNI_FRAME", [&](const omni_frame_t& m) { raw.push_back(m); });
    bus.Subscribe<laser_scan_t>("R1_LASER_SCAN", [&](const laser_scan_t& m) { scans.push_back(m); });
    SimNode node(bus, config, scene);
    while (node.Step()) {
      while (bus.HandleOnce(0)) {
      }
    }
    return std::make_pair(raw, scans);
  };
  const auto [raw, scans] = run(5);
  ASSERT_EQ(raw.size(), 5u);
  ASSERT_EQ(scans.size(), 5u);
  for (const auto& f : raw) {
    EXPECT_EQ(f.encoding, omni_frame_t::JPEG);
    const cv::Mat img = glue::FrameToImage(f);
    EXPECT_EQ(img.cols, 640);
    EXPECT_EQ(img.rows, 480);
    EXPECT_NE(f.mirror_center_x_px, 320.f);  // the calibration a real camera has: off by a few pixels
  }
  const auto [again, scans_again] = run(5);
  EXPECT_EQ(raw[4].data, again[4].data);
  EXPECT_EQ(scans[4].ranges_m, scans_again[4].ranges_m);
}

// A preset that does not exist: the error names the file, the line and the key.
TEST(SimConfigFile, UnknownPresetsNameFileLineAndKey) {
  const std::string path = SNAPNAV_CONFIG_DIR "/sim.ini";
  for (const std::string section : {"camera", "laser"}) {
    glue::IniFile ini = glue::IniFile::Load(path);
    ini.Set(section, "preset", "fancy", "test");
    try {
      SimConfig::FromIni(ini, "");
      FAIL() << "no error for [" << section << "] preset = fancy";
    } catch (const glue::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path + ":" + std::to_string(ini.KeyLine(section, "preset")) + ": [" + section + "] preset"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("expected clean or realistic"), std::string::npos) << what;
    }
  }
  // The realistic presets load, and take the frames' JPEG quality.
  glue::IniFile ini = glue::IniFile::Load(path);
  ini.Set("camera", "preset", "realistic", "test");
  ini.Set("laser", "preset", "realistic", "test");
  const SimConfig c = SimConfig::FromIni(ini, "");
  EXPECT_TRUE(c.camera.optics.enabled);
  EXPECT_EQ(c.camera.optics.jpeg_quality, c.jpeg_quality);
  EXPECT_TRUE(c.laser.faults.enabled);
  std::ostringstream printed;
  c.Print(printed);
  EXPECT_NE(printed.str().find("auto-exposure on"), std::string::npos) << printed.str();
  EXPECT_NE(printed.str().find("people as legs"), std::string::npos) << printed.str();
}

}  // namespace
}  // namespace snapnav::processes
