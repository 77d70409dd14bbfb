// eval-compare's app (eval_compare_app.hpp): the flags, the standard set of runs, the tables and
// summary.json over the runs of slam_compare.hpp.
#include "eval_compare_app.hpp"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include <opencv2/core.hpp>

#include "calibrated_mask.hpp"
#include "compare_config.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_config_use.hpp"
#include "sim_node.hpp"
#include "slam_compare.hpp"
#include "snapnav/glue/flags.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

// The kidnapped-robot run of the standard set: the corridor's robot drives down its left wing from
// (1, 8); at 10 s it is carried to the same place in the right wing, where the laser sees the
// same walls and only the posters differ (for kKidnapRunS s, eval_compare_app.hpp).
constexpr double kKidnapAtS = 10.0;
const nav::Pose2 kKidnapTo{29.0, 5.0, -M_PI / 2};


}  // namespace

namespace snapnav::eval {

bool EvalCompareApp::Initialize(int argc, char** argv) {
  glue::Flags flags(
      "eval-compare",
      "The SLAM comparison (issue 8; thesis 1.2, 5, 6.3.3): dead reckoning, laser-only SLAM, RatSLAM and fused\n"
      "visual + laser SLAM on the same simulated run with ground truth. A place-cell memory is explored first\n"
      "in a separate run (the scene's route once, a cell every --cell-spacing-m at fused SLAM's pose during\n"
      "that run (no memory yet: its laser), or see --explore-pose; seed --explore-seed); the evaluated run\n"
      "drives the route (--laps or --duration-s) with the simulator's noise\n"
      "(--sim-config); dead reckoning and laser SLAM run over its odometry and scans as eval slam does, fused\n"
      "SLAM beside it with a place-cell fix every 1/--visual-rate-hz s, RatSLAM with every frame at\n"
      "--ratslam-rate-hz. Without --scene/--scenes the standard set runs: indoor13, people11 (walking people\n"
      "occlude camera and laser), corridor, and corridor_kidnap (kidnapped at 10 s from the left wing to the\n"
      "mirrored place in the right one, 120 s). --kidnap-at-s / --kidnap-to make a --scene run a kidnapping.\n"
      "Writes compare.md, compare.csv and summary.json (flat keys: <method>_ate_rmse_m, RPE, ms per update,\n"
      "visual measurements accepted/rejected, kidnap_recovery_s; one run: unprefixed, several: <run>_...),\n"
      "and per run trajectories.png, errors.png, timing.png, trajectories.csv, fixes.csv (a folder per run\n"
      "when there are several). --log LOG [--reference REF] adds dead reckoning and laser SLAM on a recorded\n"
      "log (as eval slam; RatSLAM and fused SLAM need frames). Exit status 0 even when a target is missed;\n"
      "the missed targets are printed and listed in summary.json.");
  flags.AddString("scene", &scene_name, "one scene (config/scenes/NAME.scene or a file)");
  flags.AddString("scenes", &scenes, "several scenes, comma-separated (no kidnapped run unless --kidnap-at-s)");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddInt("laps", &laps, "laps of the scene's route per run (0: use --duration-s; a lap ends the run first)");
  flags.AddDouble("duration-s", &duration_s, "simulated seconds per run (default 300, or none with --laps)");
  flags.AddDouble("kidnap-at-s", &kidnap_at_s, "kidnap the robot at this simulated time [s] (0: none)");
  flags.AddString("kidnap-to", &kidnap_to_text, "where to: x_m,y_m,theta_deg (default 29,5,-90: the corridor's right wing)");
  flags.AddDouble("kidnap-run-s", &kidnap_run_s, "simulated seconds of the standard kidnapped run");
  flags.AddBool("no-kidnap-run", &no_kidnap_run, "standard set: leave out the kidnapped corridor run");
  flags.AddBool("with-kidnap-run", &with_kidnap_run, "with --scene/--scenes: add the standard kidnapped corridor run");
  flags.AddInt("seed", &seed, "seed of the evaluated runs (default: the sim config's)");
  flags.AddInt("explore-seed", &explore_seed, "seed of the exploration run that builds the place-cell memory");
  flags.AddDouble("cell-spacing-m", &o.cell_spacing_m, "a place cell every this much travel of the exploration [m]");
  flags.AddString("explore-pose", &explore_pose,
                  "where the exploration places its cells, as a robot without ground truth: fused-slam (fused SLAM's "
                  "pose during the exploration, with no memory yet: its laser and people test) | laser-slam (laser-only "
                  "SLAM's) | truth (the true pose: an upper bound no robot has)");
  flags.AddDouble("visual-rate-hz", &o.visual_rate_hz, "place-cell fixes per simulated second");
  flags.AddDouble("ratslam-rate-hz", &o.ratslam_rate_hz, "frames per simulated second given to RatSLAM");
  flags.AddBool("visual-prediction", &o.visual_prediction,
                "localize with the fused pose as the distance filter's prediction (default: global fixes)");
  flags.AddBool("no-ratslam", &no_ratslam, "do not run RatSLAM");
  flags.AddDouble("rpe-delta-m", &o.rpe_delta_m, "travelled distance of the relative pose error [m]");
  flags.AddDouble("recovery-error-m", &o.recovery_error_m, "kidnapping: recovered when the fused error stays below this [m]");
  flags.AddDouble("recovery-hold-s", &o.recovery_hold_s, "... for this long [s]");
  flags.AddString("sim-config", &paths.sim, "simulator config (robot noise, laser, camera, rates, seed)");
  flags.AddString("camera", &camera, "camera preset, overrides --sim-config's [camera] preset: realistic | clean");
  flags.AddString("mask", &mask_source,
                  "self-occlusion mask of the raw frames (place cells, RatSLAM): calibrated (calibrate-mirror's, from 60 "
                  "frames of the camera) | none | truth (the renderer's robot parts) | FILE; default: calibrated with the "
                  "realistic camera, none with the clean one");
  flags.AddString("fused-config", &paths.fused, "fused-slam config ([laser_slam], [fused_slam])");
  flags.AddString("laser-config", &paths.laser, "laser-slam config of laser-only SLAM ([laser_slam])");
  flags.AddString("ratslam-config", &paths.ratslam, "RatSLAM config ([ratslam])");
  flags.AddString("placecells-config", &paths.placecells, "place-cell config (view, localizer, vocabulary)");
  flags.AddString("log", &log_path, "dead reckoning and laser SLAM on these LCM logs too (comma-separated; made by "
                                     "./snapnav import); alone, without --scene/--scenes: only the logs");
  flags.AddString("reference", &reference_path, "references of --log, in order: CSV utime,x,y,theta or a CARMEN corrected log");
  flags.AddInt("threads", &threads, "OpenCV threads (SIFT is parallel); 1: one core");
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (duration_s < 0) duration_s = laps > 0 ? 0 : 300;
  if (laps < 0 || duration_s < 0 || (laps == 0 && duration_s == 0)) {
    throw glue::FlagError("give --laps N (> 0) or --duration-s S (> 0)");
  }
  if (threads < 1) throw glue::FlagError("--threads must be >= 1");
  if (!scene_name.empty() && !scenes.empty()) throw glue::FlagError("give --scene or --scenes, not both");
  if (!reference_path.empty() && log_path.empty()) throw glue::FlagError("--reference needs --log");
  return true;
}

int EvalCompareApp::Run() {
  cv::setNumThreads(threads);
  nav::Pose2 kidnap_to = kKidnapTo;
  if (!kidnap_to_text.empty()) {
    const auto parts = glue::SplitList(kidnap_to_text);
    if (parts.size() != 3) throw glue::FlagError("--kidnap-to takes x_m,y_m,theta_deg");
    try {
      kidnap_to = {std::stod(parts[0]), std::stod(parts[1]), std::stod(parts[2]) * M_PI / 180};
    } catch (const std::exception&) {
      throw glue::FlagError("--kidnap-to: '" + kidnap_to_text + "' is not x_m,y_m,theta_deg");
    }
  }

  o.explore_seed = static_cast<uint64_t>(explore_seed);
  if (explore_pose == "truth") {
    o.explore_pose = eval::CompareOptions::ExplorePose::kTruth;
  } else if (explore_pose == "laser-slam") {
    o.explore_pose = eval::CompareOptions::ExplorePose::kLaserSlam;
  } else if (explore_pose != "fused-slam") {
    throw glue::FlagError("--explore-pose takes laser-slam, fused-slam or truth, not '" + explore_pose + "'");
  }
  o.run_ratslam = !no_ratslam;
  const processes::SimConfig sim_config = eval::LoadCompareConfigs(paths, &o);
  eval::ApplyCameraFlag(camera, sim_config.seed, &o.camera);
  o.mask = eval::MaskOrDefault(mask_source, o.camera);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }

