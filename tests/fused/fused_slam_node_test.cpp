// Node test: fused-slam on memq:// — odometry and scans of a ray-cast room with place-cell poses;
// the fused pose on every scan and visual measurement (their utimes), the status, a kidnapping
// relocalised through the bus, and bad input counted by reason, never a crash.
#include "fused_slam_node.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "snapnav/fused_slam_status_t.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/laser_scan_checks.hpp"
#include "snapnav/point_map_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {
namespace {

constexpr double kRoomW = 6.0, kRoomH = 4.0;  // [0, 6] x [0, 4] m
constexpr int kBeams = 681;
constexpr double kAngleMin = -120.0 * M_PI / 180.0;
constexpr double kAngleIncrement = 240.0 * M_PI / 180.0 / (kBeams - 1);
constexpr double kRangeMin = 0.02, kRangeMax = 5.6;
constexpr int64_t kT0 = 1'700'000'000'000'000;

std::string ShippedText() {
  std::ifstream in(SNAPNAV_CONFIG_DIR "/fused_slam.ini");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

FusedSlamConfig ShippedConfig(const std::string& prefix) {
  return FusedSlamConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/fused_slam.ini"), prefix);
}

// The shipped text with the line starting with `key =` replaced by `replacement` (empty: removed).
std::string Edited(const std::string& key, const std::string& replacement) {
  std::istringstream in(ShippedText());
  std::ostringstream out;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key + " =", 0) == 0) {
      if (!replacement.empty()) out << replacement << "\n";
      continue;
    }
    out << line << "\n";
  }
  return out.str();
}

std::vector<float> CastRoom(const nav::Pose2& robot, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.005);
  const Eigen::Vector2d p = robot.Transform({0.1, 0.0});
  std::vector<float> ranges(kBeams);
  for (int i = 0; i < kBeams; ++i) {
    const double a = robot.theta_rad + kAngleMin + kAngleIncrement * i;
    const double dx = std::cos(a), dy = std::sin(a);
    double t = std::numeric_limits<double>::infinity();
    if (dx > 1e-12) t = std::min(t, (kRoomW - p.x()) / dx);
    if (dx < -1e-12) t = std::min(t, -p.x() / dx);
    if (dy > 1e-12) t = std::min(t, (kRoomH - p.y()) / dy);
    if (dy < -1e-12) t = std::min(t, -p.y() / dy);
    ranges[i] = t >= kRangeMax ? static_cast<float>(kRangeMax) : static_cast<float>(t + noise(*rng));
  }
  return ranges;
}

laser_scan_t Scan(int64_t utime, std::vector<float> ranges) {
  laser_scan_t s{};
  s.utime = utime;
  s.sensor_name = "test";
  s.sensor_x_m = 0.1f;
  s.angle_min_rad = static_cast<float>(kAngleMin);
  s.angle_increment_rad = static_cast<float>(kAngleIncrement);
  s.range_min_m = static_cast<float>(kRangeMin);
  s.range_max_m = static_cast<float>(kRangeMax);
  s.nranges = static_cast<int32_t>(ranges.size());
  s.ranges_m = std::move(ranges);
  s.nintensities = 0;
  return s;
}

odometry_t Odo(int64_t utime, const nav::Pose2& cumulative, const nav::Pose2& delta) {
  return glue::ToOdometryMsg(utime, "test", cumulative, delta, 0.1);
}

pose_t Visual(int64_t utime, const nav::Pose2& pose, double sigma_m = 0.1, double sigma_rad = 0.05) {
  return glue::ToPoseMsg(utime, "place_cells", "map", pose,
                         Eigen::Vector3d(sigma_m * sigma_m, sigma_m * sigma_m, sigma_rad * sigma_rad).asDiagonal());
}

