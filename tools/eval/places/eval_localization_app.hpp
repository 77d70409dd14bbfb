#pragma once
// eval-localization (./snapnav eval localization) as an app: place-cell localization evaluated the way
// the thesis does (5.1.4, 5.2.2, fig. 5.9): memories explored in a simulated scene (the grid database, a
// manual route, random exploration at several novelty thresholds), random off-grid test positions, and
// the position and heading error of each distance measure with and without the distance filter,
// nearest cell against the interpolated estimate. Writes report.md, results.csv, queries.csv,
// summary.json and PNG figures into --out (one sub-folder per scene with --scenes).
#include <string>

#include "localization_eval.hpp"

namespace snapnav::eval {

// Overrides of the config's localizer options (negative: keep the config's value).
struct LocalizerOverrides {
  double ratio = -1, keep_fraction = -1, ransac_threshold_rad = -1, window_min_ncc = -2, filter_radius_m = -1,
         filter_weight = -1, filter_gate_m = -1, interpolate_power = -1, interpolate_radius_m = -1,
         residual_cap_rad = -1;
  int keep_min = -1, min_matches = -1, interpolate_k = -1, candidates = -1, near_candidates = -1, exhaustive_below = -1;
  void Apply(nav::LocalizerOptions* l) const {
    if (ratio >= 0) l->measure.match.ratio = ratio;
    if (keep_fraction >= 0) l->measure.keep_fraction = keep_fraction;
    if (residual_cap_rad >= 0) l->measure.residual_cap_rad = residual_cap_rad;
    if (ransac_threshold_rad >= 0) l->measure.ransac_threshold_rad = ransac_threshold_rad;
    if (window_min_ncc >= -1) l->measure.window_min_ncc = window_min_ncc;
    if (filter_radius_m >= 0) l->filter.radius_m = filter_radius_m;
    if (filter_weight >= 0) l->filter.weight = filter_weight;
    if (filter_gate_m >= 0) l->filter.gate_m = filter_gate_m;
    if (interpolate_power >= 0) l->interpolate_power = interpolate_power;
    if (interpolate_radius_m >= 0) l->interpolate_radius_m = interpolate_radius_m;
    if (keep_min >= 0) l->measure.keep_min = keep_min;
    if (min_matches >= 0) l->measure.min_matches = min_matches;
    if (interpolate_k >= 0) l->interpolate_k = interpolate_k;
    if (candidates >= 0) l->candidates = candidates;
    if (near_candidates >= 0) l->near_candidates = near_candidates;
    if (exhaustive_below >= 0) l->exhaustive_below = exhaustive_below;
  }
};

class EvalLocalizationApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // Explores, localizes and writes each scene's outputs (or the grid folder's); prints each scene's errors.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string scene_name = "indoor13", scenes, out_dir;
  std::string sim_config_path = SNAPNAV_CONFIG_DIR "/sim.ini", config_path = SNAPNAV_CONFIG_DIR "/placecells.ini";
  std::string features, memories = "grid,route,random", measures = "bearing-smallest,bearing-ransac,count,vline";
  std::string filters = "on,off", pose_source = "truth", thresholds = "0.08,0.05,0.03", explore_measure = "bearing-smallest";
  int threads = 1, seed = 1;
  std::string camera, mask_source, protocols = "snapnav", grid_dir;
  LocalizationEvalOptions o;
  LocalizerOverrides ov;
};

}  // namespace snapnav::eval
