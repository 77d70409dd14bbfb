// slam-sim-eval's app (slam_sim_app.hpp): dead reckoning and laser SLAM on a simulated route with ground
// truth. The simulator (configured by config/sim.ini, as the sim process) drives a scene's route for a
// number of laps with odometry noise and heading drift; both estimators run over its odometry and scans
// (eval::RunSlam, as eval-slam); their absolute trajectory error (with and without alignment: both start
// at the true start pose) and relative pose error per --rpe-delta-m of travel go to summary.json with the
// figures.
#include "slam_sim_app.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "json_values.hpp"
#include "results.hpp"
#include "slam_plot.hpp"
#include "slam_sim.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/plot/plot.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using eval::R4;

void PrintErrors(std::ostream& o, const std::string& name, const eval::TrajectoryErrors& e) {
  o << std::fixed << std::setprecision(3) << "  " << std::left << std::setw(15) << name << std::right << " ATE RMSE "
    << e.ate.rmse_m << " m (max " << e.ate.max_m << ", final " << e.ate.final_m << "), aligned " << e.ate_aligned.rmse_m
    << " m; RPE per " << e.rpe.delta_m << " m: " << e.rpe.translation_rmse_m << " m, " << e.rpe.rotation_rmse_deg
    << " deg RMSE\n";
}

void JsonErrors(results::Json& j, const std::string& key, const eval::TrajectoryErrors& e) {
  j[key + "_ate_rmse_m"] = R4(e.ate_aligned.rmse_m);
  j[key + "_ate_max_m"] = R4(e.ate_aligned.max_m);
  j[key + "_ate_unaligned_rmse_m"] = R4(e.ate.rmse_m);
  j[key + "_ate_unaligned_max_m"] = R4(e.ate.max_m);
  j[key + "_ate_unaligned_final_m"] = R4(e.ate.final_m);
  j[key + "_rpe_translation_rmse_m"] = R4(e.rpe.translation_rmse_m);
  j[key + "_rpe_translation_max_m"] = R4(e.rpe.translation_max_m);
  j[key + "_rpe_rotation_rmse_deg"] = R4(e.rpe.rotation_rmse_deg);
  j[key + "_rpe_rotation_max_deg"] = R4(e.rpe.rotation_max_deg);
}

// Position error (no alignment) against the distance travelled, per estimator.
cv::Mat DrawErrors(const eval::SimSlamEvaluation& e) {
  plot::Series slam{"laser slam", {}, {}}, dr{"dead reckoning", {}, {}};
  double travelled = 0;
  const size_t every = std::max<size_t>(1, e.truth.size() / 400);  // a readable number of markers
  for (size_t i = 0; i < e.truth.size(); ++i) {
    if (i > 0) travelled += std::hypot(e.truth[i].x_m - e.truth[i - 1].x_m, e.truth[i].y_m - e.truth[i - 1].y_m);
    if (i % every != 0 && i + 1 != e.truth.size()) continue;
    for (auto [series, est] : {std::pair{&slam, &e.run.slam}, std::pair{&dr, &e.run.dead_reckoning}}) {
      series->x.push_back(travelled);
      series->y.push_back(std::hypot((*est)[i].x_m - e.truth[i].x_m, (*est)[i].y_m - e.truth[i].y_m));
    }
  }
  plot::Axes axes;
  axes.title = "position error against the ground truth (no alignment)";
  axes.x_label = "distance travelled [m]";
  axes.y_label = "error [m]";
  axes.y_from_zero = true;
  return plot::LineChart(axes, {slam, dr}, {900, 500});
}


}  // namespace

