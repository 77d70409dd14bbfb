#pragma once
// eval-homing (./snapnav eval homing) as an app: snapshot homing evaluated the way the thesis does
// (3.1.4, Appendix A): angular error over a scene's grid database, the average angular error (AAE),
// the closed-loop return ratio, vector maps, AAE by cell size and descriptor range, by noise type
// and level, entropy by cell size, and a parameter sweep table; landmark homing (--method,
// --compare, --people-diagnosis: landmark_compare.hpp, people_diagnosis.hpp) and a lab's own image
// grid (--grid: grid_folder.hpp). Initialize reads the flags; Run writes OUT/summary.json,
// report.md and the figures.
#include <filesystem>
#include <string>

#include "homing_eval.hpp"
#include "homing_node.hpp"
#include "sim_node.hpp"

namespace snapnav::eval {

// Flags over the homing config's [hog], [alv], [compass] and [preprocess] (0, -1, "" or false: the
// config's).
struct HogOverrides {
  int cell = 0, bins = 0;
  std::string range, weight, difference, band;
  double threshold = -1;
  bool no_compass = false, equalize = false, warp = false;
};

class EvalHomingApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // The evaluation the flags ask for; its exit status.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string scene_name = "indoor13", method = "hog", home_text, out_dir, input = "raw";
  std::string config_path = SNAPNAV_CONFIG_DIR "/homing.ini", sim_config_path = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string entropy_scenes = "indoor13,indoor_objects11,outdoor11";
  std::string landmarks_config_path = SNAPNAV_CONFIG_DIR "/landmarks.ini", alv = "unit";
  std::string compare_scenes = "indoor13,indoor_objects11,outdoor11,featureless11,people11", counts = "3,5,20,all";
  int top_n = 0;
  bool random_headings = false, sweep = false, quick = false, no_return = false, compare = false;
  bool people_diagnosis = false, return_best_only = false;
  int home_frames = -1, current_frames = -1, return_stride = 1;
  double home_interval_s = -1, current_interval_s = -1;
  std::string fusion, camera, mask_source, protocols = "snapnav", grid_dir;
  double min_fraction = -1;
  FrameProtocol fused{9, 1.0, 3, 0.5};
  int seed = 1;
  HogOverrides overrides;
  ReturnOptions ret;
  bool thesis_5x5 = false;  // --protocols has thesis-5x5

 private:
  // --method vline | sift | surf, --compare, --people-diagnosis (landmark_compare.hpp).
  int RunLandmarkMethods(const processes::SimConfig& sim, const processes::HomingConfig& homing,
                         const nav::HogHomingConfig& config);
  // HOG over --scene's grid: AAE, compass, return runs, figures, --sweep.
  int RunScene(const processes::SimConfig& sim, const nav::HogHomingConfig& config, const std::filesystem::path& out);
};

}  // namespace snapnav::eval