void Drain(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

struct Collector {
  std::vector<pose_t> poses;
  std::vector<fused_slam_status_t> statuses;
  std::vector<point_map_t> maps;
  Collector(glue::Bus& bus, const std::string& prefix) {
    bus.Subscribe<pose_t>(prefix + "POSE_EKF", [this](const pose_t& p) { poses.push_back(p); });
    bus.Subscribe<fused_slam_status_t>(prefix + "FUSED_SLAM_STATUS",
                                       [this](const fused_slam_status_t& s) { statuses.push_back(s); });
    bus.Subscribe<point_map_t>(prefix + "POINT_MAP_FUSED", [this](const point_map_t& m) { maps.push_back(m); });
  }
};

TEST(FusedSlamConfig, ShippedConfigLoadsAndMissingOrUnknownKeysAreErrors) {
  const FusedSlamConfig c = ShippedConfig("P_");
  EXPECT_EQ(c.pose_channel, "P_POSE_EKF");
  EXPECT_EQ(c.visual_channel, "P_POSE_PLACE_CELLS");
  EXPECT_EQ(c.start, FusedStart::kOdometry);
  EXPECT_NEAR(c.options.relocalize_sigma_theta_rad, 5.0 * M_PI / 180, 1e-9);
  // Printed back, it reads the same.
  std::ostringstream printed;
  c.Print(printed);
  const FusedSlamConfig again = FusedSlamConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  EXPECT_EQ(again.pose_channel, "P_POSE_EKF");
  EXPECT_EQ(again.options.relocalize_after, c.options.relocalize_after);
  EXPECT_EQ(again.options.laser.match_distance_m, c.options.laser.match_distance_m);
  // The people test: shipped = libnav defaults, printed back the same.
  const nav::FusedSlamOptions d;
  EXPECT_DOUBLE_EQ(c.options.dynamic_explain_m, d.dynamic_explain_m);
  EXPECT_DOUBLE_EQ(c.options.dynamic_max_behind_m, d.dynamic_max_behind_m);
  EXPECT_DOUBLE_EQ(c.options.dynamic_map_age_s, d.dynamic_map_age_s);
  EXPECT_DOUBLE_EQ(c.options.dynamic_max_fraction, d.dynamic_max_fraction);
  EXPECT_DOUBLE_EQ(c.options.occlusion_fix_inflation, d.occlusion_fix_inflation);
  EXPECT_DOUBLE_EQ(again.options.dynamic_explain_m, c.options.dynamic_explain_m);
  EXPECT_DOUBLE_EQ(again.options.dynamic_map_age_s, c.options.dynamic_map_age_s);
  EXPECT_THROW(FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("dynamic_map_age_s", ""), "f.ini"), ""),
               glue::ConfigError);
  EXPECT_THROW(FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("dynamic_max_fraction", "dynamic_max_fraction = 2"), "f.ini"), ""),
               glue::ConfigError);
  try {
    FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("gate_chi2", ""), "f.ini"), "");
    FAIL() << "a missing key must be an error";
  } catch (const glue::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gate_chi2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("gate_chi2", "gate_chi2 = 11\ngate = 3"), "f.ini"), ""),
               glue::ConfigError);
  EXPECT_THROW(FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("start", "start = somewhere"), "f.ini"), ""),
               glue::ConfigError);
  EXPECT_THROW(FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("gate_chi2", "gate_chi2 = -1"), "f.ini"), ""),
               glue::ConfigError);
  EXPECT_THROW(FusedSlamConfig::FromIni(glue::IniFile::Parse(Edited("match_distance_m", ""), "f.ini"), ""),
               glue::ConfigError);  // the [laser_slam] section is required too
}

