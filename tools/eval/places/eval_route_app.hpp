#pragma once
// eval-route (./snapnav eval route) as an app: route following in closed loop (thesis 5.1.2-5.1.3, issue
// 6) with place cells, odometry and homing, beside the same follower on odometry alone (route_eval.hpp).
#include <string>

namespace snapnav::eval {

class EvalRouteApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // The closed-loop runs (place cells and odometry, the odometry-only baseline) and their files.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string scene_name = "indoor13", out_dir, alv = "scale", mask_source, camera;
  std::string sim_config_path = SNAPNAV_CONFIG_DIR "/sim.ini",
              places_config_path = SNAPNAV_CONFIG_DIR "/placecells.ini";
  std::string homing_config_path = SNAPNAV_CONFIG_DIR "/homing.ini";
  std::string navigator_config_path = SNAPNAV_CONFIG_DIR "/navigator.ini";
  std::string arrival;
  int route = 1, laps = 3, seed = 1, cell_step = 1, localize_every = 1, threads = 1;
  double tolerance_m = 0, homing_arrived_rad = 0, max_time_s = 0;
  bool no_homing = false, no_waypoint_cells = false;
};

}  // namespace snapnav::eval
