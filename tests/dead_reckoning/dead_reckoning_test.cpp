// Node test: dead-reckoning on memq:// — publish odometry, handle, assert on the decoded pose.
#include <gtest/gtest.h>

#include <cmath>

#include "dead_reckoning_node.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {
namespace {

odometry_t Odo(int64_t utime, double x, double y, double theta, double dx, double dth) {
  odometry_t o{};
  o.utime = utime;
  o.sensor_name = "test";
  o.x_m = x;
  o.y_m = y;
  o.theta_rad = theta;
  o.delta_x_m = dx;
  o.delta_theta_rad = dth;
  o.delta_t_s = 0.1;
  return o;
}

DeadReckoningConfig TestConfig(const std::string& prefix) {
  return DeadReckoningConfig::FromIni(
      glue::IniFile::Parse("[channels]\nodometry = ODOMETRY\npose = POSE_DEAD_RECKONING\n[dead_reckoning]\n"
                           "translation_noise_m_per_m = 0.05\nrotation_noise_rad_per_rad = 0.05\n"
                           "rotation_noise_rad_per_m = 0.0052\n",
                           "test.ini"),
      prefix);
}

TEST(DeadReckoningNode, IntegratesOdometryAndPublishesPoses) {
  glue::Bus bus("memq://");
  const auto config = TestConfig("T1_");
  DeadReckoningNode node(bus, config);
  std::vector<pose_t> poses;
  bus.Subscribe<pose_t>("T1_POSE_DEAD_RECKONING", [&](const pose_t& p) { poses.push_back(p); });

  bus.Publish("T1_ODOMETRY", Odo(1000, 0, 0, 0, 0, 0));
  for (int i = 1; i <= 10; ++i) bus.Publish("T1_ODOMETRY", Odo(1000 + i * 100000, 0, 0, 0, 0.1, 0));
  bus.Publish("T1_ODOMETRY", Odo(2200000, 0, 0, 0, 0, M_PI / 2));
  for (int i = 1; i <= 5; ++i) bus.Publish("T1_ODOMETRY", Odo(2200000 + i * 100000, 0, 0, 0, 0.1, 0));
  while (bus.HandleOnce(0)) {
  }
  ASSERT_EQ(poses.size(), 17u);
  const pose_t& last = poses.back();
  EXPECT_EQ(last.estimator, "dead_reckoning");
  EXPECT_EQ(last.utime, 2700000);
  EXPECT_NEAR(last.x_m, 1.0, 1e-9);
  EXPECT_NEAR(last.y_m, 0.5, 1e-9);
  EXPECT_NEAR(last.theta_rad, M_PI / 2, 1e-9);
  EXPECT_GT(last.covariance[0], poses[5].covariance[0]);
}

TEST(DeadReckoningNode, BadOdometryIsCountedAndSkipped) {
  glue::Bus bus("memq://");
  DeadReckoningNode node(bus, TestConfig("T2_"));
  int poses = 0;
  bus.Subscribe<pose_t>("T2_POSE_DEAD_RECKONING", [&](const pose_t&) { ++poses; });
  bus.Publish("T2_ODOMETRY", Odo(1000, 0, 0, 0, 0, 0));
  bus.Publish("T2_ODOMETRY", Odo(2000, 0, 0, 0, NAN, 0));  // non-finite
  bus.Publish("T2_ODOMETRY", Odo(500, 0, 0, 0, 0.1, 0));   // goes back in time
  bus.Publish("T2_ODOMETRY", Odo(3000, 0, 0, 0, 0.1, 0));
  while (bus.HandleOnce(0)) {
  }
  EXPECT_EQ(poses, 2);
  EXPECT_EQ(bus.stats().at("T2_ODOMETRY").decode_errors, 2u);  // rejected, with the reason
  EXPECT_EQ(node.rejected().at("bad odometry"), 1);
  EXPECT_EQ(node.rejected().at("odometry back in time"), 1);
}

// One stamp far in the future must not block the node: five messages in a row behind it
// restart the stream.
TEST(DeadReckoningNode, FarFutureStampIsOvercomeAfterFiveMessages) {
  glue::Bus bus("memq://");
  DeadReckoningNode node(bus, TestConfig("T3_"));
  int poses = 0;
  bus.Subscribe<pose_t>("T3_POSE_DEAD_RECKONING", [&](const pose_t&) { ++poses; });
  bus.Publish("T3_ODOMETRY", Odo(1000, 0, 0, 0, 0, 0));
  bus.Publish("T3_ODOMETRY", Odo(int64_t{1} << 61, 0, 0, 0, 0.1, 0));  // far future, accepted
  for (int i = 0; i < 6; ++i) bus.Publish("T3_ODOMETRY", Odo(2000 + i, 0, 0, 0, 0.1, 0));
  bus.Publish("T3_ODOMETRY", Odo(-5, 0, 0, 0, 0.1, 0));                  // implausible
  while (bus.HandleOnce(0)) {
  }
  EXPECT_EQ(poses, 2 + 2);  // the first two, then the fifth behind (restart) and the sixth
  EXPECT_EQ(node.rejected().at("odometry back in time"), 4);
  EXPECT_EQ(node.rejected().at("implausible utime"), 1);
}

TEST(DeadReckoningNode, ConfigMissingKeyIsAnError) {
  EXPECT_THROW(DeadReckoningConfig::FromIni(glue::IniFile::Parse("[channels]\nodometry = O\n", "x.ini"), ""),
               glue::ConfigError);
}

}  // namespace
}  // namespace snapnav::processes