  // The runs.
  std::vector<eval::CompareRunOptions> runs;
  auto make_run = [&](const std::string& scene, const std::string& name) {
    eval::CompareRunOptions r;
    r.name = name;
    r.sim = eval::SimSlamOptions::FromSimConfig(sim_config);
    r.sim.scene = scene;
    r.sim.laps = laps;
    r.sim.duration_s = duration_s;
    r.sim.kidnap = {};
    if (seed >= 0) r.sim.seed = static_cast<uint64_t>(seed);
    return r;
  };
  if (!scene_name.empty()) {
    runs.push_back(make_run(scene_name, fs::path(scene_name).stem().string()));
  } else if (!scenes.empty()) {
    for (const auto& s : glue::SplitList(scenes)) runs.push_back(make_run(s, fs::path(s).stem().string()));
  } else if (log_path.empty()) {
    for (const char* s : {"indoor13", "people11", "corridor"}) runs.push_back(make_run(s, s));
    with_kidnap_run = !no_kidnap_run;
  }
  if (kidnap_at_s > 0) {
    for (auto& r : runs) {
      r.sim.kidnap = {kidnap_at_s, kidnap_to};
      r.name += "_kidnap";
    }
  }
  if (with_kidnap_run) {
    eval::CompareRunOptions k = make_run("corridor", "corridor_kidnap");
    k.sim.laps = 0;
    k.sim.duration_s = kidnap_run_s;
    k.sim.kidnap = {kKidnapAtS, kidnap_to};
    runs.push_back(k);
  }
  if (runs.empty() && log_path.empty()) throw glue::FlagError("--scenes must name at least one scene");