// The robot drives along x in the room at (1 + 0.05 k, 2); the odometry reads 10 % too far. Visual
// fixes at the truth every 5th scan are accepted; every scan and every fix gives a fused pose.
TEST(FusedSlamNode, PublishesAPosePerScanAndPerVisualMeasurementWithTheirUtimes) {
  glue::Bus bus("memq://");
  FusedSlamNode node(bus, ShippedConfig("F1_"));
  Collector got(bus, "F1_");
  std::mt19937 rng(3);
  nav::Pose2 odom{1.0, 2.0, 0.0};
  bus.Publish("F1_ODOMETRY", Odo(kT0, odom, {}));
  int visual_sent = 0;
  for (int k = 0; k < 40; ++k) {
    const int64_t t = kT0 + k * 100000;
    if (k > 0) {
      odom = odom.Compose({0.055, 0.0, 0.0});
      bus.Publish("F1_ODOMETRY", Odo(t, odom, {0.055, 0.0, 0.0}));
    }
    const nav::Pose2 truth{1.0 + 0.05 * k, 2.0, 0.0};
    bus.Publish("F1_LASER_SCAN", Scan(t, CastRoom(truth, &rng)));
    if (k % 5 == 4) {
      bus.Publish("F1_POSE_PLACE_CELLS", Visual(t - 50000, {truth.x_m - 0.025, 2.0, 0.0}));  // 50 ms old
      ++visual_sent;
    }
    Drain(bus);
  }
  ASSERT_NE(node.slam(), nullptr);
  EXPECT_EQ(node.updates(), 40);
  EXPECT_EQ(node.visual_used(), visual_sent);
  EXPECT_EQ(node.slam()->accepted(), visual_sent);
  EXPECT_EQ(node.slam()->rejected(), 0);
  ASSERT_EQ(got.poses.size(), static_cast<size_t>(40 + visual_sent));
  int visual_poses = 0;
  for (const auto& p : got.poses) {
    EXPECT_EQ(p.estimator, "fused_slam");
    EXPECT_EQ(p.frame, "map");
    if ((p.utime - kT0) % 100000 == 50000) ++visual_poses;  // stamped with the visual measurement's utime
  }
  EXPECT_EQ(visual_poses, visual_sent);
  // The last one is the fix's (50 ms before the last scan), the one before it the last scan's: both on
  // the truth, not on the odometry (+0.2 m by then).
  ASSERT_EQ(got.poses.back().utime, kT0 + 39 * 100000 - 50000);
  EXPECT_NEAR(got.poses.back().x_m, 1.0 + 0.05 * 39 - 0.025, 0.05);
  const pose_t& last_scan = got.poses[got.poses.size() - 2];
  ASSERT_EQ(last_scan.utime, kT0 + 39 * 100000);
  EXPECT_NEAR(last_scan.x_m, 1.0 + 0.05 * 39, 0.05);
  EXPECT_NEAR(last_scan.y_m, 2.0, 0.03);
  // Statuses: one per visual measurement and every 10th scan.
  EXPECT_EQ(got.statuses.size(), static_cast<size_t>(visual_sent + 4));
  EXPECT_EQ(got.statuses.back().state, fused_slam_status_t::TRACKING);
  EXPECT_EQ(got.statuses.back().visual_accepted, visual_sent);
  EXPECT_FALSE(got.maps.empty());
  EXPECT_EQ(got.maps.back().estimator, "fused_slam");
}

