// Node tests: the navigator process on memq:// — a route, odometry and place-cell fixes go in,
// drive commands and statuses come out; malformed messages are counted, never fatal.
#include "navigator_node.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "../support/config_errors.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/conversions.hpp"

namespace snapnav::processes {
namespace {

const std::string kShippedConfig = std::string(SNAPNAV_CONFIG_DIR) + "/navigator.ini";

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The shipped config with `key = value` of [section] replaced. Fails the test when the key is missing.
std::string Edit(const std::string& text, const std::string& section, const std::string& key,
                 const std::string& value) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, current;
  bool found = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '[') current = line.substr(1, line.find(']') - 1);
    if (current == section && !line.empty() && line[0] != '#' && line[0] != ';' &&
        line.substr(0, line.find_first_of(" \t=")) == key) {
      found = true;
      out << key << " = " << value << "\n";
      continue;
    }
    out << line << "\n";
  }
  EXPECT_TRUE(found) << "[" << section << "] " << key << " not in the shipped config";
  return out.str();
}

struct Override {
  const char* section;
  const char* key;
  const char* value;
};

NavigatorConfig Config(const std::string& prefix, std::initializer_list<Override> overrides) {
  std::string text = ReadText(kShippedConfig);
  for (const auto& o : overrides) text = Edit(text, o.section, o.key, o.value);
  return NavigatorConfig::FromIni(glue::IniFile::Parse(text, "test.ini"), prefix);
}

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

odometry_t Odometry(int64_t utime, const nav::Pose2& cumulative, const nav::Pose2& delta) {
  return glue::ToOdometryMsg(utime, "test", cumulative, delta, 0.02);
}

pose_t Fix(int64_t utime, const nav::Pose2& pose, double sigma_m = 0.05) {
  return glue::ToPoseMsg(utime, "place_cells", "map", pose,
                         Eigen::Vector3d(sigma_m * sigma_m, sigma_m * sigma_m, 0.01).asDiagonal());
}

waypoint_route_t RouteMsg(const std::vector<Eigen::Vector2d>& waypoints, int64_t utime = 1) {
  waypoint_route_t r{};
  r.utime = utime;
  r.name = "test_route";
  r.loop = false;
  r.tolerance_m = 0.05f;
  r.nwaypoints = static_cast<int32_t>(waypoints.size());
  for (const auto& w : waypoints) {
    r.x_m.push_back(w.x());
    r.y_m.push_back(w.y());
  }
  return r;
}

TEST(NavigatorConfig, ShippedConfigLoadsAndPrintsBack) {
  const auto c = NavigatorConfig::FromIni(glue::IniFile::Load(kShippedConfig), "");
  EXPECT_EQ(c.odometry_channel, "ODOMETRY");
  EXPECT_EQ(c.status_channel, "NAVIGATOR_STATUS");
  ASSERT_TRUE(c.ConfiguredRoute());
  EXPECT_EQ(c.ConfiguredRoute()->waypoints.size(), 6u);
  std::ostringstream printed;
  c.Print(printed);
  const auto again = NavigatorConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  EXPECT_EQ(again.route_source, c.route_source);
  EXPECT_NEAR(again.follower.turn_in_place_rad, c.follower.turn_in_place_rad, 1e-9);
  EXPECT_NEAR(again.tracker.gate_chi2, c.tracker.gate_chi2, 1e-12);
  EXPECT_EQ(again.follower.arrival, c.follower.arrival);
}

TEST(NavigatorConfig, BadValuesAreConfigErrors) {
  EXPECT_THROW(Config("", {{"route", "route", "thesis3"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"follower", "arrival", "sometimes"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"follower", "homing_speed_mps", "5"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"route", "first_waypoint", "6"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"channels", "status", "ODOMETRY"}}), glue::ConfigError);
  std::string text = ReadText(kShippedConfig) + "\n[navigator]\nstatus_period = 1\n";
  EXPECT_THROW(NavigatorConfig::FromIni(glue::IniFile::Parse(text, "t"), ""), glue::ConfigError);
}