  std::ostringstream effective;
  eval::PrintCompareOptions(effective, paths, o);
  effective << "threads " << threads << "\n";
  for (const auto& r : runs) {
    effective << "run " << r.name << ": scene " << r.sim.scene << ", seed " << r.sim.seed << ", "
              << (r.sim.laps > 0 ? std::to_string(r.sim.laps) + " laps" : eval::Fixed(r.sim.duration_s, 0) + " s");
    if (r.sim.kidnap.enabled()) {
      effective << ", kidnapped at " << r.sim.kidnap.at_s << " s to (" << r.sim.kidnap.to.x_m << ", " << r.sim.kidnap.to.y_m
                << ", " << r.sim.kidnap.to.theta_rad * 180 / M_PI << " deg)";
    }
    effective << "\n";
  }
  std::cerr << "eval-compare: effective options:\n";
  {
    std::istringstream lines(effective.str());
    for (std::string line; std::getline(lines, line);) std::cerr << "  " << line << "\n";
  }

  const fs::path out(out_dir);
  fs::create_directories(out);
  std::vector<eval::CompareRun> compared;
  std::map<std::string, eval::RouteMemory> memories;  // one per scene
  std::vector<std::string> missed;
  for (const auto& r : runs) {
    const auto scene = processes::LoadSceneFile(processes::SceneFilePath(r.sim.scene));
    auto log = [&](const std::string& text) { std::cerr << "eval-compare: " << r.name << ": " << text << "\n"; };
    if (!memories.count(scene.name)) {
      log("exploring the route for the place-cell memory");
      memories[scene.name] = eval::ExploreRouteMemory(scene, o, r.sim);
      const eval::RouteMemory& m = memories[scene.name];
      log(std::to_string(m.memory->size()) + " cells at the " + eval::ExplorePoseName(o.explore_pose) + " pose in " +
          eval::Fixed(m.seconds, 1) + " s (cells off the truth by " + eval::Fixed(m.cell_error_mean_m, 3) + " m mean, " +
          eval::Fixed(m.cell_error_max_m, 3) + " m max)");
    }
    eval::CompareRun run = eval::RunComparison(scene, memories[scene.name], r, o, log);
    const fs::path dir = runs.size() > 1 ? out / run.name : out;
    eval::WriteCompareRun(run, dir.string());
    std::ostringstream line;
    line << run.name << ": " << eval::Fixed(run.distance_m, 1) << " m, ATE (aligned)";
    for (const auto& m : run.methods) {
      line << " " << m.name << " " << (m.ran ? eval::Fixed(m.errors.ate_aligned.rmse_m, 4) : std::string("n/a"));
    }
    line << "; visual " << run.visual_accepted << " accepted / " << run.visual_rejected << " rejected, "
         << run.relocalizations << " relocalisations";
    if (run.kidnapped) {
      line << ", kidnap recovery "
           << (std::isfinite(run.recovery_s) ? eval::Fixed(run.recovery_s, 1) + " s" : std::string("none"));
    }
    std::cout << line.str() << "\n";
    for (const auto& m : eval::MissedTargets(run)) missed.push_back(m);
    log("wrote " + dir.string() + " in " + eval::Fixed(run.seconds, 0) + " s");
    compared.push_back(std::move(run));
  }
  std::vector<eval::LogComparison> logs;
  if (!log_path.empty()) {
    const auto log_paths = glue::SplitList(log_path), references = glue::SplitList(reference_path);
    if (references.size() > log_paths.size()) throw glue::FlagError("--reference lists more files than --log");
    for (size_t i = 0; i < log_paths.size(); ++i) {
      const std::string ref = i < references.size() ? references[i] : "";
      std::cerr << "eval-compare: dead reckoning and laser SLAM on " << log_paths[i]
                << (ref.empty() ? "" : " against " + ref) << "\n";
      logs.push_back(eval::CompareOnLog(log_paths[i], ref, o.laser, o.rpe_delta_m));
    }
  }

