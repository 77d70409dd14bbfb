// bench-slam: our laser SLAM against MRPT's icp-slam, measured in one run on MRPT's Malaga loop
// (Debian's mrpt-common): the rawlog is imported as log-import does into an LCM log, our
// LaserSlam (the [laser_slam] options of --config, default the shipped config/laser_slam.ini)
// runs over it --runs times (median ms per scan, as eval-slam times it: LaserSlam::Update),
// icp-slam runs --icp-runs times on the same rawlog (median of its own per-scan timing,
// eval/icp_slam.hpp), and the trajectories are compared (RMS difference of the positions at the
// same scans after SE(2) alignment). Then scans per second on 681-beam scans (the simulated
// Hokuyo URG-04LX of config/sim.ini driving a scene's route). Goals (issue): icp-slam/ours time
// ratio >= 2, RMS difference <= 0.05 m, >= 500 scans/s at 681 beams on one core (the snapnav
// script pins it with taskset -c 0). Writes bench.json and bench.md into --out.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <vector>

#include "icp_slam.hpp"
#include "importers.hpp"
#include "report_text.hpp"
#include "slam_config.hpp"
#include "slam_log.hpp"
#include "slam_plot.hpp"
#include "slam_sim.hpp"
#include "stats.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/laser_slam.hpp"
#include "snapnav/plot/plot.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using eval::Fixed;
using eval::JsonString;
using eval::Median;

constexpr double kGoalTimeRatio = 2.0;        // icp-slam ms/scan over ours, at least
constexpr double kGoalRmsDifferenceM = 0.05;  // ours against icp-slam, at most
constexpr double kGoalScansPerSecond = 500;   // 681-beam scans, one core, at least


// "min-max" of run times.
std::string Spread(const std::vector<double>& v) {
  if (v.empty()) return "-";
  return Fixed(*std::min_element(v.begin(), v.end()), 3) + "-" + Fixed(*std::max_element(v.begin(), v.end()), 3);
}

// Median ms per scan of `runs` runs of our SLAM over `log`; the last run in *last.
double OurMsPerScan(const eval::SlamLog& log, const nav::LaserSlamOptions& options, int runs, const std::string& what,
                    eval::SlamRun* last) {
  std::vector<double> ms;
  for (int r = 0; r < runs; ++r) {
    *last = eval::RunSlam(log, options);
    ms.push_back(last->ms_per_scan());
    std::cerr << "bench-slam: " << what << " run " << r + 1 << "/" << runs << ": " << Fixed(ms.back(), 3)
              << " ms/scan\n";
  }
  return Median(ms);
}

