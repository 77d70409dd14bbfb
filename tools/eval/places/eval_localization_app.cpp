// eval-localization's app (eval_localization_app.hpp): the flags, the effective options, and the
// runs of localization_eval.hpp over each scene or a grid folder.
#include "eval_localization_app.hpp"

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <opencv2/core/utility.hpp>

#include "calibrated_mask.hpp"
#include "grid_folder.hpp"
#include "localization_eval.hpp"
#include "sim_config_use.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/place_cells.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

std::vector<double> ParseDoubles(const std::string& text, const std::string& flag) {
  std::vector<double> v;
  for (const auto& part : glue::SplitList(text)) {
    try {
      size_t used = 0;
      v.push_back(std::stod(part, &used));
      if (used != part.size()) throw std::invalid_argument(part);
    } catch (const std::exception&) {
      throw glue::FlagError("--" + flag + ": '" + part + "' is not a number");
    }
  }
  return v;
}


}  // namespace

namespace snapnav::eval {

bool EvalLocalizationApp::Initialize(int argc, char** argv) {
  glue::Flags flags("eval-localization",
                    "Place-cell localization (thesis 5.1.4, 5.2.2, fig. 5.9): explores a simulated scene (its grid\n"
                    "database, a manual serpentine route, random exploration at several novelty thresholds), then\n"
                    "localizes at --tests random off-grid positions with random headings. For every distance\n"
                    "measure, memory, distance filter on/off and nearest-cell/interpolated estimate: mean and max\n"
                    "position error, heading error, ms per query. Views come from raw omni images rendered and\n"
                    "unwrapped (the real pipeline), made once and shared by every configuration. View, localizer\n"
                    "and vocabulary options come from --config (the placecells process' INI); measure, filter and\n"
                    "estimate are varied, the flags below override the rest.\n"
                    "Writes report.md, results.csv, queries.csv, summary.json (mean_localization_error_m: bearing-\n"
                    "smallest, filter on, interpolated, grid memory) and figures into --out.");
  flags.AddString("scene", &scene_name, "scene name (config/scenes) or file");
  flags.AddString("grid", &grid_dir,
                  "a lab's own image grid instead of a scene: a folder as gridgen writes (positions.csv; raw images with "
                  "a camera.ini [mirror], or panoramas of the sim config's [panorama]); the leave-one-out protocol over it");
  flags.AddString("scenes", &scenes, "several scenes (comma-separated): one sub-folder of --out each");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddString("config", &config_path, "place-cell config: [landmarks] [place_view] [vline] [sift] [surf] [matching] "
                                          "[measure] [distance_filter] [localizer] [vocabulary]");
  flags.AddString("sim-config", &sim_config_path, "simulator config: its camera, [mirror], [panorama], [effects], seed and robot noise apply; a changed key "
                  "it does not use is refused");
  flags.AddString("camera", &camera, "camera preset, overrides --sim-config's [camera] preset: clean | realistic");
  flags.AddString("mask", &mask_source,
                  "self-occlusion mask of the raw images: calibrated (calibrate-mirror's, from 60 frames of the camera) | "
                  "none | truth (the renderer's robot parts) | FILE; default: calibrated with the realistic camera, none "
                  "with the clean one");
  flags.AddString("features", &features, "override [landmarks] method: sift | surf");
  flags.AddString("protocols", &protocols,
                  "snapnav (random off-grid test positions, the whole grid kept; always run) and/or leave-one-out "
                  "(thesis 5.2.2 and 4.4: every grid image a query against the grid without its own cell)");
  flags.AddInt("leave-one-out-stride", &o.leave_one_out_stride, "leave-one-out: every n-th grid image a query");
  flags.AddString("memories", &memories, "memories: grid, route, random (comma-separated)");
  flags.AddString("measures", &measures, "distance measures: bearing-smallest, bearing-ransac, count, vline");
  flags.AddString("filters", &filters, "distance filter settings: on, off");
  flags.AddInt("tests", &o.tests, "test positions");
  flags.AddDouble("prediction-sigma-m", &o.prediction_sigma_m, "odometry prediction noise per axis [m] (distance filter)");
  flags.AddString("pose-source", &pose_source, "cell positions of route and random exploration: truth | odometry");
  flags.AddString("thresholds", &thresholds, "random exploration: novelty thresholds (units of --explore-measure)");
  flags.AddString("explore-measure", &explore_measure, "random exploration: measure of the novelty test");
  flags.AddInt("walk-runs", &o.walk.runs, "random exploration: runs (start headings spread over the circle)");
  flags.AddInt("walk-steps", &o.walk.steps, "random exploration: steps (views) per run");
  flags.AddDouble("walk-step-m", &o.walk.step_m, "random exploration: step length [m]");
  flags.AddDouble("walk-turn-sigma-rad", &o.walk.turn_sigma_rad, "random exploration: heading change std. dev. per step");
  flags.AddDouble("route-row-spacing-m", &o.route_row_spacing_m, "manual route: distance between serpentine rows [m]");
  flags.AddDouble("route-spacing-m", &o.route_spacing_m, "manual route: a cell every this much travel [m]");
  flags.AddInt("seed", &seed, "seed of exploration, test positions, prediction noise and people");
  flags.AddInt("threads", &threads, "OpenCV threads (SIFT is parallel); 1: one core");
  flags.AddString("save-test-panoramas", &o.save_test_panoramas_dir, "folder for the test positions' panoramas (PNG)");
  // These override a config key; left at the sentinel (negative), the config's value is used.
  const std::string keep = " (negative: the config's)";
  const char* const configs = "the config's";
  flags.AddDouble("ratio", &ov.ratio, "override [matching] ratio" + keep, configs);
  flags.AddDouble("keep-fraction", &ov.keep_fraction, "override [measure] keep_fraction" + keep, configs);
  flags.AddDouble("residual-cap-rad", &ov.residual_cap_rad, "override residual_cap_rad (bearing residual cap)" + keep,
                  configs);
  flags.AddInt("keep-min", &ov.keep_min, "override [measure] keep_min" + keep, configs);
  flags.AddDouble("ransac-threshold-rad", &ov.ransac_threshold_rad, "override the RANSAC inlier residual [rad]" + keep,
                  configs);
  flags.AddDouble("window-min-ncc", &ov.window_min_ncc, "override [measure] window_min_ncc (< -1: the config's)",
                  configs);
  flags.AddInt("min-matches", &ov.min_matches, "override [measure] min_matches" + keep, configs);
  flags.AddDouble("filter-radius-m", &ov.filter_radius_m, "override [distance_filter] radius_m" + keep, configs);
  flags.AddDouble("filter-weight", &ov.filter_weight, "override [distance_filter] weight" + keep, configs);
  flags.AddDouble("filter-gate-m", &ov.filter_gate_m, "override [distance_filter] gate_m" + keep, configs);
  flags.AddInt("interpolate-k", &ov.interpolate_k, "override [localizer] interpolate_k" + keep, configs);
  flags.AddDouble("interpolate-power", &ov.interpolate_power, "override [localizer] interpolate_power" + keep, configs);
  flags.AddDouble("interpolate-radius-m", &ov.interpolate_radius_m,
                  "override interpolate_radius_m: cells this near the chosen one are interpolated" + keep, configs);
  flags.AddInt("candidates", &ov.candidates, "override [localizer] candidates" + keep, configs);
  flags.AddInt("near-candidates", &ov.near_candidates, "override [localizer] near_candidates" + keep, configs);
  flags.AddInt("exhaustive-below", &ov.exhaustive_below, "override [localizer] exhaustive_below" + keep, configs);
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (!features.empty() && features != "sift" && features != "surf") throw glue::FlagError("--features must be sift or surf");
  if (pose_source != "truth" && pose_source != "odometry") throw glue::FlagError("--pose-source must be truth or odometry");
  if (threads < 1) throw glue::FlagError("--threads must be >= 1");
  o.memories = glue::SplitList(memories);
  for (const auto& p : glue::SplitList(protocols)) {
    if (p == "leave-one-out") o.leave_one_out = true;
    else if (p != "snapnav") throw glue::FlagError("--protocols takes snapnav and leave-one-out, not '" + p + "'");
  }
  o.measures = glue::SplitList(measures);
  o.filters.clear();
  for (const auto& f : glue::SplitList(filters)) {
    if (f != "on" && f != "off") throw glue::FlagError("--filters takes on and off, not '" + f + "'");
    o.filters.push_back(f == "on");
  }
  o.thresholds = ParseDoubles(thresholds, "thresholds");
  o.explore_measure = explore_measure;
  o.odometry_poses = pose_source == "odometry";
  o.seed = static_cast<uint64_t>(seed);
  return true;
}

int EvalLocalizationApp::Run() {
  cv::setNumThreads(threads);

  const auto sim = eval::LoadSimConfigFor(sim_config_path, eval::LocalizationSimConfigUse());
  o.camera = sim.camera;
  eval::ApplyCameraFlag(camera, o.seed, &o.camera);
  o.mask = eval::MaskOrDefault(mask_source, o.camera);
  o.effects = sim.effects;
  o.drive = sim.drive_options;
  const auto ini = glue::IniFile::Load(config_path);
  o.view = glue::ReadPlaceViewOptions(ini);
  o.localizer = glue::ReadLocalizerOptions(ini);
  o.vocabulary = glue::ReadVocabularyOptions(ini);
  if (!features.empty()) o.view.features.method = features == "sift" ? nav::LandmarkMethod::kSift : nav::LandmarkMethod::kSurf;
  ov.Apply(&o.localizer);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }
  std::ostringstream effective;
  effective << "config " << config_path << " (with the overrides), sim config " << sim_config_path << ", threads "
            << threads << "\n";
  glue::PrintPlaceViewOptions(effective, o.view);
  glue::PrintLocalizerOptions(effective, o.localizer);
  glue::PrintVocabularyOptions(effective, o.vocabulary);
  effective << "[evaluation]\n" << eval::DescribeOptions(o);
  const std::string options_text = effective.str();
  std::cerr << "eval-localization: effective options (measure, refinement, filter and estimate are varied per "
               "configuration):\n";
  std::istringstream lines(options_text);
  for (std::string line; std::getline(lines, line);) std::cerr << "  " << line << "\n";

