// eval-ratslam's app (eval_ratslam_app.hpp): RatSLAM on a simulated route with ground truth
// (./snapnav eval ratslam). The simulator (config/sim.ini, as the sim process) drives a scene's
// route for --laps laps with its odometry noise and heading drift and renders the camera; RatSLAM
// (the [ratslam] section of --ratslam-config, as the ratslam process) and dead reckoning run on the
// odometry and the grey panoramas. Writes summary.json (ratslam_ate_rmse_m,
// dead_reckoning_ate_rmse_m after SE(2) alignment, loop closures, ms per update),
// experience_map.png, errors.png, trajectories.csv.
#include "eval_ratslam_app.hpp"

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <vector>

#include "calibrated_mask.hpp"
#include "ratslam_eval.hpp"
#include "scene_file.hpp"
#include "sim_config_use.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/ratslam_options.hpp"

namespace {

using namespace snapnav;

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read " + path);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// `text` with the value of `key` in [section] replaced (the comment after it dropped).
std::string SetKey(const std::string& text, const std::string& section, const std::string& key,
                   const std::string& value) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, current;
  bool found = false;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line[first] == '[') {
      current = line.substr(first + 1, line.find(']') - first - 1);
    } else if (current == section && first != std::string::npos && line.compare(first, key.size(), key) == 0) {
      const size_t eq = line.find('=', first);
      if (eq != std::string::npos && line.substr(first, eq - first).find_last_not_of(" \t") == key.size() - 1) {
        line = key + " = " + value;
        found = true;
      }
    }
    out << line << "\n";
  }
  if (!found) throw glue::FlagError("--sweep: no key '" + key + "' in [" + section + "]");
  return out.str();
}

struct Sweep {
  std::vector<std::pair<std::string, std::vector<std::string>>> axes;  // key, values
};

// "key=v1,v2;key2=v3" -> every combination, as (label, INI text).
std::vector<std::pair<std::string, std::string>> Combinations(const std::string& spec, const std::string& text) {
  Sweep sweep;
  for (const std::string& part : glue::SplitList(spec, ';')) {
    const size_t eq = part.find('=');
    if (eq == std::string::npos || eq == 0) throw glue::FlagError("--sweep: expected key=v1,v2,... in '" + part + "'");
    sweep.axes.push_back({part.substr(0, eq), glue::SplitList(part.substr(eq + 1), ',')});
    if (sweep.axes.back().second.empty()) throw glue::FlagError("--sweep: no values for " + sweep.axes.back().first);
  }
  std::vector<std::pair<std::string, std::string>> out{{"", text}};
  for (const auto& [key, values] : sweep.axes) {
    std::vector<std::pair<std::string, std::string>> next;
    for (const auto& [label, t] : out) {
      for (const std::string& v : values) {
        next.push_back({label + (label.empty() ? "" : " ") + key + "=" + v, SetKey(t, "ratslam", key, v)});
      }
    }
    out = std::move(next);
  }
  return out;
}


}  // namespace