int Main(int argc, char** argv) {
  std::string rawlog = eval::kMalagaLoopRawlog, out_dir, sim_config_path = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string sim_scene = "corridor";
  int runs = 7, icp_runs = 5;
  double sim_duration_s = 60;
  eval::IcpSlamOptions icp_options;
  icp_options.progress = false;
  glue::Flags flags("bench-slam",
                    "Our laser SLAM against MRPT's icp-slam on one rawlog (default: MRPT's Malaga loop): imports it\n"
                    "into an LCM log, runs our SLAM --runs times and icp-slam --icp-runs times, and prints the\n"
                    "median ms per scan of each, their ratio (goal >= 2), the RMS difference of the trajectories\n"
                    "(goal <= 0.05 m), and our scans per second on 681-beam simulated scans (goal >= 500). Run it\n"
                    "on one core (./snapnav bench slam uses taskset -c 0). Writes bench.json and bench.md to --out.");
  flags.AddString("rawlog", &rawlog, "MRPT rawlog with laser scans and odometry");
  flags.AddInt("runs", &runs, "runs of our laser SLAM per figure");
  flags.AddInt("icp-runs", &icp_runs, "runs of icp-slam");
  bool no_dense = false;
  flags.AddBool("no-dense-icp-slam", &no_dense,
                "skip the extra icp-slam run with a denser map (keyframes every 0.2 m / 5 deg, every scan point)");
  flags.AddString("icp-slam-config", &icp_options.base_config, "icp-slam ini file the config is generated from");
  flags.AddString("icp-slam-bin", &icp_options.icp_slam, "the icp-slam program (name on PATH or path)");
  flags.AddString("sim-config", &sim_config_path, "simulator config of the 681-beam scans (laser, robot)");
  flags.AddString("sim-scene", &sim_scene, "scene the simulated robot drives (its route)");
  flags.AddDouble("sim-duration-s", &sim_duration_s, "simulated seconds (10 scans/s)");
  flags.AddString("out", &out_dir, "folder for bench.json, bench.md and the work files (default: a temporary folder)");
  eval::LaserSlamConfigChoice config;
  flags.AddString("config", &config.path, "laser-slam config whose [laser_slam] options our laser SLAM runs");
  std::vector<std::string> sets;
  flags.AddStringList("set", &sets, "override of one [laser_slam] key of --config, KEY=VALUE (repeatable)");
  if (!flags.Parse(argc, argv)) return 0;
  config.overrides = sets;
  const nav::LaserSlamOptions slam_options = eval::LoadLaserSlamOptions(config);
  std::cerr << "bench-slam: laser slam options of " << config.path;
  for (const std::string& o : config.overrides) std::cerr << ", " << o;
  std::cerr << ":\n";
  eval::PrintLaserSlamOptions(std::cerr, slam_options);
  if (runs < 1 || icp_runs < 1) throw glue::FlagError("--runs and --icp-runs must be >= 1");
  if (!(sim_duration_s > 0)) throw glue::FlagError("--sim-duration-s must be positive");
  if (!fs::is_regular_file(rawlog)) {
    throw glue::FlagError("rawlog " + rawlog + ": no such file" +
                          (rawlog == eval::kMalagaLoopRawlog ? " (install Debian's mrpt-common)" : ""));
  }
  bool temporary = false;
  if (out_dir.empty()) {
    std::string pattern = (fs::temp_directory_path() / "bench-slam-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a temporary folder in /tmp");
    out_dir = pattern;
    temporary = true;
  }
  const fs::path out(out_dir);
  fs::create_directories(out / "work");

  // 1. The rawlog as an LCM log, as log-import writes it.
  const std::string log_path = (out / "work" / "rawlog.lcmlog").string();
  std::cerr << "bench-slam: importing " << rawlog << " -> " << log_path << "\n";
  {
    importers::LcmLogSink sink(log_path);
    const importers::ImportReport report = importers::ImportRawlog(rawlog, sink, importers::RawlogOptions{});
    sink.Close();
    if (!report.ok()) {
      std::ostringstream s;
      importers::PrintSummary(report, s);
      throw std::runtime_error("importing " + rawlog + " failed:\n" + s.str());
    }
  }
  const eval::SlamLog log = eval::LoadSlamLog(log_path, false);
  std::cerr << "bench-slam: " << log.scans << " scans of " << log.beams << " beams, " << log.odometry << " odometry\n";

  // 2. Ours and icp-slam on the same scans, runs interleaved so that load from elsewhere on the
  // machine falls on both alike.
  eval::SlamRun run;
  std::vector<double> ours_runs, icp_ms, icp_wall_ms;
  eval::IcpSlamRun icp;
  for (int r = 0; r < std::max(runs, icp_runs); ++r) {
    if (r < runs) {
      run = eval::RunSlam(log, slam_options);
      ours_runs.push_back(run.ms_per_scan());
      std::cerr << "bench-slam: laser slam run " << r + 1 << "/" << runs << ": " << Fixed(ours_runs.back(), 3)
                << " ms/scan\n";
    }
    if (r < icp_runs) {
      icp = eval::RunIcpSlam(rawlog, (out / "work" / "icp-slam").string(), icp_options);
      icp_ms.push_back(icp.ms_per_scan());
      icp_wall_ms.push_back(icp.wall_ms_per_scan());
      std::cerr << "bench-slam: icp-slam run " << r + 1 << "/" << icp_runs << ": " << Fixed(icp_ms.back(), 3)
                << " ms/scan (wall " << Fixed(icp_wall_ms.back(), 3) << ")\n";
    }
  }
  const double ours_ms = Median(ours_runs);
  const double theirs_ms = Median(icp_ms), theirs_wall_ms = Median(icp_wall_ms);
  const eval::IcpSlamComparison cmp = eval::CompareWithIcpSlam(run.utime, run.slam, icp.poses);
  const double ratio = theirs_ms / std::max(ours_ms, 1e-9);
  // Which map is consistent where the two differ: scans against the scans seen on a revisit.
  std::vector<std::optional<nav::Pose2>> ours_at_scans(run.slam.begin(), run.slam.end());
  const eval::MapConsistency ours_consistency = eval::ComputeMapConsistency(log, ours_at_scans);
  const eval::MapConsistency icp_consistency = eval::ComputeMapConsistency(log, cmp.icp_at_scans);
  {
    // Both trajectories over each one's map (every scan placed at that trajectory's poses, one
    // point per 5 cm cell): where they differ, the crisper map is the right one.
    const nav::Pose2 to_slam = cmp.slam_to_icp.Inverse();
    std::vector<nav::Pose2> icp_track;
    std::vector<std::optional<nav::Pose2>> icp_in_our_frame;
    for (const auto& p : cmp.icp_at_scans) {
      icp_in_our_frame.push_back(p ? std::optional<nav::Pose2>(to_slam.Compose(*p)) : std::nullopt);
      if (p) icp_track.push_back(*icp_in_our_frame.back());
    }
    const auto scans_map = [&](const std::vector<std::optional<nav::Pose2>>& poses) {
      nav::PointGridMap grid(0.05, 0.25);
      size_t k = 0;
      for (const eval::SlamStep& step : log.steps) {
        if (!step.is_scan) continue;
        if (k < poses.size() && poses[k]) {
          for (const Eigen::Vector2d& q : step.points) grid.Add(poses[k]->Transform(q));
        }
        ++k;
      }
      return grid.points();
    };
    const std::vector<std::vector<nav::Pose2>> tracks = {run.slam, icp_track};
    const std::vector<std::string> names = {"laser slam (ours)", "icp-slam (MRPT)"};
    plot::SavePng(eval::DrawRun(tracks, names, scans_map(ours_at_scans),
                                "scans at our poses; consistency " + Fixed(ours_consistency.median_m, 4) + " m"),
                  (out / "map_ours.png").string());
    plot::SavePng(eval::DrawRun(tracks, names, scans_map(icp_in_our_frame),
                                "scans at icp-slam's poses; consistency " + Fixed(icp_consistency.median_m, 4) + " m"),
                  (out / "map_icp_slam.png").string());
  }
  {
    std::ofstream csv(out / "trajectories.csv");
    csv << "utime,slam_x_m,slam_y_m,slam_theta_rad,icp_x_m,icp_y_m,icp_theta_rad,difference_m,"
           "slam_consistency_m,icp_consistency_m\n"
        << std::setprecision(9);
    const nav::Pose2 to_slam = cmp.slam_to_icp.Inverse();
    for (size_t i = 0; i < run.slam.size(); ++i) {
      const nav::Pose2& s = run.slam[i];
      csv << run.utime[i] << "," << s.x_m << "," << s.y_m << "," << s.theta_rad;
      if (cmp.icp_at_scans[i]) {
        const nav::Pose2 p = to_slam.Compose(*cmp.icp_at_scans[i]);  // icp-slam's pose in our frame
        csv << "," << p.x_m << "," << p.y_m << "," << p.theta_rad << "," << std::hypot(p.x_m - s.x_m, p.y_m - s.y_m);
      } else {
        csv << ",,,,";
      }
      csv << "," << ours_consistency.per_scan_m[i] << "," << icp_consistency.per_scan_m[i] << "\n";
    }
  }

  // 2b. Evidence of which trajectory is right where they differ: icp-slam once more with a denser
  // map (a keyframe wherever it matches, every point; icp-slam's classic config inserts a scan only
  // every 1.2 m or 45 deg and matches every 5th point). If it moves towards ours and its map gets
  // more consistent, the difference was icp-slam's.
  std::optional<eval::IcpSlamRun> dense;
  std::optional<eval::IcpSlamComparison> dense_cmp;
  std::optional<eval::MapConsistency> dense_consistency;
  if (!no_dense) {
    std::ifstream base_in(icp_options.base_config);
    if (!base_in) throw std::runtime_error("cannot read icp-slam config " + icp_options.base_config);
    std::stringstream text;
    text << base_in.rdbuf();
    std::ostringstream dense_ini;
    std::string line;
    while (std::getline(text, line)) {
      const auto starts = [&](const char* key) { return line.rfind(key, 0) == 0; };
      if (starts("insertionLinDistance")) line = "insertionLinDistance = 0.2  // bench-slam: dense (was: " + line + ")";
      else if (starts("insertionAngDistance")) line = "insertionAngDistance = 5  // bench-slam: dense (was: " + line + ")";
      else if (starts("corresponding_points_decimation"))
        line = "corresponding_points_decimation = 1  // bench-slam: dense (was: " + line + ")";
      dense_ini << line << "\n";
    }
    const std::string dense_base = (out / "work" / "icp-slam-dense-base.ini").string();
    std::ofstream(dense_base) << dense_ini.str();
    eval::IcpSlamOptions dense_options = icp_options;
    dense_options.base_config = dense_base;
    dense = eval::RunIcpSlam(rawlog, (out / "work" / "icp-slam-dense").string(), dense_options);
    dense_cmp = eval::CompareWithIcpSlam(run.utime, run.slam, dense->poses);
    dense_consistency = eval::ComputeMapConsistency(log, dense_cmp->icp_at_scans);
    std::cerr << "bench-slam: icp-slam with a dense map: " << Fixed(dense->ms_per_scan(), 3) << " ms/scan\n";
  }

  // 3. 681-beam scans per second.
  const auto sim_config = processes::SimConfig::FromIni(glue::IniFile::Load(sim_config_path), "");
  eval::SimSlamOptions sim_options = eval::SimSlamOptions::FromSimConfig(sim_config);
  sim_options.scene = sim_scene;
  sim_options.laps = 0;
  sim_options.duration_s = sim_duration_s;
  sim_options.Validate();
  std::cerr << "bench-slam: simulating " << sim_duration_s << " s in '" << sim_scene << "' (" << sim_options.laser.beams
            << "-beam laser of " << sim_config_path << ")\n";
  const eval::SimulatedSlamLog sim = eval::SimulateSlamLog(sim_options);
  eval::SlamRun sim_run;
  const double sim_ms =
      OurMsPerScan(sim.log, slam_options, runs, std::to_string(sim.log.beams) + "-beam scans", &sim_run);
  const double sim_scans_per_s = 1000.0 / std::max(sim_ms, 1e-9);

  const bool ratio_met = ratio >= kGoalTimeRatio;
  const bool rms_met = cmp.difference.rmse_m <= kGoalRmsDifferenceM;
  const bool rate_met = sim.log.beams == 681 && sim_scans_per_s >= kGoalScansPerSecond;
  auto mark = [](bool met) { return met ? "met" : "MISSED"; };
  std::ostringstream report;
  report << "bench-slam: " << fs::path(rawlog).filename().string() << ", " << log.scans << " scans of " << log.beams
         << " beams; ours: median of " << runs << " runs, icp-slam: median of " << icp_runs << " runs\n"
         << "  laser slam (ours)     " << Fixed(ours_ms, 3) << " ms/scan  (" << Fixed(1000 / std::max(ours_ms, 1e-9), 0)
         << " scans/s; runs " << Spread(ours_runs) << ")\n"
         << "  icp-slam (MRPT)       " << Fixed(theirs_ms, 3) << " ms/scan  (its own timing of its SLAM steps; runs "
         << Spread(icp_ms) << "; whole process " << Fixed(theirs_wall_ms, 3) << " ms/scan)\n"
         << "  ratio icp-slam/ours   " << Fixed(ratio, 2) << "x           goal >= " << Fixed(kGoalTimeRatio, 0) << ": "
         << mark(ratio_met) << "\n"
         << "  trajectory difference " << Fixed(cmp.difference.rmse_m, 3) << " m RMS (max "
         << Fixed(cmp.difference.max_m, 3) << " m) over " << cmp.paired
         << " scans, after SE(2) alignment; goal <= " << Fixed(kGoalRmsDifferenceM, 2) << " m: " << mark(rms_met)
         << "\n"
         << "  map consistency       ours " << Fixed(ours_consistency.median_m, 4) << " m, icp-slam "
         << Fixed(icp_consistency.median_m, 4) << " m (median distance of a scan's points to the scans seen on a "
         << "revisit, over " << ours_consistency.scans << " / " << icp_consistency.scans << " scans)\n"
         << (dense ? "  icp-slam, dense map   " + Fixed(dense_cmp->difference.rmse_m, 3) + " m RMS from ours (max " +
                         Fixed(dense_cmp->difference.max_m, 3) + " m), map consistency " +
                         Fixed(dense_consistency->median_m, 4) + " m, " + Fixed(dense->ms_per_scan(), 3) +
                         " ms/scan (keyframes every 0.2 m / 5 deg, every point: evidence, not the timed baseline)\n"
                   : std::string())
         << "  " << sim.log.beams << "-beam scans       " << Fixed(sim_ms, 3)
         << " ms/scan = " << Fixed(sim_scans_per_s, 0) << " scans/s (" << sim.log.scans << " simulated scans in '"
         << sim.scene_name << "', median of " << runs << " runs); goal >= " << Fixed(kGoalScansPerSecond, 0) << ": "
         << mark(rate_met) << "\n";
  std::cout << report.str() << std::flush;

  std::ofstream json(out / "bench.json");
  std::string overrides;
  for (const std::string& o : config.overrides) overrides += (overrides.empty() ? "" : "; ") + o;
  json << std::fixed << std::setprecision(4) << "{\n  \"rawlog\": " << JsonString(rawlog)
       << ",\n  \"laser_slam_config\": " << JsonString(config.path)
       << ",\n  \"laser_slam_overrides\": " << JsonString(overrides) << ",\n  \"scans\": " << log.scans
       << ",\n  \"beams\": " << log.beams << ",\n  \"runs\": " << runs << ",\n  \"icp_runs\": " << icp_runs
       << ",\n  \"laser_slam_ms_per_scan\": " << ours_ms
       << ",\n  \"laser_slam_scans_per_s\": " << 1000 / std::max(ours_ms, 1e-9)
       << ",\n  \"icp_slam_ms_per_scan\": " << theirs_ms << ",\n  \"icp_slam_wall_ms_per_scan\": " << theirs_wall_ms
       << ",\n  \"icp_slam_config\": " << JsonString(icp.config) << ",\n  \"icp_slam_scans\": " << icp.poses.size()
       << ",\n  \"icp_slam_scans_paired\": " << cmp.paired << ",\n  \"icp_slam_over_laser_slam_time_ratio\": " << ratio
       << ",\n  \"laser_slam_vs_icp_slam_rms_m\": " << cmp.difference.rmse_m
       << ",\n  \"laser_slam_vs_icp_slam_max_m\": " << cmp.difference.max_m
       << ",\n  \"laser_slam_map_consistency_m\": " << ours_consistency.median_m
       << ",\n  \"icp_slam_map_consistency_m\": " << icp_consistency.median_m
       << ",\n  \"icp_slam_dense_vs_laser_slam_rms_m\": " << (dense ? dense_cmp->difference.rmse_m : -1)
       << ",\n  \"icp_slam_dense_map_consistency_m\": " << (dense ? dense_consistency->median_m : -1)
       << ",\n  \"icp_slam_dense_ms_per_scan\": " << (dense ? dense->ms_per_scan() : -1)
       << ",\n  \"laser_slam_ms_per_scan_runs\": [" << eval::JsonNumbers(ours_runs) << "]"
       << ",\n  \"icp_slam_ms_per_scan_runs\": [" << eval::JsonNumbers(icp_ms) << "]"
       << ",\n  \"sim_scene\": " << JsonString(sim.scene_name) << ",\n  \"sim_beams\": " << sim.log.beams
       << ",\n  \"sim_scans\": " << sim.log.scans << ",\n  \"sim_laser_slam_ms_per_scan\": " << sim_ms
       << ",\n  \"sim_laser_slam_scans_per_s\": " << sim_scans_per_s
       << ",\n  \"goal_time_ratio_met\": " << (ratio_met ? "true" : "false")
       << ",\n  \"goal_rms_difference_met\": " << (rms_met ? "true" : "false")
       << ",\n  \"goal_scans_per_s_met\": " << (rate_met ? "true" : "false") << "\n}\n";
  json.close();
  std::ofstream md(out / "bench.md");
  md << "# bench-slam\n\n```\n"
     << report.str() << "```\n\n"
     << "| | laser slam (ours) | icp-slam (MRPT) | goal |\n|---|---|---|---|\n"
     << "| ms/scan, " << log.beams << " beams | " << Fixed(ours_ms, 3) << " | " << Fixed(theirs_ms, 3) << " (wall "
     << Fixed(theirs_wall_ms, 3) << ") | ratio " << Fixed(ratio, 2) << " >= 2 |\n"
     << "| RMS difference | " << Fixed(cmp.difference.rmse_m, 3) << " m | | <= 0.05 m |\n"
     << "| scans/s, " << sim.log.beams << " beams | " << Fixed(sim_scans_per_s, 0) << " | | >= 500 |\n"
     << "| map consistency (median distance to the scans seen on a revisit) | " << Fixed(ours_consistency.median_m, 4)
     << " m | " << Fixed(icp_consistency.median_m, 4) << " m | lower is crisper |\n\n"
     << "## What each time includes\n\n"
     << "- **ours**: `LaserSlam::Update` for every scan (timed around the call in the same process, the log already "
     << "decoded in memory): scan normals, the heading search, ICP on every scan (no motion gating), the EKF update and "
     << "the map insertion with its lookup grid. Odometry prediction (`Predict`) is not timed (it is a few "
     << "multiplications). Median of " << runs << " runs, spread " << Spread(ours_runs) << " ms/scan.\n"
     << "- **icp-slam**: the sum of its own `log_times.txt` (CMetricMapBuilderICP's processing of each rawlog entry, "
     << "odometry-only entries included) over the scans, i.e. without process start, reading the rawlog or writing "
     << "files. It runs ICP only after 0.2 m or 5 deg of motion, on every 5th scan point, and inserts a scan into "
     << "its map every 1.2 m or 45 deg (the classic config). Median of " << icp_runs << " runs, spread "
     << Spread(icp_ms) << " ms/scan; the whole process takes " << Fixed(theirs_wall_ms, 3) << " ms/scan.\n"
     << "- Both run on one core (`taskset -c 0`), interleaved run by run, so load from elsewhere falls on both.\n\n"
     << "## Where the trajectories differ\n\n"
     << "`map_ours.png` and `map_icp_slam.png` draw both trajectories over the scans placed at our poses and at "
     << "icp-slam's (doubled walls show where a trajectory is off); `trajectories.csv` has both trajectories "
     << "(icp-slam's in our frame), their distance per scan and each map's consistency per scan. Map consistency: each scan placed at the trajectory's pose, each point paired with the "
     << "nearest point (within 0.5 m) of scans at least 30 scans away; the median pair distance per scan, then the "
     << "median over scans. Ours " << Fixed(ours_consistency.median_m, 4) << " m, icp-slam "
     << Fixed(icp_consistency.median_m, 4) << " m.\n";
  if (dense) {
    md << "\nicp-slam with a denser map (keyframes every 0.2 m / 5 deg, every scan point; generated from the same "
       << "config, `work/icp-slam-dense-base.ini`): " << Fixed(dense_cmp->difference.rmse_m, 3) << " m RMS from ours "
       << "(classic config: " << Fixed(cmp.difference.rmse_m, 3) << " m), map consistency "
       << Fixed(dense_consistency->median_m, 4) << " m, " << Fixed(dense->ms_per_scan(), 3)
       << " ms/scan. Made more accurate, icp-slam moves towards our trajectory.\n";
  }
  md << "\nicp-slam config: `" << icp.config << "`.\n";
  md.close();
  if (temporary) {
    std::cerr << "bench-slam: (no --out) removing " << out_dir << "\n";
    fs::remove_all(out);
  } else {
    std::cerr << "bench-slam: wrote " << (out / "bench.json").string() << " and bench.md\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
