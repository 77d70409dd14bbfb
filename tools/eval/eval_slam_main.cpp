// eval-slam: dead reckoning and laser SLAM (thesis 5.3) run in lockstep over an LCM log of
// laser scans and odometry (made by log-import), with the absolute trajectory error against a
// reference: a CSV of utime,x,y,theta, or a CARMEN log of corrected poses whose scans are
// paired with the log's by identical ranges. With --icp-slam, MRPT's icp-slam runs on the
// rawlog or CARMEN log the LCM log was imported from (eval/icp_slam.hpp), beside ours: its
// trajectory is paired with ours by scan time and compared (RMS difference after SE(2)
// alignment, time per scan), and measured against the reference too.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <sstream>

#include "icp_slam.hpp"
#include "report_text.hpp"
#include "slam_log.hpp"
#include "slam_plot.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/laser_slam.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/plot/plot.hpp"
#include "snapnav/pose_t.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using eval::Fixed;
using eval::JsonString;

int Main(int argc, char** argv) {
  std::string log_path, reference_path, out_dir, icp_input;
  nav::LaserSlamOptions options;
  eval::IcpSlamOptions icp_options;
  glue::Flags flags("eval-slam",
                    "Runs dead reckoning and laser SLAM in lockstep over an LCM log of LASER_SCAN and ODOMETRY\n"
                    "(see log-import) and writes trajectories, a map image and summary.json; with --reference,\n"
                    "the ATE (RMSE after SE(2) alignment) of each against a CSV (utime,x,y,theta) or a CARMEN log\n"
                    "of corrected poses, paired with the log's scans by identical ranges. With --icp-slam, MRPT's\n"
                    "icp-slam runs beside it on the rawlog or CARMEN log the LCM log was imported from (work files\n"
                    "and the generated config in OUT/icp-slam/): time per scan, RMS difference from our trajectory\n"
                    "(paired by scan time, after SE(2) alignment) and its ATE against the reference.");
  flags.AddString("log", &log_path, "LCM log (required)");
  flags.AddString("reference", &reference_path, "reference trajectory: .csv or CARMEN log (.log, .clf, .gz)");
  flags.AddString("icp-slam", &icp_input,
                  "rawlog (.rawlog[.gz]) or CARMEN log the LCM log was imported from: run MRPT's icp-slam on it");
  flags.AddString("icp-slam-config", &icp_options.base_config, "icp-slam ini file the config is generated from");
  flags.AddString("icp-slam-bin", &icp_options.icp_slam, "the icp-slam program (name on PATH or path)");
  flags.AddDouble("match-distance-m", &options.match_distance_m, "laser slam: match distance [m]");
  flags.AddInt("icp-iterations", &options.icp_iterations, "laser slam: ICP iterations per scan");
  flags.AddDouble("map-resolution-m", &options.map_resolution_m, "laser slam: map cell [m]");
  flags.AddDouble("add-distance-m", &options.add_distance_m, "laser slam: new map point if nothing this close [m]");
  flags.AddInt("scan-step", &options.scan_step, "laser slam: use every n-th beam");
  bool sweep = false;
  flags.AddBool("sweep", &sweep,
                "with --reference: also run the laser slam at neighbouring settings (each of seven options one step\n"
                "down and up) and write the ATE of each and its min / median / max to sweep.md and sweep.csv");
  flags.AddString("out", &out_dir, "output folder (required)");
  if (!flags.Parse(argc, argv)) return 0;
  if (log_path.empty() || out_dir.empty()) throw glue::FlagError("--log LOG and --out DIR are required");
  options.Validate();
  if (!icp_input.empty() && !fs::is_regular_file(icp_input)) {
    throw glue::FlagError("--icp-slam " + icp_input + ": no such file");
  }
  fs::create_directories(out_dir);
  const fs::path out(out_dir);

  const eval::SlamLog log = eval::LoadSlamLog(log_path);
  const eval::SlamRun run = eval::RunSlam(log, options);
  const double ms_per_scan = run.ms_per_scan();
  std::cerr << "eval-slam: laser slam " << ms_per_scan << " ms/scan, map " << run.map.size() << " points\n";
  // The thesis' own procedure (5.3.1) beside it: point-to-point ICP at one match distance, no
  // heading search, the odometry noise of dead reckoning.
  nav::LaserSlamOptions thesis = options;
  thesis.metric = nav::IcpMetric::kPointToPoint;
  thesis.match_distance_m = thesis.match_distance_start_m = 0.25;
  thesis.search_window_max_rad = 0;
  thesis.motion = nav::DeadReckoningOptions{};
  thesis.turn_noise_rad_per_rad = 0;
  thesis.stale_odometry = false;
  thesis.update_score_margin = 0;
  thesis.lookup_cell_m = 0;  // the exact nearest map point
  const eval::SlamRun thesis_run = eval::RunSlam(log, thesis);
  std::cerr << "eval-slam: thesis configuration " << thesis_run.ms_per_scan() << " ms/scan\n";

  std::ostringstream json;
  json << std::fixed << std::setprecision(4) << "{\n  \"log\": " << JsonString(log_path)
       << ",\n  \"scans\": " << log.scans << ",\n  \"beams\": " << log.beams << ",\n  \"odometry\": " << log.odometry
       << ",\n  \"rejected\": " << log.rejected << ",\n  \"log_damaged_places\": " << log.damaged_places
       << ",\n  \"log_damaged_bytes\": " << log.damaged_bytes << ",\n  \"laser_slam_ms_per_scan\": " << ms_per_scan
       << ",\n  \"map_points\": " << run.map.size() << ",\n  \"thesis_slam_ms_per_scan\": " << thesis_run.ms_per_scan();
  std::vector<std::vector<nav::Pose2>> tracks = {run.slam, run.dead_reckoning};
  std::vector<std::string> names = {"laser slam", "dead reckoning"};
  std::string title = "laser slam on " + fs::path(log_path).filename().string();

  // MRPT's icp-slam beside it.
  std::optional<eval::IcpSlamRun> icp;
  std::optional<eval::IcpSlamComparison> cmp;
  if (!icp_input.empty()) {
    icp = eval::RunIcpSlam(icp_input, (out / "icp-slam").string(), icp_options);
    cmp = eval::CompareWithIcpSlam(run.utime, run.slam, icp->poses);
    const double ratio = ms_per_scan > 0 ? icp->ms_per_scan() / ms_per_scan : 0;
    std::cerr << std::fixed << std::setprecision(3) << "eval-slam: side by side on " << cmp->paired << " of "
              << run.slam.size() << " scans (icp-slam has " << icp->poses.size() << "):\n"
              << "  laser slam  " << ms_per_scan << " ms/scan\n"
              << "  icp-slam    " << icp->ms_per_scan() << " ms/scan (its own timing of its SLAM steps; "
              << icp->wall_ms_per_scan() << " ms/scan wall, whole process)\n"
              << "  ratio icp-slam/laser slam " << std::setprecision(2) << ratio << "x; trajectories differ by "
              << std::setprecision(3) << cmp->difference.rmse_m << " m RMS (max " << cmp->difference.max_m
              << " m) after SE(2) alignment\n";
    json << ",\n  \"icp_slam_input\": " << JsonString(icp_input)
         << ",\n  \"icp_slam_config\": " << JsonString(icp->config)
         << ",\n  \"icp_slam_rawlog_entries\": " << icp->steps << ",\n  \"icp_slam_scans\": " << icp->poses.size()
         << ",\n  \"icp_slam_scans_paired\": " << cmp->paired << ",\n  \"icp_slam_ms_per_scan\": " << icp->ms_per_scan()
         << ",\n  \"icp_slam_wall_ms_per_scan\": " << icp->wall_ms_per_scan()
         << ",\n  \"icp_slam_over_laser_slam_time_ratio\": " << ratio
         << ",\n  \"laser_slam_vs_icp_slam_rms_m\": " << cmp->difference.rmse_m
         << ",\n  \"laser_slam_vs_icp_slam_max_m\": " << cmp->difference.max_m;
    // icp-slam's track in our frame.
    const nav::Pose2 to_slam = cmp->slam_to_icp.Inverse();
    std::vector<nav::Pose2> track;
    for (const auto& p : cmp->icp_at_scans) {
      if (p) track.push_back(to_slam.Compose(*p));
    }
    tracks.push_back(track);
    names.push_back("icp-slam (MRPT)");
    std::ofstream csv(out / "icp_slam_trajectory.csv");
    csv << "utime,icp_x_m,icp_y_m,icp_theta_rad\n" << std::setprecision(9);
    for (const auto& p : icp->poses)
      csv << p.utime << "," << p.pose.x_m << "," << p.pose.y_m << "," << p.pose.theta_rad << "\n";
  }

  if (!reference_path.empty()) {
    const eval::Reference ref = eval::LoadReference(reference_path);
    const auto slam_pairs = eval::PairWithReference(run.slam, run, ref);
    const auto dr_pairs = eval::PairWithReference(run.dead_reckoning, run, ref);
    if (slam_pairs.size() < 2) throw std::runtime_error("fewer than 2 scans of the log pair with the reference");
    const auto slam_ate = nav::ComputeAte(slam_pairs, nav::AlignSE2(slam_pairs));
    const auto dr_ate = nav::ComputeAte(dr_pairs, nav::AlignSE2(dr_pairs));
    const auto thesis_pairs = eval::PairWithReference(thesis_run.slam, thesis_run, ref);
    const auto thesis_ate = nav::ComputeAte(thesis_pairs, nav::AlignSE2(thesis_pairs));
    std::cerr << "eval-slam: " << slam_pairs.size() << " scans paired with the reference; ATE RMSE: laser slam "
              << slam_ate.rmse_m << " m, thesis configuration " << thesis_ate.rmse_m << " m, dead reckoning "
              << dr_ate.rmse_m << " m\n";
    json << ",\n  \"thesis_slam_ate_rmse_m\": " << thesis_ate.rmse_m;
    json << ",\n  \"reference\": " << JsonString(reference_path) << ",\n  \"reference_pairs\": " << slam_pairs.size()
         << ",\n  \"laser_slam_ate_rmse_m\": " << slam_ate.rmse_m << ",\n  \"laser_slam_ate_max_m\": " << slam_ate.max_m
         << ",\n  \"dead_reckoning_ate_rmse_m\": " << dr_ate.rmse_m
         << ",\n  \"dead_reckoning_ate_max_m\": " << dr_ate.max_m;
    std::string ate_title =
        "ATE " + Fixed(slam_ate.rmse_m, 3) + " m (dead reckoning " + Fixed(dr_ate.rmse_m, 3) + " m)";
    if (cmp) {
      // icp-slam's poses at our scans that have a reference pose.
      std::vector<std::pair<nav::Pose2, nav::Pose2>> icp_pairs;
      for (size_t i = 0; i < run.slam.size(); ++i) {
        if (!cmp->icp_at_scans[i]) continue;
        if (const auto truth = ref.Find(run.ranges_key[i], run.utime[i]))
          icp_pairs.push_back({*cmp->icp_at_scans[i], *truth});
      }
      if (icp_pairs.size() < 2) throw std::runtime_error("fewer than 2 of icp-slam's poses pair with the reference");
      const auto icp_ate = nav::ComputeAte(icp_pairs, nav::AlignSE2(icp_pairs));
      std::cerr << "eval-slam: icp-slam ATE RMSE " << icp_ate.rmse_m << " m over " << icp_pairs.size() << " scans\n";
      json << ",\n  \"icp_slam_reference_pairs\": " << icp_pairs.size()
           << ",\n  \"icp_slam_ate_rmse_m\": " << icp_ate.rmse_m << ",\n  \"icp_slam_ate_max_m\": " << icp_ate.max_m;
      // The title line holds about 85 characters.
      ate_title = "ATE laser slam " + Fixed(slam_ate.rmse_m, 2) + ", dead reckoning " + Fixed(dr_ate.rmse_m, 2) +
                  ", icp-slam " + Fixed(icp_ate.rmse_m, 2) + " m; slam vs icp-slam " +
                  Fixed(cmp->difference.rmse_m, 2) + " m";
    }
    if (sweep) {
      // Sensitivity: the ATE at neighbouring settings, one option changed at a time.
      struct Variant {
        std::string name;
        nav::LaserSlamOptions options;
      };
      std::vector<Variant> variants = {{"as configured", options}};
      const auto add = [&](const std::string& name, auto change) {
        nav::LaserSlamOptions o = options;
        change(o);
        variants.push_back({name, o});
      };
      for (const double f : {0.9, 1.1}) {
        add("match_distance_m x" + Fixed(f, 1), [f](auto& o) { o.match_distance_m *= f; });
        add("match_distance_start_m x" + Fixed(f - 0.1 * (f < 1 ? 1 : -1), 1),
            [f](auto& o) { o.match_distance_start_m *= f < 1 ? 0.8 : 1.2; });
        add("rotation_noise_rad_per_rad x" + Fixed(f < 1 ? 0.75 : 1.25, 2),
            [f](auto& o) { o.motion.rotation_noise_rad_per_rad *= f < 1 ? 0.75 : 1.25; });
        add("translation_noise_m_per_m x" + Fixed(f < 1 ? 0.8 : 1.2, 1),
            [f](auto& o) { o.motion.translation_noise_m_per_m *= f < 1 ? 0.8 : 1.2; });
        add("search_sigmas " + Fixed(options.search_sigmas + (f < 1 ? -0.5 : 0.5), 1),
            [f](auto& o) { o.search_sigmas += f < 1 ? -0.5 : 0.5; });
        add("turn_noise_rad_per_rad x" + Fixed(f < 1 ? 0.8 : 1.2, 1),
            [f](auto& o) { o.turn_noise_rad_per_rad *= f < 1 ? 0.8 : 1.2; });
        add("update_score_margin x" + Fixed(f < 1 ? 0.6 : 1.4, 1),
            [f](auto& o) { o.update_score_margin *= f < 1 ? 0.6 : 1.4; });
      }
      std::vector<double> ates;
      std::ofstream csv(out / "sweep.csv");
      std::ostringstream md;
      csv << "setting,ate_rmse_m,ate_max_m,ms_per_scan\n";
      md << "# eval-slam sweep: ATE at neighbouring settings\n\n| setting | ATE RMSE [m] | max [m] |\n|---|---|---|\n";
      for (const Variant& v : variants) {
        v.options.Validate();
        const eval::SlamRun r = eval::RunSlam(log, v.options);
        const auto pairs = eval::PairWithReference(r.slam, r, ref);
        const auto ate = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
        ates.push_back(ate.rmse_m);
        csv << v.name << "," << ate.rmse_m << "," << ate.max_m << "," << r.ms_per_scan() << "\n";
        md << "| " << v.name << " | " << Fixed(ate.rmse_m, 3) << " | " << Fixed(ate.max_m, 3) << " |\n";
        std::cerr << "eval-slam: sweep " << v.name << ": ATE " << Fixed(ate.rmse_m, 4) << " m\n";
      }
      std::vector<double> sorted = ates;
      std::sort(sorted.begin(), sorted.end());
      const double median = sorted[sorted.size() / 2];
      md << "\n" << ates.size() << " runs: min " << Fixed(sorted.front(), 3) << " m, median " << Fixed(median, 3)
         << " m, max " << Fixed(sorted.back(), 3) << " m\n";
      std::ofstream(out / "sweep.md") << md.str();
      std::cerr << "eval-slam: sweep of " << ates.size() << " settings: ATE min " << Fixed(sorted.front(), 4)
                << " m, median " << Fixed(median, 4) << " m, max " << Fixed(sorted.back(), 4) << " m (sweep.md)\n";
      json << ",\n  \"sweep_runs\": " << ates.size() << ",\n  \"sweep_ate_rmse_min_m\": " << sorted.front()
           << ",\n  \"sweep_ate_rmse_median_m\": " << median << ",\n  \"sweep_ate_rmse_max_m\": " << sorted.back();
    }
    title = cmp ? ate_title : title + ": " + ate_title;
    // Draw the reference in the SLAM frame.
    const nav::Pose2 to_slam = nav::AlignSE2(slam_pairs).Inverse();
    std::vector<nav::Pose2> ref_track;
    for (const auto& [est, truth] : slam_pairs) ref_track.push_back(to_slam.Compose(truth));
    tracks.push_back(ref_track);
    names.push_back("reference");
  }
  if (cmp && reference_path.empty()) {
    title += "; vs icp-slam: " + Fixed(cmp->difference.rmse_m, 3) + " m RMS, time ratio " +
             Fixed(icp->ms_per_scan() / std::max(ms_per_scan, 1e-9), 2);
  }
  json << "\n}\n";
  std::ofstream(out / "summary.json") << json.str();
  plot::SavePng(eval::DrawRun(tracks, names, run.map, title), (out / "trajectories.png").string());
  {
    std::ofstream csv(out / "trajectories.csv");
    csv << "utime,slam_x_m,slam_y_m,slam_theta_rad,dr_x_m,dr_y_m,dr_theta_rad\n" << std::setprecision(9);
    for (size_t i = 0; i < run.slam.size(); ++i) {
      const nav::Pose2 &s = run.slam[i], &d = run.dead_reckoning[i];
      csv << run.utime[i] << "," << s.x_m << "," << s.y_m << "," << s.theta_rad << "," << d.x_m << "," << d.y_m << ","
          << d.theta_rad << "\n";
    }
  }
  std::cerr << "eval-slam: wrote " << (out / "summary.json").string() << ", trajectories.png, trajectories.csv"
            << (icp ? ", icp_slam_trajectory.csv, icp-slam/" : "") << "\n";
  if (log.damaged_places > 0) {
    std::cerr << "eval-slam: warning: " << log_path << " is damaged (" << log.damaged_places << " place(s), "
              << log.damaged_bytes << " bytes skipped, see above): evaluated its intact events\n";
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
