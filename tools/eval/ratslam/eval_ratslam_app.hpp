#pragma once
// eval-ratslam (./snapnav eval ratslam) as an app: RatSLAM on a simulated route with ground truth
// (ratslam_eval.hpp), or --sweep's [ratslam] configurations on the same simulated run.
#include <string>

namespace snapnav::eval {

class EvalRatSlamApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // One run (or --sweep's configurations on the same simulated run) and its files.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string sim_config = SNAPNAV_CONFIG_DIR "/sim.ini", ratslam_config = SNAPNAV_CONFIG_DIR "/ratslam.ini";
  std::string scene = "indoor13", out_dir, sweep, mask, camera;
  int laps = 3, seed = -1;
  double duration_s = 0, rpe_delta_m = 1.0;
  bool raw = false, no_people = false;
};

}  // namespace snapnav::eval