  if (!grid_dir.empty()) {
    if (!scenes.empty()) throw glue::FlagError("--grid and --scenes: one or the other");
    const auto folder = eval::LoadGridFolder(grid_dir);
    cv::Mat mask;
    const auto panoramas = eval::GridFolderPanoramas(folder, o.camera.panorama, &mask);
    std::vector<nav::Pose2> poses;
    for (const auto& im : folder.images) poses.push_back(im.pose);
    std::cerr << "eval-localization: grid folder " << grid_dir << ": " << poses.size() << " "
              << (folder.raw ? "raw" : "panorama") << " images" << (mask.empty() ? "" : ", masked") << "\n";
    const auto result = eval::RunGridFolderLocalization(grid_dir, poses, panoramas, mask, o, [&](const std::string& text, bool transient) {
      std::cerr << "eval-localization: " << text << (transient ? "\r" : "\n") << std::flush;
    });
    eval::WriteGridFolderOutputs(result, o, out_dir, options_text);
    const auto* def = result.FindLeaveOneOut("bearing-smallest", true, nav::PlaceEstimate::kInterpolated);
    if (def) std::cout << "leave_one_out_mean_localization_error_m " << eval::Fixed(def->errors.mean_m, 4) << "\n";
    std::cerr << "eval-localization: wrote " << (fs::path(out_dir) / "summary.json").string() << " and report.md\n";
    return 0;
  }
  const std::vector<std::string> scene_names = scenes.empty() ? std::vector<std::string>{scene_name} : glue::SplitList(scenes);
  if (scene_names.empty()) throw glue::FlagError("--scenes must name at least one scene");
  const fs::path out(out_dir);
  fs::create_directories(out);
  results::Json top;  // several scenes: one summary over them
  top["scenes"] = scene_names;
  int missed = 0;
  for (const auto& name : scene_names) {
    const auto scene = processes::LoadSceneFile(processes::SceneFilePath(name));
    std::cerr << "eval-localization: scene " << scene.name << ", grid " << scene.grid.nx << "x" << scene.grid.ny << " at "
              << scene.grid.spacing_m << " m, " << scene.people.count << " people\n";
    const auto result = eval::RunLocalizationEval(scene, o, [&](const std::string& text, bool transient) {
      std::cerr << "eval-localization: " << scene.name << ": " << text << (transient ? "\r" : "\n") << std::flush;
    });
    const fs::path dir = scene_names.size() > 1 ? out / scene.name : out;
    const auto figures = eval::WriteLocalizationOutputs(result, o, dir.string(), options_text);
    const auto* def = result.Find("grid", "bearing-smallest", true, nav::PlaceEstimate::kInterpolated);
    const auto* thesis = result.Find("grid", "bearing-smallest", true, nav::PlaceEstimate::kNearestCell);
    const auto target = eval::TargetMeanErrorM(scene.name);
    std::cerr << "eval-localization: " << scene.name << ": wrote " << (dir / "summary.json").string() << ", report.md, "
              << "results.csv, queries.csv and " << figures.size() << " figures in " << eval::Fixed(result.total_seconds, 0)
              << " s\n";
    if (def) {
      std::cout << scene.name << " mean_localization_error_m " << eval::Fixed(def->errors.mean_m, 4)
                << " max_localization_error_m " << eval::Fixed(def->errors.max_m, 4);
      if (thesis) std::cout << " thesis_configuration_mean_localization_error_m " << eval::Fixed(thesis->errors.mean_m, 4);
      const auto* loo = result.FindLeaveOneOut("bearing-smallest", true, nav::PlaceEstimate::kInterpolated);
      const auto* loo_near = result.FindLeaveOneOut("bearing-smallest", true, nav::PlaceEstimate::kNearestCell);
      if (loo) std::cout << " leave_one_out_mean_localization_error_m " << eval::Fixed(loo->errors.mean_m, 4);
      if (loo_near) std::cout << " leave_one_out_nearest_cell_mean_localization_error_m " << eval::Fixed(loo_near->errors.mean_m, 4);
      if (loo) top[scene.name + "_leave_one_out_mean_localization_error_m"] = results::Rounded(loo->errors.mean_m, 4);
      if (target) std::cout << " target " << eval::Fixed(*target, 2) << (def->errors.mean_m <= *target ? " met" : " MISSED");
      std::cout << "\n";
      if (target && def->errors.mean_m > *target) ++missed;
      top[scene.name + "_mean_localization_error_m"] = results::Rounded(def->errors.mean_m, 4);
      top[scene.name + "_max_localization_error_m"] = results::Rounded(def->errors.max_m, 4);
      if (thesis) {
        top[scene.name + "_thesis_configuration_mean_localization_error_m"] = results::Rounded(thesis->errors.mean_m, 4);
      }
    }
  }
  if (scene_names.size() > 1) {
    top["scenes_missing_target"] = missed;
    results::WriteJsonFile((out / "summary.json").string(), top);
  }
  return 0;
}

}  // namespace snapnav::eval