// A route from ROUTE, a place-cell fix, then odometry: the command turns towards the waypoint.
TEST(NavigatorNode, DriveCommandTurnsTowardsTheNextWaypoint) {
  glue::Bus bus("memq://");
  NavigatorNode node(bus, Config("N1_", {{"route", "route", "none"}, {"navigator", "status_period_s", "0"}}));
  std::vector<drive_command_t> commands;
  std::vector<navigator_status_t> statuses;
  bus.Subscribe<drive_command_t>("N1_DRIVE_COMMAND", [&](const drive_command_t& m) { commands.push_back(m); });
  bus.Subscribe<navigator_status_t>("N1_NAVIGATOR_STATUS", [&](const navigator_status_t& m) { statuses.push_back(m); });

  // No route yet: odometry gives no command.
  bus.Publish("N1_ODOMETRY", Odometry(1000, {0, 0, 0}, {0, 0, 0}));
  HandleAll(bus);
  EXPECT_TRUE(commands.empty());

  // A route to (1, 2) then (3, 2); the robot at (1, 1) facing +x: the waypoint is on its left.
  bus.Publish("N1_ROUTE", RouteMsg({{1, 2}, {3, 2}}));
  bus.Publish("N1_ODOMETRY", Odometry(2000, {0, 0, 0}, {0, 0, 0}));  // before any fix: stand still
  bus.Publish("N1_POSE_PLACE_CELLS", Fix(2500, {1, 1, 0}));
  bus.Publish("N1_ODOMETRY", Odometry(3000, {0, 0, 0}, {0, 0, 0}));
  HandleAll(bus);
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(commands[0].utime, 2000);
  EXPECT_EQ(commands[0].linear_velocity_mps, 0);
  EXPECT_EQ(commands[0].angular_velocity_radps, 0);
  EXPECT_EQ(commands[1].utime, 3000);
  EXPECT_EQ(commands[1].source, "navigator");
  EXPECT_EQ(commands[1].linear_velocity_mps, 0);       // turn on the spot first
  EXPECT_GT(commands[1].angular_velocity_radps, 0.3);  // to the left
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.front().state, navigator_status_t::WAITING_FOR_POSE);
  const navigator_status_t& s = statuses.back();
  EXPECT_EQ(s.state, navigator_status_t::TURNING);
  EXPECT_EQ(s.route_name, "test_route");
  EXPECT_EQ(s.nwaypoints, 2);
  EXPECT_EQ(s.waypoint_index, 0);
  EXPECT_NEAR(s.distance_to_waypoint_m, 1.0, 1e-6);
  EXPECT_NEAR(s.heading_error_rad, M_PI / 2, 1e-6);
  EXPECT_EQ(s.fixes_accepted, 1);
  EXPECT_EQ(node.fixes().at("initialized"), 1);

  // Turned to face it (odometry says +90 deg): drive forward.
  bus.Publish("N1_ODOMETRY", Odometry(4000, {0, 0, M_PI / 2}, {0, 0, M_PI / 2}));
  HandleAll(bus);
  ASSERT_EQ(commands.size(), 3u);
  EXPECT_GT(commands[2].linear_velocity_mps, 0.1);
  EXPECT_NEAR(commands[2].angular_velocity_radps, 0, 1e-6);

  // Driven 1 m forward: waypoint 0 is reached, the next one (3, 2) is on the right.
  bus.Publish("N1_ODOMETRY", Odometry(5000, {0, 1, M_PI / 2}, {1, 0, 0}));
  HandleAll(bus);
  ASSERT_EQ(commands.size(), 4u);
  EXPECT_EQ(node.follower().waypoint(), 1);
  EXPECT_EQ(node.follower().arrivals(), 1);
  EXPECT_EQ(commands[3].linear_velocity_mps, 0);
  EXPECT_LT(commands[3].angular_velocity_radps, -0.3);
  EXPECT_EQ(node.rejected_total(), 0);
}

TEST(NavigatorNode, ConfiguredThesisRouteDrivesOnOdometryAfterTheFirstFix) {
  glue::Bus bus("memq://");
  NavigatorNode node(bus, Config("N2_", {}));  // thesis1 on indoor13's square, from waypoint 1
  std::vector<drive_command_t> commands;
  bus.Subscribe<drive_command_t>("N2_DRIVE_COMMAND", [&](const drive_command_t& m) { commands.push_back(m); });
  const auto& route = node.follower().route();
  ASSERT_EQ(route.waypoints.size(), 6u);
  EXPECT_EQ(node.follower().waypoint(), 1);
  // At the start (100, 0) facing the second waypoint (54, 81): drive.
  const Eigen::Vector2d to = route.waypoints[1] - route.waypoints[0];
  bus.Publish("N2_POSE_PLACE_CELLS",
              Fix(100, {route.waypoints[0].x(), route.waypoints[0].y(), std::atan2(to.y(), to.x())}));
  bus.Publish("N2_ODOMETRY", Odometry(200, {0, 0, 0}, {0, 0, 0}));
  HandleAll(bus);
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_NEAR(commands[0].linear_velocity_mps, node.follower().options().max_linear_mps, 1e-9);
}

