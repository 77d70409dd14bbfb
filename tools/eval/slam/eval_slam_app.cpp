// eval-slam's app (eval_slam_app.hpp): dead reckoning and laser SLAM (thesis 5.3) run in lockstep over an
// LCM log of laser scans and odometry (made by log-import), with the absolute trajectory error against a
// reference: a CSV of utime,x,y,theta, or a CARMEN log of corrected poses whose scans are paired with
// the log's by identical ranges (or their near readings). With --icp-slam, MRPT's icp-slam runs on the rawlog or CARMEN log the
// LCM log was imported from (icp_slam.hpp), beside ours: its trajectory is paired with ours by scan time
// and compared (RMS difference after SE(2) alignment, time per scan), and measured against the
// reference too.
#include "eval_slam_app.hpp"

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
#include "json_values.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "slam_config.hpp"
#include "slam_log.hpp"
#include "slam_plot.hpp"
#include "slam_graph.hpp"
#include "slam_suite.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/plot/plot.hpp"
#include "snapnav/pose_t.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using eval::Fixed;


}  // namespace

namespace snapnav::eval {

bool EvalSlamApp::Initialize(int argc, char** argv) {
  glue::Flags flags("eval-slam",
                    "Runs dead reckoning and laser SLAM in lockstep over an LCM log of LASER_SCAN and ODOMETRY\n"
                    "(see log-import) and writes trajectories, a map image and summary.json; with --reference,\n"
                    "the ATE (RMSE after SE(2) alignment) of each against a CSV (utime,x,y,theta) or MRPT's\n"
                    "ground truth (.txt: timestamp x y phi), paired by time, or a CARMEN log of corrected poses,\n"
                    "paired with the log's scans by identical ranges (or by the readings below the lower maximum\n"
                    "range, where the log's laser reaches less far), and the reference checked against the scans\n"
                    "(reference_suspects.csv: poses whose scan fits clearly better turned). With --icp-slam, MRPT's\n"
                    "icp-slam runs beside it on the rawlog or CARMEN log the LCM log was imported from (work files\n"
                    "and the generated config in OUT/icp-slam/): time per scan, RMS difference from our trajectory\n"
                    "(paired by scan time, after SE(2) alignment) and its ATE against the reference. The laser SLAM\n"
                    "runs the [laser_slam] options of --config (default: the shipped config/laser_slam.ini), with\n"
                    "--set overrides; the effective options are printed. The trajectory is each scan's pose.\n"
                    "Odometry's systematic errors (heading drift per metre, turn and distance scale) as the\n"
                    "matches calibrate them are printed and written (summary.json odometry_*, scans.csv), with\n"
                    "--reference also as the reference's motion implies them (reference_odometry_*).");
  flags.AddString("log", &log_path, "LCM log (required)");
  flags.AddString("reference", &reference_path, "reference trajectory: .csv, MRPT ground truth (.txt) or CARMEN log (.log, .clf, .gz)");
  flags.AddString("icp-slam", &icp_input,
                  "rawlog (.rawlog[.gz]) or CARMEN log the LCM log was imported from: run MRPT's icp-slam on it");
  flags.AddString("icp-slam-config", &icp_options.base_config, "icp-slam ini file the config is generated from");
  flags.AddString("icp-slam-bin", &icp_options.icp_slam, "the icp-slam program (name on PATH or path)");
  flags.AddString("config", &config.path, "laser-slam config whose [laser_slam] options the laser slam runs");
  flags.AddStringList("set", &sets, "override of one [laser_slam] key of --config, KEY=VALUE");
  flags.AddString("match-distance-m", &match_distance, "laser slam: match distance [m] (= --set match_distance_m=V)");
  flags.AddString("icp-iterations", &icp_iterations, "laser slam: ICP iterations per scan (= --set icp_iterations=V)");
  flags.AddString("map-resolution-m", &map_resolution, "laser slam: map cell [m] (= --set map_resolution_m=V)");
  flags.AddString("add-distance-m", &add_distance,
                  "laser slam: new map point if nothing this close [m] (= --set add_distance_m=V)");
  flags.AddString("scan-step", &scan_step, "laser slam: use every n-th beam (= --set scan_step=V)");
  flags.AddBool("sweep", &sweep,
                "with --reference: also run the laser slam at neighbouring settings (each of ten options one step\n"
                "down and up) and under tiny perturbations (search step, match distance, start heading sigma,\n"
                "search order), and write the ATE of each and the min / median / max to sweep.md and sweep.csv");
  flags.AddString("suite", &suite_path,
                  "run every entry of a suite file instead of one log (--suite alone: the shipped\n"
                  "config/slam_suite.ini): the laser SLAM (of the suite's config, with --set), the thesis\n"
                  "configuration, icp-slam and dead reckoning on each, against its reference; suite.md,\n"
                  "suite.csv, summary.json and a trajectory PNG per run in --out");
  flags.AddStringList("only", &only, "with --suite: run only this entry");
  flags.AddString("out", &out_dir, "output folder (required)");
  // `--suite` without a file (the last flag, or followed by another flag): the shipped suite.
  std::vector<std::string> args(argv, argv + argc);
  for (size_t i = 1; i < args.size(); ++i) {
    if (args[i] == "--suite" && (i + 1 == args.size() || args[i + 1].rfind("--", 0) == 0)) {
      args.insert(args.begin() + static_cast<std::ptrdiff_t>(i) + 1, SNAPNAV_CONFIG_DIR "/slam_suite.ini");
    }
  }
  std::vector<char*> ptrs;
  for (std::string& a : args) ptrs.push_back(a.data());
  if (!flags.Parse(static_cast<int>(ptrs.size()), ptrs.data())) return false;
  return true;
}

int EvalSlamApp::Run() {
  if (!suite_path.empty()) {
    if (out_dir.empty()) throw glue::FlagError("--suite needs --out DIR");
    eval::SuiteOptions so;
    so.overrides = sets;
    so.only = only;
    so.icp = icp_options;
    const eval::Suite suite = eval::LoadSuite(suite_path);
    const auto results = eval::RunSuite(suite, out_dir, so);
    for (const auto& r : results) {
      if (!r.skipped && !r.pass) return 2;
    }
    return 0;
  }
  if (log_path.empty() || out_dir.empty()) throw glue::FlagError("--log LOG and --out DIR are required");
  eval::AddOverride(&config, "match_distance_m", match_distance);
  eval::AddOverride(&config, "icp_iterations", icp_iterations);
  eval::AddOverride(&config, "map_resolution_m", map_resolution);
  eval::AddOverride(&config, "add_distance_m", add_distance);
  eval::AddOverride(&config, "scan_step", scan_step);
  config.overrides.insert(config.overrides.end(), sets.begin(), sets.end());
  options = eval::LoadLaserSlamOptions(config);
  std::cerr << "eval-slam: laser slam options of " << config.path;
  for (const std::string& o : config.overrides) std::cerr << ", " << o;
  std::cerr << ":\n";
  eval::PrintLaserSlamOptions(std::cerr, options);
  if (!icp_input.empty() && !fs::is_regular_file(icp_input)) {
    throw glue::FlagError("--icp-slam " + icp_input + ": no such file");
  }
  fs::create_directories(out_dir);
  const fs::path out(out_dir);

  const eval::SlamLog log = eval::LoadSlamLog(log_path);
  // With backend = graph the laser SLAM is the graph back end: its optimized trajectory and map.
  const eval::SlamBackendChoice backend = eval::LoadSlamBackend(config);
  const eval::SlamRun run =
      backend.graph ? eval::RunGraphSlam(log, options, backend.options).run : eval::RunSlam(log, options);
  const double ms_per_scan = run.ms_per_scan();
  std::cerr << "eval-slam: laser slam" << (backend.graph ? " (graph back end)" : "") << " " << ms_per_scan
            << " ms/scan, map " << run.map.size() << " points\n";
  // The thesis' own procedure (5.3.1) beside it: point-to-point ICP at one match distance, no
  // heading search, the odometry noise of dead reckoning.
  const nav::LaserSlamOptions thesis = nav::ThesisLaserSlamOptions(options);
  const eval::SlamRun thesis_run = eval::RunSlam(log, thesis);
  std::cerr << "eval-slam: thesis configuration " << thesis_run.ms_per_scan() << " ms/scan\n";

  std::string overrides;
  for (const std::string& o : config.overrides) overrides += (overrides.empty() ? "" : "; ") + o;
  results::Json json;
  json["log"] = log_path;
  json["laser_slam_config"] = config.path;
  json["laser_slam_overrides"] = overrides;
  json["scans"] = R4(log.scans);
  json["beams"] = R4(log.beams);
  json["odometry"] = R4(log.odometry);
  json["rejected"] = R4(log.rejected);
  json["log_damaged_places"] = R4(log.damaged_places);
  json["log_damaged_bytes"] = R4(log.damaged_bytes);
  json["laser_slam_ms_per_scan"] = R4(ms_per_scan);
  json["map_points"] = run.map.size();
  json["thesis_slam_ms_per_scan"] = R4(thesis_run.ms_per_scan());
  {
    // Map consistency over every scan (the median distance of a scan's points to the scans seen on a
    // revisit): needs no reference, so it is the figure a lab's own log gives.
    const auto every_scan = [](const std::vector<nav::Pose2>& poses) {
      return std::vector<std::optional<nav::Pose2>>(poses.begin(), poses.end());
    };
    const auto figure = [](const eval::MapConsistency& c) {
      return c.scans > 0 ? Fixed(c.median_m, 4) + " m (" + std::to_string(c.scans) + " scans seen again)"
                         : std::string("- (no scan seen again)");
    };
    const eval::MapConsistency c_slam = eval::ComputeMapConsistency(log, every_scan(run.slam));
    const eval::MapConsistency c_thesis = eval::ComputeMapConsistency(log, every_scan(thesis_run.slam));
    const eval::MapConsistency c_dr = eval::ComputeMapConsistency(log, every_scan(run.dead_reckoning));
    std::cerr << "eval-slam: map consistency over every scan (no reference needed): laser slam " << figure(c_slam)
              << ", thesis configuration " << figure(c_thesis) << ", dead reckoning " << figure(c_dr) << "\n";
    if (c_slam.scans > 0) json["laser_slam_map_consistency_all_scans_m"] = R4(c_slam.median_m);
    if (c_thesis.scans > 0) json["thesis_slam_map_consistency_all_scans_m"] = R4(c_thesis.median_m);
    if (c_dr.scans > 0) json["dead_reckoning_map_consistency_all_scans_m"] = R4(c_dr.median_m);
  }
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
    json["icp_slam_input"] = icp_input;
    json["icp_slam_config"] = icp->config;
    json["icp_slam_rawlog_entries"] = R4(icp->steps);
    json["icp_slam_scans"] = icp->poses.size();
    json["icp_slam_scans_paired"] = R4(cmp->paired);
    json["icp_slam_ms_per_scan"] = R4(icp->ms_per_scan());
    json["icp_slam_wall_ms_per_scan"] = R4(icp->wall_ms_per_scan());
    json["icp_slam_over_laser_slam_time_ratio"] = R4(ratio);
    json["laser_slam_vs_icp_slam_rms_m"] = R4(cmp->difference.rmse_m);
    json["laser_slam_vs_icp_slam_max_m"] = R4(cmp->difference.max_m);
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

  const auto odometry_json = [&json](const std::string& prefix, const eval::OdometryFigure& f) {
    if (!f.measured) return;
    json[prefix + "drift_deg_per_m"] = R4(f.drift_deg_per_m);
    json[prefix + "turn_scale"] = R4(f.turn_scale);
    json[prefix + "distance_scale"] = R4(f.distance_scale);
    json[prefix + "stretches"] = f.stretches;
  };
  {
    // Odometry's systematic errors as the matches calibrate them (UMBmark from any log).
    const eval::OdometryFigure odometry = eval::SlamOdometryCalibration(run);
    std::cerr << "eval-slam: odometry as the scans calibrate it: " << eval::DescribeOdometry(odometry)
              << (options.odometry_calibration.apply ? " (applied)" : " (not applied: odometry_calibration = false)")
              << "\n";
    odometry_json("odometry_", odometry);
  }
  if (!reference_path.empty()) {
    const eval::Reference ref = eval::LoadReference(reference_path, &log);
    {
      const eval::OdometryFigure implied = eval::ReferenceOdometryCalibration(run, ref, options);
      std::cerr << "eval-slam: odometry against the reference's motion: " << eval::DescribeOdometry(implied) << "\n";
      odometry_json("reference_odometry_", implied);
    }
    const auto slam_pairs = eval::PairWithReference(run.slam, run, ref);
    const auto dr_pairs = eval::PairWithReference(run.dead_reckoning, run, ref);
    if (slam_pairs.size() < 2) throw std::runtime_error("fewer than 2 scans of the log pair with the reference");
    const auto slam_ate = nav::ComputeAte(slam_pairs, nav::AlignSE2(slam_pairs));
    {
      // Every scan with a reference pose: where along the run the error arises.
      std::ofstream csv(out / "reference_pairs.csv");
      csv << "scan,utime,slam_x_m,slam_y_m,slam_theta_rad,ref_x_m,ref_y_m,ref_theta_rad\n" << std::setprecision(9);
      for (size_t i = 0; i < run.slam.size(); ++i) {
        const auto truth = ref.Find(run.ranges_key[i], run.utime[i]);
        if (!truth) continue;
        const nav::Pose2& e = run.slam[i];
        csv << i << "," << run.utime[i] << "," << e.x_m << "," << e.y_m << "," << e.theta_rad << "," << truth->x_m
            << "," << truth->y_m << "," << truth->theta_rad << "\n";
      }
    }
    const auto dr_ate = nav::ComputeAte(dr_pairs, nav::AlignSE2(dr_pairs));
    {
      // Map consistency (a scan's points against the scans seen on a revisit) of our trajectory and
      // of the reference's, over the scans the reference has: which of the two draws the sharper map.
      std::vector<std::optional<nav::Pose2>> ours(run.slam.size()), theirs(run.slam.size());
      for (size_t i = 0; i < run.slam.size(); ++i) {
        if (const auto truth = ref.Find(run.ranges_key[i], run.utime[i])) {
          ours[i] = run.slam[i];
          theirs[i] = *truth;
        }
      }
      const eval::MapConsistency c_ours = eval::ComputeMapConsistency(log, ours);
      const eval::MapConsistency c_ref = eval::ComputeMapConsistency(log, theirs);
      std::cerr << "eval-slam: map consistency (median distance of a scan's points to revisited scans): laser slam "
                << c_ours.median_m << " m, reference " << c_ref.median_m << " m\n";
      json["laser_slam_map_consistency_m"] = R4(c_ours.median_m);
      json["reference_map_consistency_m"] = R4(c_ref.median_m);
    }
    {
      // The reference's own consistency: poses its scans contradict (a corrected log is another
      // SLAM's output).
      const eval::ReferenceCheck check = eval::CheckReference(log, ref);
      std::cerr << "eval-slam: reference check: " << eval::DescribeReferenceCheck(check) << "\n";
      eval::WriteReferenceCheckCsv((out / "reference_suspects.csv").string(), check);
      json["reference_checked_poses"] = check.checked;
      json["reference_suspect_poses"] = check.suspects.size();
    }
    const auto thesis_pairs = eval::PairWithReference(thesis_run.slam, thesis_run, ref);
    const auto thesis_ate = nav::ComputeAte(thesis_pairs, nav::AlignSE2(thesis_pairs));
    std::cerr << "eval-slam: " << slam_pairs.size() << " scans paired with the reference; ATE RMSE: laser slam "
              << slam_ate.rmse_m << " m, thesis configuration " << thesis_ate.rmse_m << " m, dead reckoning "
              << dr_ate.rmse_m << " m\n";
    json["thesis_slam_ate_rmse_m"] = R4(thesis_ate.rmse_m);
    json["reference"] = reference_path;
    json["reference_pairs"] = slam_pairs.size();
    json["laser_slam_ate_rmse_m"] = R4(slam_ate.rmse_m);
    json["laser_slam_ate_max_m"] = R4(slam_ate.max_m);
    json["dead_reckoning_ate_rmse_m"] = R4(dr_ate.rmse_m);
    json["dead_reckoning_ate_max_m"] = R4(dr_ate.max_m);
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
      json["icp_slam_reference_pairs"] = icp_pairs.size();
      json["icp_slam_ate_rmse_m"] = R4(icp_ate.rmse_m);
      json["icp_slam_ate_max_m"] = R4(icp_ate.max_m);
      // The title line holds about 85 characters.
      ate_title = "ATE laser slam " + Fixed(slam_ate.rmse_m, 2) + ", dead reckoning " + Fixed(dr_ate.rmse_m, 2) +
                  ", icp-slam " + Fixed(icp_ate.rmse_m, 2) + " m; slam vs icp-slam " +
                  Fixed(cmp->difference.rmse_m, 2) + " m";
    }
    if (sweep) {
      // Sensitivity: the ATE at neighbouring settings (one option a step down and up), and under
      // perturbations too small to matter (a result that flips under them is chance).
      struct Variant {
        std::string group, name;
        nav::LaserSlamOptions options;
      };
      std::vector<Variant> variants = {{"configured", "as configured", options}};
      const auto add = [&](const std::string& group, const std::string& name, auto change) {
        nav::LaserSlamOptions o = options;
        change(o);
        variants.push_back({group, name, o});
      };
      const std::string n = "neighbour", p = "perturbation";
      for (const bool up : {false, true}) {
        const auto x = [up](double down_factor, double up_factor) { return up ? up_factor : down_factor; };
        add(n, "match_distance_m x" + Fixed(x(0.9, 1.1), 1), [&](auto& o) { o.match_distance_m *= x(0.9, 1.1); });
        add(n, "match_distance_start_m x" + Fixed(x(0.8, 1.2), 1),
            [&](auto& o) { o.match_distance_start_m *= x(0.8, 1.2); });
        add(n, "rotation_noise_rad_per_rad x" + Fixed(x(0.75, 1.25), 2),
            [&](auto& o) { o.motion.rotation_noise_rad_per_rad *= x(0.75, 1.25); });
        add(n, "translation_noise_m_per_m x" + Fixed(x(0.8, 1.2), 1),
            [&](auto& o) { o.motion.translation_noise_m_per_m *= x(0.8, 1.2); });
        add(n, "search_sigmas " + Fixed(options.search_sigmas + x(-0.5, 0.5), 1),
            [&](auto& o) { o.search_sigmas += x(-0.5, 0.5); });
        add(n, "turn_noise_rad_per_rad x" + Fixed(x(0.8, 1.2), 1),
            [&](auto& o) { o.turn_noise_rad_per_rad *= x(0.8, 1.2); });
        add(n, "update_score_margin x" + Fixed(x(0.6, 1.4), 1), [&](auto& o) { o.update_score_margin *= x(0.6, 1.4); });
        if (options.matcher == nav::ScanMatcher::kCorrelative) {
          add(n, "search_sigma_m x" + Fixed(x(0.8, 1.2), 1), [&](auto& o) { o.search_sigma_m *= x(0.8, 1.2); });
          add(n, "search_window_xy_m x" + Fixed(x(0.8, 1.2), 1), [&](auto& o) { o.search_window_xy_m *= x(0.8, 1.2); });
          add(n, "search_prior_weight x" + Fixed(x(0.5, 2), 1), [&](auto& o) { o.search_prior_weight *= x(0.5, 2); });
        }
        // Tiny perturbations.
        add(p, "search_step_deg x" + Fixed(x(0.9996, 1.0004), 4),
            [&](auto& o) { o.search_step_rad *= x(0.9996, 1.0004); });
        add(p, "initial_sigma_theta_deg x" + Fixed(x(0.99, 1.01), 2),
            [&](auto& o) { o.initial_sigma_theta_rad *= x(0.99, 1.01); });
        add(p, "match_distance_m x" + Fixed(x(0.999, 1.001), 3),
            [&](auto& o) { o.match_distance_m *= x(0.999, 1.001); });
      }
      add(p, "search order reversed (ties resolved the other way)", [](auto& o) { o.search_order_reversed = true; });
      std::map<std::string, std::vector<double>> ates;  // by group, and "all"
      std::ofstream csv(out / "sweep.csv");
      std::ostringstream md;
      csv << "group,setting,ate_rmse_m,ate_max_m,ms_per_scan\n";
      md << "# eval-slam sweep: ATE at neighbouring settings and under tiny perturbations\n\n"
         << "| group | setting | ATE RMSE [m] | max [m] |\n|---|---|---|---|\n";
      for (const Variant& v : variants) {
        v.options.Validate();
        const eval::SlamRun r = eval::RunSlam(log, v.options);
        const auto pairs = eval::PairWithReference(r.slam, r, ref);
        const auto ate = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
        ates["all"].push_back(ate.rmse_m);
        ates[v.group].push_back(ate.rmse_m);
        csv << v.group << "," << v.name << "," << ate.rmse_m << "," << ate.max_m << "," << r.ms_per_scan() << "\n";
        md << "| " << v.group << " | " << v.name << " | " << Fixed(ate.rmse_m, 3) << " | " << Fixed(ate.max_m, 3)
           << " |\n";
        std::cerr << "eval-slam: sweep " << v.name << ": ATE " << Fixed(ate.rmse_m, 4) << " m\n";
      }
      md << "\n| runs | count | min [m] | median [m] | max [m] |\n|---|---|---|---|---|\n";
      for (const std::string group : {"all", "neighbour", "perturbation"}) {
        std::vector<double> sorted = ates[group];
        if (sorted.empty()) continue;
        std::sort(sorted.begin(), sorted.end());
        const double median = sorted[sorted.size() / 2];
        md << "| " << group << " | " << sorted.size() << " | " << Fixed(sorted.front(), 3) << " | " << Fixed(median, 3)
           << " | " << Fixed(sorted.back(), 3) << " |\n";
        std::cerr << "eval-slam: sweep, " << group << " (" << sorted.size() << " runs): ATE min "
                  << Fixed(sorted.front(), 4) << " m, median " << Fixed(median, 4) << " m, max "
                  << Fixed(sorted.back(), 4) << " m\n";
        const std::string k = group == "all" ? "sweep" : "sweep_" + group;
        json[k + "_runs"] = sorted.size();
        json[k + "_ate_rmse_min_m"] = R4(sorted.front());
        json[k + "_ate_rmse_median_m"] = R4(median);
        json[k + "_ate_rmse_max_m"] = R4(sorted.back());
      }
      std::ofstream(out / "sweep.md") << md.str();
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
  results::WriteJsonFile((out / "summary.json").string(), json);
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
  {
    // What the laser slam did at each scan.
    std::ofstream csv(out / "scans.csv");
    csv << "scan,utime,points,matches,fit,searches,recoveries,stale_odometry,widened,measured,"
           "predicted_x_m,predicted_y_m,predicted_theta_rad,predicted_sigma_xy_m,predicted_sigma_theta_deg,"
           "measured_x_m,measured_y_m,measured_theta_rad,measured_sigma_x_m,measured_sigma_y_m,"
           "measured_sigma_theta_deg,x_m,y_m,theta_rad,start_x_m,start_y_m,start_theta_rad,outcome,prediction,"
           "predictions,mahalanobis2,ambiguity,kernel,coasting,wall_measured,wall_gated,wall_offset_deg,wall_contrast,"
           "odometry_drift_deg_per_m,odometry_turn_scale,odometry_distance_scale,motion_noise_scale\n"
        << std::setprecision(9);
    for (size_t i = 0; i < run.updates.size(); ++i) {
      const nav::LaserSlamUpdate& u = run.updates[i];
      const nav::Pose2& s = run.slam[i];
      const double deg = 180 / 3.14159265358979323846;
      csv << i << "," << run.utime[i] << "," << u.points << "," << u.matches << "," << u.fit << "," << u.searches << ","
          << u.recoveries << "," << u.stale_odometry << "," << u.widened << "," << u.measured << "," << u.predicted.x_m
          << "," << u.predicted.y_m << "," << u.predicted.theta_rad << ","
          << std::sqrt(std::max(u.predicted_covariance(0, 0), u.predicted_covariance(1, 1))) << ","
          << std::sqrt(u.predicted_covariance(2, 2)) * deg << "," << u.measurement.x_m << "," << u.measurement.y_m
          << "," << u.measurement.theta_rad << "," << std::sqrt(u.measurement_covariance(0, 0)) << ","
          << std::sqrt(u.measurement_covariance(1, 1)) << "," << std::sqrt(u.measurement_covariance(2, 2)) * deg << ","
          << s.x_m << "," << s.y_m << "," << s.theta_rad << "," << u.start.x_m << "," << u.start.y_m << ","
          << u.start.theta_rad << "," << nav::MatchOutcomeName(u.outcome) << ","
          << nav::PredictionSourceName(u.prediction) << "," << u.predictions << "," << u.mahalanobis2 << ","
          << u.ambiguity << "," << u.kernel << "," << u.coasting << "," << u.wall_measured << "," << u.wall_gated << ","
          << u.wall_offset_rad * deg << "," << u.wall_contrast << "," << u.odometry_drift_rad_per_m * deg << ","
          << u.odometry_turn_scale << "," << u.odometry_distance_scale << "," << u.motion_noise_scale << "\n";
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

}  // namespace snapnav::eval
