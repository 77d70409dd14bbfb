#pragma once
// slam-sim-eval as an app: dead reckoning and laser SLAM on a simulated route with ground truth (ATE
// with and without SE(2) alignment, RPE), optionally the run as an LCM log (slam_sim.hpp).
#include <string>

namespace snapnav::eval {

class SlamSimEvalApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // Simulates the run, evaluates both estimators, writes summary.json, the figures and trajectories.csv.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string config_path = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string scene = "corridor", out_dir;
  int laps = 2, seed = -1;
  double duration_s = 0, rpe_delta_m = 1.0;
  bool write_log = false;
};

}  // namespace snapnav::eval