  std::ofstream(out / "compare.md") << "# SLAM comparison\n\n" << eval::CompareTableMarkdown(compared, logs) << "\n"
                                    << (missed.empty() ? "All targets met.\n" : "Missed targets:\n")
                                    << [&] {
                                         std::string s;
                                         for (const auto& m : missed) s += "- " + m + "\n";
                                         return s;
                                       }()
                                    << "\nOptions:\n\n```\n" << effective.str() << "```\n";
  std::ofstream(out / "compare.csv") << eval::CompareTableCsv(compared, logs);
  {
    results::Json j;
    j["runs"] = results::Json::array();
    for (const auto& run : compared) j["runs"].push_back(run.name);
    j["ratslam"] = o.run_ratslam ? "ran" : "off";
    j["explore_pose"] = eval::ExplorePoseName(o.explore_pose);
    j["camera"] = o.camera.optics.enabled ? "realistic" : "clean";
    j["mask"] = o.mask;  // none | calibrated | truth | the file's path, as eval homing writes it
    for (const auto& run : compared) {
      const std::string prefix = compared.size() > 1 ? run.name + "_" : "";
      if (compared.size() == 1) {
        j["run"] = run.name;
        j["scene"] = run.scene;
      }
      for (const auto& [key, value] : eval::SummaryKeys(run)) j[prefix + key] = results::Significant(value);
    }
    for (const auto& l : logs) {
      // Keys named after the log file: log_<stem>_...
      std::string stem = fs::path(l.log).stem().string();
      for (char& c : stem) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      const std::string k = "log_" + stem + "_";
      j[k + "path"] = l.log;
      j[k + "scans"] = l.scans;
      if (l.has_reference) {
        j[k + "dead_reckoning_ate_rmse_m"] = results::Significant(l.dead_reckoning.errors.ate_aligned.rmse_m);
        j[k + "laser_slam_ate_rmse_m"] = results::Significant(l.laser_slam.errors.ate_aligned.rmse_m);
        j[k + "laser_slam_rpe_translation_rmse_m"] = results::Significant(l.laser_slam.errors.rpe.translation_rmse_m);
      }
      j[k + "laser_slam_ms_per_scan"] = results::Significant(l.laser_slam.ms_per_update);
    }
    j["targets_missed"] = missed.size();
    j["missed"] = missed;
    results::WriteJsonFile((out / "summary.json").string(), j);
  }
  for (const auto& l : logs) {
    std::cout << "log " << l.log << ": " << l.scans << " scans";
    if (l.has_reference) {
      std::cout << ", ATE dead_reckoning " << eval::Fixed(l.dead_reckoning.errors.ate_aligned.rmse_m, 4) << " laser_slam "
                << eval::Fixed(l.laser_slam.errors.ate_aligned.rmse_m, 4);
    }
    std::cout << ", laser slam " << eval::Fixed(l.laser_slam.ms_per_update, 3) << " ms/scan\n";
  }
  for (const auto& m : missed) std::cout << "MISSED: " << m << "\n";
  std::cerr << "eval-compare: wrote " << (out / "compare.md").string() << ", compare.csv, summary.json\n";
  return 0;
}

}  // namespace snapnav::eval