// The filter is at (1, 2); the robot stands at (5, 2) (carried off before the first scan it sees
// there). Consistent visual fixes at (5, 2) are rejected, then relocalise it after
// relocalize_after of them; the map is protected meanwhile.
TEST(FusedSlamNode, RelocalisesAfterAgreeingRejectedVisualMeasurements) {
  glue::Bus bus("memq://");
  FusedSlamConfig config = ShippedConfig("F2_");
  config.options.suspect_after = 1;  // the map protection (off in the shipped config) on
  FusedSlamNode node(bus, config);
  Collector got(bus, "F2_");
  std::mt19937 rng(5);
  bus.Publish("F2_ODOMETRY", Odo(kT0, {1.0, 2.0, 0.0}, {}));
  bus.Publish("F2_LASER_SCAN", Scan(kT0, CastRoom({1.0, 2.0, 0.0}, &rng)));
  Drain(bus);
  const size_t map_before = node.slam()->map().size();
  for (int k = 1; k <= config.options.relocalize_after; ++k) {
    const int64_t t = kT0 + k * 500000;
    bus.Publish("F2_ODOMETRY", Odo(t, {1.0, 2.0, 0.0}, {}));
    bus.Publish("F2_POSE_PLACE_CELLS", Visual(t, {5.0, 2.0, 0.0}));
    Drain(bus);
    if (k < config.options.relocalize_after) {
      EXPECT_EQ(got.statuses.back().last_outcome, fused_slam_status_t::REJECTED);
      EXPECT_EQ(got.statuses.back().state, fused_slam_status_t::SUSPECT);
      EXPECT_EQ(got.statuses.back().agreeing_rejections, k);
      bus.Publish("F2_LASER_SCAN", Scan(t, CastRoom({5.0, 2.0, 0.0}, &rng)));
      Drain(bus);
    }
  }
  EXPECT_EQ(got.statuses.back().last_outcome, fused_slam_status_t::RELOCALIZED);
  EXPECT_EQ(got.statuses.back().relocalizations, 1);
  EXPECT_EQ(got.statuses.back().state, fused_slam_status_t::TRACKING);
  EXPECT_NEAR(got.poses.back().x_m, 5.0, 0.05);
  EXPECT_EQ(node.slam()->map().size(), map_before);  // scans while suspect did not map
  EXPECT_GE(node.slam()->unmapped_scans(), 1);
  // After it the scans at (5, 2) match the map (the room is the same) and the pose holds.
  bus.Publish("F2_LASER_SCAN", Scan(kT0 + 5'000'000, CastRoom({5.0, 2.0, 0.0}, &rng)));
  Drain(bus);
  EXPECT_NEAR(got.poses.back().x_m, 5.0, 0.05);
  EXPECT_NEAR(got.poses.back().y_m, 2.0, 0.05);
}

TEST(FusedSlamNode, StartsAtTheFirstVisualFixWhenConfiguredSo) {
  glue::Bus bus("memq://");
  FusedSlamConfig config = ShippedConfig("F3_");
  config.start = FusedStart::kVisual;
  FusedSlamNode node(bus, config);
  Collector got(bus, "F3_");
  std::mt19937 rng(7);
  // Odometry in its own frame (origin), scans: nothing happens before the first fix.
  bus.Publish("F3_ODOMETRY", Odo(kT0, {}, {}));
  bus.Publish("F3_ODOMETRY", Odo(kT0 + 100000, {}, {}));
  bus.Publish("F3_LASER_SCAN", Scan(kT0 + 100000, CastRoom({2.0, 1.0, 0.5}, &rng)));
  Drain(bus);
  EXPECT_EQ(node.slam(), nullptr);
  EXPECT_EQ(node.skipped("waiting for a visual fix"), 2);
  EXPECT_TRUE(got.poses.empty());
  bus.Publish("F3_POSE_PLACE_CELLS", Visual(kT0 + 150000, {2.0, 1.0, 0.5}, 0.001, 0.001));
  bus.Publish("F3_ODOMETRY", Odo(kT0 + 200000, {}, {}));
  bus.Publish("F3_LASER_SCAN", Scan(kT0 + 200000, CastRoom({2.0, 1.0, 0.5}, &rng)));
  Drain(bus);
  ASSERT_NE(node.slam(), nullptr);
  ASSERT_EQ(got.poses.size(), 2u);
  EXPECT_NEAR(got.poses.back().x_m, 2.0, 1e-6);
  EXPECT_NEAR(got.poses.back().theta_rad, 0.5, 1e-6);
  // The start covariance is the fix's, floored by min_fix_sigma_xy_m (the map's offset from the
  // world), plus the laser's initial uncertainty relative to its own map.
  const double floor = config.options.min_fix_sigma_xy_m, laser = config.options.laser.initial_sigma_xy_m;
  EXPECT_NEAR(got.poses.front().covariance[0], floor * floor + laser * laser, 1e-9);
}

