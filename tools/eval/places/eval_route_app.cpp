// eval-route's app (eval_route_app.hpp): route following in closed loop (thesis 5.1.2-5.1.3, issue
// 6). The simulated robot follows a thesis route for several laps with place cells, odometry and
// homing; the error at every waypoint, per lap, its growth over the laps, against odometry alone.
#include "eval_route_app.hpp"

#include <iostream>
#include <opencv2/core.hpp>
#include <sstream>

#include "calibrated_mask.hpp"
#include "navigator_node.hpp"
#include "report_text.hpp"
#include "route_eval.hpp"
#include "scene_file.hpp"
#include "sim_config_use.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/glue/place_cells.hpp"

namespace {

using namespace snapnav;


}  // namespace

namespace snapnav::eval {

bool EvalRouteApp::Initialize(int argc, char** argv) {
  glue::Flags flags("eval-route",
                    "Route following in closed loop (thesis 5.1.2-5.1.3, issue 6): the simulated robot follows route\n"
                    "1 or 2 of thesis figure 5.5 (scaled to the scene's grid square) for --laps laps, localizing with\n"
                    "place cells explored at the grid positions and the waypoints (raw images unwrapped), driving by\n"
                    "odometry between fixes (pose tracker, [tracker] of the navigator config) and approaching each\n"
                    "waypoint by landmark homing towards its snapshot. The same follower on odometry alone is the\n"
                    "baseline. Writes OUT/summary.json, arrivals.csv, report.md, trajectory.png, waypoint_errors.png.");
  flags.AddString("scene", &scene_name, "scene name (config/scenes) or file");
  flags.AddInt("route", &route, "thesis route: 1 (figure 5.5 left) or 2 (right)");
  flags.AddInt("laps", &laps, "laps to drive");
  flags.AddInt("seed", &seed, "seed of the simulation (control error, odometry noise, people)");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddInt("cell-step", &cell_step,
               "memory: a cell at every N-th grid position (1: the whole grid, 2: every 2nd ...)");
  flags.AddBool("no-waypoint-cells", &no_waypoint_cells,
                "memory: no extra cells at the waypoints (nor homing to them)");
  flags.AddInt("localize-every", &localize_every, "localize every N control steps (camera frames)");
  flags.AddBool("no-homing", &no_homing, "no final approach by homing: arrival by the tracked position alone");
  flags.AddDouble("homing-arrived-rad", &homing_arrived_rad,
                  "the homing says 'arrived' below this bearing distance to the waypoint's cell [rad]; 0: never");
  flags.AddString("arrival", &arrival, "override [follower] arrival: estimate | homing | either");
  flags.AddDouble("tolerance-m", &tolerance_m,
                  "arrival tolerance [m] (default: [route] tolerance_m of the navigator config)");
  flags.AddString("alv", &alv,
                  "landmark ALV of the final approach: scale (with the config's consensus) | unit | weighted | config "
                  "(the homing config's [landmark_alv] variant)");
  flags.AddDouble("max-time-s", &max_time_s, "simulated time limit [s]; 0: from the route length");
  flags.AddInt("threads", &threads, "OpenCV threads");
  flags.AddString("sim-config", &sim_config_path, "simulator config (camera, mirror, panorama, robot noise, rates)");
  flags.AddString("camera", &camera, "camera preset, overrides --sim-config's [camera] preset: realistic | clean");
  flags.AddString("mask", &mask_source,
                  "self-occlusion mask of the raw frames: calibrated (calibrate-mirror's, from 60 frames of the camera) | "
                  "none | truth (the renderer's robot parts) | FILE; default: calibrated with the realistic camera, none "
                  "with the clean one");
  flags.AddString("placecells-config", &places_config_path, "place-cell config (view, measure, filter, localizer)");
  flags.AddString("homing-config", &homing_config_path, "homing config ([matching], [landmark_alv])");
  flags.AddString("navigator-config", &navigator_config_path,
                  "navigator config ([tracker], [follower], [route] tolerance_m)");
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (route != 1 && route != 2) throw glue::FlagError("--route must be 1 or 2");
  if (laps < 1) throw glue::FlagError("--laps must be >= 1");
  if (threads < 1) throw glue::FlagError("--threads must be >= 1");
  return true;
}

int EvalRouteApp::Run() {
  cv::setNumThreads(threads);

  eval::RouteEvalOptions o;
  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(sim_config_path), "");
  o.camera = sim.camera;
  eval::ApplyCameraFlag(camera, static_cast<uint64_t>(seed), &o.camera);
  o.mask = eval::MaskOrDefault(mask_source, o.camera);
  o.drive = sim.drive_options;
  o.physics_rate_hz = sim.physics_rate_hz;
  o.control_rate_hz = sim.camera_rate_hz;
  const auto places_ini = glue::IniFile::Load(places_config_path);
  o.view = glue::ReadPlaceViewOptions(places_ini);
  o.localizer = glue::ReadLocalizerOptions(places_ini);
  o.vocabulary = glue::ReadVocabularyOptions(places_ini);
  o.homing = glue::ReadLandmarkHoming(glue::IniFile::Load(homing_config_path), o.view.features.method);
  if (alv != "config") {
    const auto v = nav::ParseAlvVariant(alv);
    if (!v) throw glue::FlagError("--alv must be unit, weighted or scale, not '" + alv + "'");
    o.homing.alv.variant = *v;
  }
  const auto nav_config = processes::NavigatorConfig::FromIni(glue::IniFile::Load(navigator_config_path), "");
  o.tracker = nav_config.tracker;
  o.follower = nav_config.follower;
  if (!arrival.empty()) {
    const auto a = nav::ParseArrivalRule(arrival);
    if (!a) throw glue::FlagError("--arrival must be estimate, homing or either, not '" + arrival + "'");
    o.follower.arrival = *a;
  }
  o.tolerance_m = tolerance_m > 0 ? tolerance_m : nav_config.route_tolerance_m;
  o.route = route;
  o.laps = laps;
  o.seed = static_cast<uint64_t>(seed);
  o.cell_step = cell_step;
  o.waypoint_cells = !no_waypoint_cells;
  o.use_homing = !no_homing;
  o.homing_arrived_rad = homing_arrived_rad;
  o.localize_every = localize_every;
  o.max_time_s = max_time_s;
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }

  std::ostringstream effective;
  effective << "scene " << scene_name << ", route " << route << ", laps " << laps << ", seed " << seed << ", cell step "
            << cell_step << (o.waypoint_cells ? " + waypoint cells" : "") << ", localize every " << localize_every
            << " control step(s) at " << o.control_rate_hz << " Hz (physics " << o.physics_rate_hz << " Hz)"
            << ", homing " << (o.use_homing ? nav::AlvVariantName(o.homing.alv.variant) : "off")
            << ", homing_arrived_rad " << homing_arrived_rad << ", tolerance " << o.tolerance_m << " m, arrival "
            << nav::ArrivalRuleName(o.follower.arrival) << ", threads " << threads << "\n"
            << "configs: " << sim_config_path << ", " << places_config_path << ", " << homing_config_path << ", "
            << navigator_config_path << "\n";
  glue::PrintPlaceViewOptions(effective, o.view);
  glue::PrintLocalizerOptions(effective, o.localizer);
  processes::NavigatorConfig printed = nav_config;
  printed.tracker = o.tracker;
  printed.follower = o.follower;
  printed.route_tolerance_m = o.tolerance_m;
  printed.Print(effective);
  const std::string options_text = effective.str();
  std::cerr << "eval-route: effective options:\n";
  std::istringstream lines(options_text);
  for (std::string line; std::getline(lines, line);) std::cerr << "  " << line << "\n";

  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  bool replacing = false;
  const auto result = eval::RunRouteEval(scene, o, [&](const std::string& text, bool replace) {
    if (replacing && !replace) std::cerr << "\n";
    std::cerr << (replace ? "\r" : "") << "eval-route: " << text << (replace ? "\033[K" : "\n") << std::flush;
    replacing = replace;
  });
  if (replacing) std::cerr << "\n";
  eval::WriteRouteOutputs(result, o, out_dir, options_text);
  const auto& s = result.summary;
  std::cerr << "eval-route: " << result.scene << " route " << route << ": " << result.run.laps_completed << "/" << laps
            << " laps, waypoint error mean " << eval::Fixed(s.mean_m * 100, 1) << " cm, max "
            << eval::Fixed(s.max_m * 100, 1) << " cm";
  for (const auto& l : s.laps) {
    std::cerr << "; lap " << l.lap << " mean " << eval::Fixed(l.mean_m * 100, 1) << " max "
              << eval::Fixed(l.max_m * 100, 1);
  }
  std::cerr << " cm; growth " << eval::Fixed(s.growth_m_per_lap * 100, 2) << " cm/lap; odometry only: mean "
            << eval::Fixed(result.baseline_summary.mean_m * 100, 1) << " cm, max "
            << eval::Fixed(result.baseline_summary.max_m * 100, 1) << " cm; " << eval::Fixed(result.run.ms_per_step, 1)
            << " ms/step\neval-route: wrote " << out_dir << "/summary.json, report.md, trajectory.png\n";
  return 0;
}

}  // namespace snapnav::eval
