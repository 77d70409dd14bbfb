// navigator: route following with place-cell fixes, odometry and homing; publishes drive commands.
#include <iostream>
#include <limits>

#include "navigator_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/navigator.ini";
  std::string route, fixes;
  constexpr int kUnset = std::numeric_limits<int>::min();
  int laps = kUnset;
  glue::Flags flags("navigator",
                    "Route following (thesis 5.1.2-5.1.3): tracks the pose from ODOMETRY and place-cell fixes\n"
                    "(POSE_PLACE_CELLS), follows the route of waypoints (ROUTE, or [route] of the config: the thesis'\n"
                    "figure 5.5 routes scaled to a square), steers the final approach by HOMING_VECTOR, and publishes\n"
                    "DRIVE_COMMAND (one per odometry message while a route is set) and NAVIGATOR_STATUS.");
  flags.AddCommon(&common);
  flags.AddString("route", &route, "thesis1 | thesis2 | none: overrides [route] route");
  flags.AddInt("laps", &laps, "finish after this many laps, 0: no limit (overrides [route] laps)");
  flags.AddString("fixes", &fixes,
                  "pose_t channel of the fixes (overrides [channels] pose; --channel-prefix applies): e.g. POSE_EKF "
                  "to drive on fused SLAM's pose while a place-cell memory is explored");
  if (!flags.Parse(argc, argv)) return 0;
  auto ini = glue::IniFile::Load(common.config);
  auto config = processes::NavigatorConfig::FromIni(ini, common.channel_prefix);
  if (!fixes.empty()) config.pose_channel = common.channel_prefix + fixes;
  if (laps != kUnset) {
    if (laps < 0) throw glue::FlagError("--laps must be >= 0 (0: no limit)");
    config.route_laps = laps;
  }
  if (!route.empty()) {
    if (route != "none" && !nav::ParseThesisRoute(route)) {
      throw glue::FlagError("--route must be thesis1, thesis2 or none, not '" + route + "'");
    }
    config.route_source = route;
    if (const auto r = config.ConfiguredRoute()) r->Validate();
  }
  return glue::RunNode<processes::NavigatorNode>(
      "navigator", common.config, config, common.lcm_url,
      [&](const processes::NavigatorNode& node, const glue::Bus& bus) {
        return "odometry " + config.odometry_channel + ", fixes " + config.pose_channel + ", homing " +
               config.homing_vector_channel + ", routes " + config.route_channel + " -> " +
               config.drive_command_channel + ", " + config.status_channel + " (" + bus.url() + ")" +
               (node.follower().has_route() ? ", route " + node.follower().route().name : ", waiting for a route");
      });
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