TEST(NavigatorNode, FixOutlierIsGatedAndHomingSteersTheFinalApproach) {
  glue::Bus bus("memq://");
  NavigatorNode node(bus, Config("N3_", {{"route", "route", "none"},
                                         {"homing", "arrived_magnitude", "0.05"},
                                         {"follower", "arrival", "homing"},
                                         {"follower", "homing_max_deviation_deg", "180"}}));
  std::vector<drive_command_t> commands;
  bus.Subscribe<drive_command_t>("N3_DRIVE_COMMAND", [&](const drive_command_t& m) { commands.push_back(m); });
  bus.Publish("N3_ROUTE", RouteMsg({{1.2, 1}, {3, 3}}));
  bus.Publish("N3_POSE_PLACE_CELLS", Fix(1000, {1, 1, 0}));
  bus.Publish("N3_POSE_PLACE_CELLS", Fix(1100, {3, 0, 0}, 0.02));  // a far cell that looked alike
  // Homing says the snapshot is to the right.
  homing_vector_t h{};
  h.utime = 1150;
  h.valid = true;
  h.direction_rad = -M_PI / 2;
  h.magnitude = 0.3f;
  bus.Publish("N3_HOMING_VECTOR", h);
  bus.Publish("N3_ODOMETRY", Odometry(1200, {0, 0, 0}, {0, 0, 0}));
  HandleAll(bus);
  EXPECT_EQ(node.fixes().at("gate"), 1);
  EXPECT_NEAR(node.tracker().pose().x_m, 1, 1e-9);
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_LT(commands[0].angular_velocity_radps, 0);  // the homing direction, not the estimate's straight ahead
  EXPECT_EQ(node.homing_used(), 1);
  // The homing magnitude falls below arrived_magnitude: arrived.
  h.utime = 1300;
  h.magnitude = 0.01f;
  bus.Publish("N3_HOMING_VECTOR", h);
  bus.Publish("N3_ODOMETRY", Odometry(1400, {0, 0, 0}, {0, 0, 0}));
  HandleAll(bus);
  EXPECT_EQ(node.follower().waypoint(), 1);
  EXPECT_EQ(node.follower().arrivals(), 1);
}

TEST(NavigatorNode, MalformedMessagesAreCountedWithReasons) {
  glue::Bus bus("memq://");
  NavigatorNode node(bus, Config("N4_", {{"route", "route", "none"}}));
  int commands = 0;
  bus.Subscribe<drive_command_t>("N4_DRIVE_COMMAND", [&](const drive_command_t&) { ++commands; });
  bus.Publish("N4_POSE_PLACE_CELLS", Fix(100, {NAN, 0, 0}));
  pose_t bad_cov = Fix(100, {0, 0, 0});
  bad_cov.covariance[0] = -1;
  bus.Publish("N4_POSE_PLACE_CELLS", bad_cov);
  bus.Publish("N4_ROUTE", RouteMsg({}));
  waypoint_route_t nan_route = RouteMsg({{0, 0}, {1, 1}});
  nan_route.y_m[1] = NAN;
  bus.Publish("N4_ROUTE", nan_route);
  homing_vector_t h{};
  h.valid = true;
  h.direction_rad = NAN;
  bus.Publish("N4_HOMING_VECTOR", h);
  bus.Publish("N4_ODOMETRY", Odometry(1000, {0, 0, 0}, {0, 0, 0}));
  bus.Publish("N4_ODOMETRY", Odometry(500, {0, 0, 0}, {0, 0, 0}));  // back in time
  bus.PublishRaw("N4_ODOMETRY", "junk", 4);                         // not an odometry_t
  HandleAll(bus);
  EXPECT_EQ(node.rejected().at("non-finite pose"), 1);
  EXPECT_EQ(node.rejected().at("negative variance"), 1);
  EXPECT_EQ(node.rejected().at("empty route"), 1);
  EXPECT_EQ(node.rejected().at("invalid route"), 1);
  EXPECT_EQ(node.rejected().at("non-finite homing vector"), 1);
  EXPECT_EQ(node.rejected().at("odometry back in time"), 1);
  EXPECT_EQ(node.rejected_total(), 6);
  EXPECT_FALSE(node.tracker().initialized());
  EXPECT_FALSE(node.follower().has_route());
  EXPECT_EQ(commands, 0);
  EXPECT_EQ(bus.stats().at("N4_ODOMETRY").decode_errors, 2u);  // back in time + junk
}

// Every number of the shipped navigator.ini made negative or NaN: each error names the file, the line
// and the key.
TEST(NavigatorConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(kShippedConfig,
                                                [](const glue::IniFile& ini) { NavigatorConfig::FromIni(ini, ""); }),
            0);
}

}  // namespace
}  // namespace snapnav::processes