namespace snapnav::eval {

bool EvalRatSlamApp::Initialize(int argc, char** argv) {
  glue::Flags flags("eval-ratslam",
                    "RatSLAM on a simulated route with ground truth: drives --scene's route for --laps laps (or\n"
                    "--duration-s) with the simulator of --config (odometry noise, heading drift, camera), feeds\n"
                    "the odometry and the grey panoramas to RatSLAM ([ratslam] of --ratslam-config) and to dead\n"
                    "reckoning, and writes into --out: summary.json (ratslam_ate_rmse_m and\n"
                    "dead_reckoning_ate_rmse_m after SE(2) alignment, *_unaligned_* from the common start, RPE, loop\n"
                    "closures, templates, experiences, ms per odometry and per image), experience_map.png (the\n"
                    "experience map and its loop-closure links over the ground truth), errors.png and\n"
                    "trajectories.csv.");
  flags.AddString("config", &sim_config, "simulator configuration: robot, camera, laser, rates, seed");
  flags.AddString("ratslam-config", &ratslam_config, "RatSLAM configuration (its [ratslam] section is used)");
  flags.AddString("scene", &scene, "scene name (config/scenes/NAME.scene) or file");
  flags.AddInt("laps", &laps, "laps of the scene's route (0: use --duration-s)");
  flags.AddDouble("duration-s", &duration_s, "simulated seconds to drive (0: use --laps)");
  flags.AddInt("seed", &seed, "random seed (default: the config's)");
  flags.AddBool("raw", &raw,
                "render raw catadioptric frames and unwrap them (as OMNI_FRAME) instead of panoramas; always with the "
                "realistic camera ([camera] preset), whose optics act on the raw image");
  flags.AddString("camera", &camera, "camera preset, overrides --config's [camera] preset: realistic | clean");
  flags.AddString("mask", &mask,
                  "self-occlusion mask of the raw frames: calibrated (calibrate-mirror's, from 60 frames of the camera) "
                  "| none | truth (the renderer's robot parts, grown by 2 px) | FILE (black = masked, the raw image's "
                  "size, e.g. calibrate-mirror's); RatSLAM's templates ignore it; default: calibrated with the "
                  "realistic camera, none with the clean one");
  flags.AddBool("no-people", &no_people, "leave the scene's walking people out of the camera's view");
  flags.AddDouble("rpe-delta-m", &rpe_delta_m, "travelled distance of the relative pose error [m]");
  flags.AddString("sweep", &sweep,
                  "run several [ratslam] configurations on the same simulated run: 'key=v1,v2;key2=v3,v4' (every\n"
                  "combination; results in sweep.md, sweep.csv and one folder per combination)");
  flags.AddString("out", &out_dir, "output folder (required)");
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");

  return true;
}

int EvalRatSlamApp::Run() {
  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(sim_config), "");
  eval::RatSlamEvalOptions options;
  options.run = eval::SimCameraOptions::FromSimConfig(sim);
  options.run.sim.scene = scene;
  options.run.sim.laps = laps;
  options.run.sim.duration_s = duration_s;
  if (seed >= 0) options.run.sim.seed = static_cast<uint64_t>(seed);
  if (!camera.empty()) {
    eval::ApplyCameraFlag(camera, options.run.sim.seed, &options.run.camera);
    options.run.raw_frames = options.run.camera.optics.enabled;
  }
  options.run.raw_frames = options.run.raw_frames || raw;  // the realistic camera: raw frames always
  mask = eval::MaskOrDefault(mask, options.run.camera);
  options.mask = mask;
  if (mask != "none") {
    if (!options.run.raw_frames) {
      throw glue::FlagError("--mask is of raw frames: it needs --raw or the realistic camera");
    }
    if (mask == "truth") {
      options.run.truth_mask = true;
    } else if (mask == "calibrated") {
      options.run.raw_mask = eval::CalibratedMask(processes::LoadSceneFile(processes::SceneFilePath(scene)),
                                                  options.run.camera, options.run.sim.seed);
    } else {
      try {
        options.run.raw_mask =
            glue::LoadMask(mask, cv::Size(options.run.camera.omni_width_px, options.run.camera.omni_height_px));
      } catch (const std::runtime_error& e) {
        throw glue::FlagError(std::string("--mask: ") + e.what());
      }
    }
  }
  options.run.people = !no_people;
  options.rpe_delta_m = rpe_delta_m;
  const std::string ratslam_text = ReadText(ratslam_config);
  options.ratslam = glue::ReadRatSlamOptions(glue::IniFile::Parse(ratslam_text, ratslam_config));
  options.run.Validate();
  std::cerr << "eval-ratslam: sim " << sim_config << ": scene " << scene << ", laps " << laps << ", seed "
            << options.run.sim.seed << ", heading drift " << options.run.sim.drive.heading_drift_deg_per_m
            << " deg/m, odometry " << options.run.sim.odometry_rate_hz << " Hz, camera " << options.run.camera_rate_hz
            << " Hz " << options.run.camera.panorama.width_px << "x" << options.run.camera.panorama.height_px
            << (options.run.camera.optics.enabled ? ", realistic" : ", clean")
            << (options.run.raw_frames ? " (raw, unwrapped)" : " (panoramas)") << ", mask " << mask
            << "\neval-ratslam: " << ratslam_config << ":\n";
  glue::PrintRatSlamOptions(std::cerr, options.ratslam);
  const auto progress = [](double t_s, int laps_done) {
    std::cerr << "eval-ratslam: " << t_s << " s simulated, " << laps_done << " laps\r" << std::flush;
  };
  namespace fs = std::filesystem;
  if (sweep.empty()) {
    const eval::RatSlamEvaluation e = eval::EvaluateRatSlam(options, progress);
    std::cerr << "\n";
    eval::WriteRatSlamEvaluation(e, options, out_dir);
    eval::PrintRatSlamEvaluation(std::cout, e);
    std::cerr << "eval-ratslam: wrote " << out_dir << "/summary.json, experience_map.png, errors.png, trajectories.csv\n";
    return 0;
  }
  const auto combos = Combinations(sweep, ratslam_text);
  std::vector<nav::RatSlamOptions> variants;
  for (const auto& [label, text] : combos) {
    variants.push_back(glue::ReadRatSlamOptions(glue::IniFile::Parse(text, ratslam_config + " (" + label + ")")));
  }
  std::cerr << "eval-ratslam: " << variants.size() << " configurations on one run\n";
  const auto results = eval::EvaluateRatSlamVariants(options, variants, progress);
  std::cerr << "\n";
  std::ostringstream md, csv;
  md << "| configuration | ATE ratslam [m] | ATE dead reckoning [m] | unaligned final ratslam [m] | loop closures (false, inconsistent links) | "
        "templates | experiences | ms/image | ms/odometry |\n|---|---|---|---|---|---|---|---|---|\n";
  csv << "configuration,ratslam_ate_rmse_m,dead_reckoning_ate_rmse_m,ratslam_ate_unaligned_final_m,loop_closures,"
         "false_loop_closures,inconsistent_links,templates,experiences,ms_per_image,ms_per_odometry\n";
  for (size_t i = 0; i < results.size(); ++i) {
    const auto& e = results[i];
    eval::RatSlamEvalOptions o = options;
    o.ratslam = variants[i];
    const std::string dir = (fs::path(out_dir) / ("v" + std::to_string(i))).string();
    eval::WriteRatSlamEvaluation(e, o, dir);
    std::ostringstream m, c;
    m << std::fixed << std::setprecision(3) << e.ratslam_errors.ate_aligned.rmse_m << " | "
      << e.dead_reckoning_errors.ate_aligned.rmse_m << " | " << e.ratslam_errors.ate.final_m << " | " << e.loop_closures
      << " (" << e.false_loop_closures() << ", " << e.inconsistent_links() << ") | " << e.templates << " | " << e.experiences.size() << " | "
      << e.image_ms_mean << " | " << e.odometry_ms_mean;
    c << std::fixed << std::setprecision(4) << e.ratslam_errors.ate_aligned.rmse_m << ","
      << e.dead_reckoning_errors.ate_aligned.rmse_m << "," << e.ratslam_errors.ate.final_m << "," << e.loop_closures
      << "," << e.false_loop_closures() << "," << e.inconsistent_links() << "," << e.templates << "," << e.experiences.size() << "," << e.image_ms_mean
      << "," << e.odometry_ms_mean;
    md << "| v" << i << ": " << combos[i].first << " | " << m.str() << " |\n";
    csv << "\"" << combos[i].first << "\"," << c.str() << "\n";
  }
  std::ofstream(fs::path(out_dir) / "sweep.md") << md.str();
  std::ofstream(fs::path(out_dir) / "sweep.csv") << csv.str();
  std::cout << md.str();
  std::cerr << "eval-ratslam: wrote " << out_dir << "/sweep.md, sweep.csv and v0.. v" << results.size() - 1 << "/\n";
  return 0;
}

}  // namespace snapnav::eval