namespace snapnav::eval {

bool SlamSimEvalApp::Initialize(int argc, char** argv) {
  glue::Flags flags("slam-sim-eval",
                    "Dead reckoning and laser SLAM on a simulated route with ground truth: drives the scene's\n"
                    "route for --laps laps (or --duration-s) with the sim's odometry noise and heading drift\n"
                    "(--config), runs both estimators over odometry and scans as eval-slam does, and writes the\n"
                    "ATE (with and without SE(2) alignment) and the RPE over --rpe-delta-m of travel to\n"
                    "summary.json (*_ate_rmse_m aligned, as eval-slam; *_ate_unaligned_* from the common start),\n"
                    "with trajectories.png, errors.png and trajectories.csv. --write-log also writes\n"
                    "the messages (sim.lcmlog: LASER_SCAN, ODOMETRY, POSE_GROUND_TRUTH) and reference.csv, for\n"
                    "eval-slam --log DIR/sim.lcmlog --reference DIR/reference.csv or a replay on the bus.");
  flags.AddString("config", &config_path, "simulator configuration: robot, laser, rates, seed");
  flags.AddString("scene", &scene, "scene name (config/scenes/NAME.scene) or file");
  flags.AddInt("laps", &laps, "laps of the scene's route to drive (0: use --duration-s)");
  flags.AddDouble("duration-s", &duration_s, "simulated seconds to drive (0: use --laps)");
  flags.AddInt("seed", &seed, "random seed (default: the config's)");
  flags.AddDouble("rpe-delta-m", &rpe_delta_m, "travelled distance of the relative pose error [m]");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddBool("write-log", &write_log, "also write sim.lcmlog and reference.csv into the output folder");
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (!(rpe_delta_m > 0)) throw glue::FlagError("--rpe-delta-m must be positive");

  return true;
}

int SlamSimEvalApp::Run() {
  const auto sim_config = processes::SimConfig::FromIni(glue::IniFile::Load(config_path), "");
  eval::SimSlamOptions options = eval::SimSlamOptions::FromSimConfig(sim_config);
  options.scene = scene;
  options.laps = laps;
  options.duration_s = duration_s;
  if (seed >= 0) options.seed = static_cast<uint64_t>(seed);
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  if (write_log) options.log_path = (out / "sim.lcmlog").string();
  options.Validate();
  const nav::LaserSlamOptions slam_options;  // the defaults, as eval-slam
  slam_options.Validate();

  const auto& d = options.drive;
  std::cerr << "slam-sim-eval: config " << config_path << ": scene " << scene << ", laps " << laps << ", duration_s "
            << duration_s << ", seed " << options.seed << ", speed " << options.route_speed_mps << " m/s, odometry "
            << options.odometry_rate_hz << " Hz, laser " << options.laser_rate_hz << " Hz (" << options.laser.beams
            << " beams, " << options.laser.range_max_m << " m, noise " << options.laser.range_noise_m << " m)\n"
            << "slam-sim-eval: robot: heading drift " << d.heading_drift_deg_per_m << " deg/m, speed noise "
            << d.linear_noise_frac << ", turn noise " << d.angular_noise_radps << " rad/s; odometry noise "
            << d.odometry_linear_noise_frac << " (distance), " << d.odometry_angular_noise_frac << " (turn)\n"
            << "slam-sim-eval: laser slam: match " << slam_options.match_distance_m << " m, icp "
            << slam_options.icp_iterations << " iterations, map " << slam_options.map_resolution_m << " m, add "
            << slam_options.add_distance_m << " m, scan step " << slam_options.scan_step << "\n";

  const eval::SimulatedSlamLog sim = eval::SimulateSlamLog(options);
  std::cerr << "slam-sim-eval: simulated " << sim.duration_s << " s, " << sim.laps << " laps, " << sim.distance_m
            << " m, " << sim.log.scans << " scans, " << sim.log.odometry << " odometry, " << sim.collisions
            << " blocked steps\n";
  const eval::SimSlamEvaluation e = eval::EvaluateSimulatedSlam(sim, slam_options, rpe_delta_m);

  results::Json json;
  json["scene"] = sim.scene_name;
  json["seed"] = options.seed;
  json["laps"] = sim.laps;
  json["duration_s"] = R4(sim.duration_s);
  json["distance_m"] = R4(sim.distance_m);
  json["scans"] = sim.log.scans;
  json["odometry"] = sim.log.odometry;
  json["blocked_steps"] = sim.collisions;
  json["heading_drift_deg_per_m"] = R4(d.heading_drift_deg_per_m);
  json["odometry_linear_noise_frac"] = R4(d.odometry_linear_noise_frac);
  json["odometry_angular_noise_frac"] = R4(d.odometry_angular_noise_frac);
  json["laser_slam_ms_per_scan"] = R4(e.run.ms_per_scan());
  json["map_points"] = e.run.map.size();
  json["rpe_delta_m"] = R4(rpe_delta_m);
  json["rpe_segments"] = e.laser_slam.rpe.segments;
  JsonErrors(json, "laser_slam", e.laser_slam);
  JsonErrors(json, "dead_reckoning", e.dead_reckoning);
  results::WriteJsonFile((out / "summary.json").string(), json);

  // Figures in the scene's frame, so the map looks like the floor plan.
  auto in_scene = [&](const std::vector<nav::Pose2>& track) {
    std::vector<nav::Pose2> t;
    for (const auto& p : track) t.push_back(sim.start.Compose(p));
    return t;
  };
  std::vector<Eigen::Vector2d> map;
  for (const auto& p : e.run.map) map.push_back(sim.start.Transform(p));
  std::ostringstream title;
  title << std::fixed << std::setprecision(3) << sim.scene_name << ", " << sim.distance_m << " m: ATE laser slam "
        << e.laser_slam.ate.rmse_m << " m, dead reckoning " << e.dead_reckoning.ate.rmse_m << " m";
  plot::SavePng(eval::DrawRun({in_scene(e.run.slam), in_scene(e.run.dead_reckoning), in_scene(e.truth)},
                              {"laser slam", "dead reckoning", "ground truth"}, map, title.str()),
                (out / "trajectories.png").string());
  plot::SavePng(DrawErrors(e), (out / "errors.png").string());
  {
    std::ofstream csv(out / "trajectories.csv");
    csv << "utime,truth_x_m,truth_y_m,truth_theta_rad,slam_x_m,slam_y_m,slam_theta_rad,dr_x_m,dr_y_m,dr_theta_rad\n"
        << std::setprecision(9);
    for (size_t i = 0; i < e.truth.size(); ++i) {
      csv << e.run.utime[i];
      for (const nav::Pose2* p : {&e.truth[i], &e.run.slam[i], &e.run.dead_reckoning[i]}) {
        csv << "," << p->x_m << "," << p->y_m << "," << p->theta_rad;
      }
      csv << "\n";
    }
  }
  if (write_log) {
    std::ofstream csv(out / "reference.csv");
    csv << "utime,x_m,y_m,theta_rad\n" << std::setprecision(9);
    for (const auto& p : sim.reference.by_time)
      csv << p.utime << "," << p.pose.x_m << "," << p.pose.y_m << "," << p.pose.theta_rad << "\n";
  }

  std::cout << "slam-sim-eval: " << sim.scene_name << ", " << sim.laps << " laps, " << std::fixed
            << std::setprecision(1) << sim.distance_m << " m in " << sim.duration_s << " s, " << sim.log.scans
            << " scans, laser slam " << std::setprecision(2) << e.run.ms_per_scan() << " ms/scan, map "
            << e.run.map.size() << " points\n";
  PrintErrors(std::cout, "laser slam", e.laser_slam);
  PrintErrors(std::cout, "dead reckoning", e.dead_reckoning);
  std::cerr << "slam-sim-eval: wrote " << (out / "summary.json").string()
            << ", trajectories.png, errors.png, trajectories.csv"
            << (write_log ? ", sim.lcmlog (" + std::to_string(sim.log_events) + " messages), reference.csv" : "")
            << "\n";
  return 0;
}

}  // namespace snapnav::eval
