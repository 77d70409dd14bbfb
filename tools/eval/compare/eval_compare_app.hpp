#pragma once
// eval-compare (./snapnav eval compare) as an app: dead reckoning, laser-only SLAM, RatSLAM and fused
// visual + laser SLAM on the same simulated runs with ground truth (issue 8; slam_compare.hpp), and the
// laser methods on recorded logs (--log).
#include <string>

#include "compare_config.hpp"
#include "slam_compare.hpp"

namespace snapnav::eval {

// Simulated seconds of the standard set's kidnapped corridor run (--kidnap-run-s).
constexpr double kKidnapRunS = 120.0;

class EvalCompareApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // Every run of the set (and --log's), compare.md, compare.csv, summary.json and each run's figures.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string scene_name, scenes, out_dir, log_path, reference_path, kidnap_to_text, mask_source, camera;
  std::string explore_pose = "fused-slam";  // --explore-pose, read into o.explore_pose by Run
  CompareConfigPaths paths;
  int laps = 0, seed = -1, explore_seed = 101, threads = 1;
  double duration_s = -1, kidnap_at_s = 0, kidnap_run_s = kKidnapRunS;
  bool no_kidnap_run = false, with_kidnap_run = false, no_ratslam = false;
  CompareOptions o;
};

}  // namespace snapnav::eval