TEST(FusedSlamNode, BadInputIsCountedByReasonNeverACrash) {
  glue::Bus bus("memq://");
  FusedSlamNode node(bus, ShippedConfig("F4_"));
  Collector got(bus, "F4_");
  std::mt19937 rng(9);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bus.Publish("F4_ODOMETRY", Odo(kT0, {1.0, 2.0, 0.0}, {}));
  bus.Publish("F4_LASER_SCAN", Scan(kT0, CastRoom({1.0, 2.0, 0.0}, &rng)));
  // Visual poses: NaN, NaN covariance, a negative variance, no covariance (unknown).
  bus.Publish("F4_POSE_PLACE_CELLS", Visual(kT0, {nan, 2.0, 0.0}));
  pose_t bad_cov = Visual(kT0, {1.0, 2.0, 0.0});
  bad_cov.covariance[4] = nan;
  bus.Publish("F4_POSE_PLACE_CELLS", bad_cov);
  bad_cov.covariance[4] = -0.01;
  bus.Publish("F4_POSE_PLACE_CELLS", bad_cov);
  pose_t unknown = Visual(kT0, {1.0, 2.0, 0.0});
  for (double& c : unknown.covariance) c = 0;
  bus.Publish("F4_POSE_PLACE_CELLS", unknown);
  // Scans: the shared checks (no ranges, too many beams, bad angles, bad range limits, bad sensor pose).
  bus.Publish("F4_LASER_SCAN", Scan(kT0 + 100000, {}));
  bus.Publish("F4_LASER_SCAN", Scan(kT0 + 100000, std::vector<float>(glue::kMaxLaserBeams + 1, 1.0f)));
  laser_scan_t s = Scan(kT0 + 100000, CastRoom({1.0, 2.0, 0.0}, &rng));
  s.angle_increment_rad = 0;
  bus.Publish("F4_LASER_SCAN", s);
  s = Scan(kT0 + 100000, CastRoom({1.0, 2.0, 0.0}, &rng));
  s.range_max_m = static_cast<float>(nan);
  bus.Publish("F4_LASER_SCAN", s);
  s = Scan(kT0 + 100000, CastRoom({1.0, 2.0, 0.0}, &rng));
  s.sensor_theta_rad = static_cast<float>(nan);
  bus.Publish("F4_LASER_SCAN", s);
  // Every beam at max range: well formed, nothing seen: no update, the pose is still published.
  bus.Publish("F4_LASER_SCAN", Scan(kT0 + 200000, std::vector<float>(kBeams, static_cast<float>(kRangeMax))));
  // Odometry with a NaN increment; a payload that is not an odometry_t.
  bus.Publish("F4_ODOMETRY", Odo(kT0 + 300000, {1.0, 2.0, 0.0}, {nan, 0.0, 0.0}));
  const std::string garbage = "not a message";
  bus.PublishRaw("F4_ODOMETRY", garbage.data(), garbage.size());
  Drain(bus);
  EXPECT_EQ(node.skipped("non-finite visual pose"), 1);
  EXPECT_EQ(node.skipped("bad visual covariance"), 2);
  EXPECT_EQ(node.skipped("visual pose without covariance"), 1);
  EXPECT_EQ(node.skipped("no ranges"), 1);
  EXPECT_EQ(node.skipped("too many beams"), 1);
  EXPECT_EQ(node.skipped("bad angles"), 1);
  EXPECT_EQ(node.skipped("bad range limits"), 1);
  EXPECT_EQ(node.skipped("bad sensor pose"), 1);
  EXPECT_EQ(node.skipped("no valid points"), 1);
  EXPECT_EQ(node.skipped("non-finite odometry"), 1);
  EXPECT_EQ(node.internal_errors(), 0);
  EXPECT_EQ(node.visual_used(), 0);
  EXPECT_EQ(got.poses.size(), 2u);  // the good scan and the empty one
  EXPECT_GE(bus.stats().at("F4_ODOMETRY").decode_errors, 2u);  // the NaN increment and the garbage
  EXPECT_EQ(bus.stats().at("F4_POSE_PLACE_CELLS").decode_errors, 3u);
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("skipped (bad visual covariance): 2"), std::string::npos) << report.str();
}

}  // namespace
}  // namespace snapnav::processes
