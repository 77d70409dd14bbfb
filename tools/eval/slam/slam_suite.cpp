#include "slam_suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "importers.hpp"
#include "program.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "slam_config.hpp"
#include "slam_plot.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// `path` relative to `base` unless absolute.
std::string Resolve(const fs::path& base, const std::string& path) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  return (base / path).lexically_normal().string();
}

}  // namespace

AteFigure MeasureAte(const std::vector<nav::Pose2>& estimate, const SlamRun& run, const Reference& reference) {
  AteFigure f;
  const auto pairs = PairWithReference(estimate, run, reference);
  f.pairs = static_cast<int>(pairs.size());
  if (pairs.size() < 2) return f;
  const nav::AteResult ate = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
  f.measured = true;
  f.rmse_m = ate.rmse_m;
  f.max_m = ate.max_m;
  return f;
}

RpeFigure MeasureRpe(const std::vector<nav::Pose2>& estimate, const SlamRun& run, const Reference& reference) {
  RpeFigure f;
  const auto pairs = PairWithReference(estimate, run, reference);
  if (pairs.size() < 2) return f;
  const nav::RpeResult one = nav::ComputeRpe(pairs, 1.0);
  const nav::RpeResult ten = nav::ComputeRpe(pairs, 10.0);
  if (one.segments == 0) return f;
  f.measured = true;
  f.translation_1m_m = one.translation_rmse_m;
  f.rotation_1m_deg = one.rotation_rmse_deg;
  f.translation_10m_m = ten.translation_rmse_m;
  f.rotation_10m_deg = ten.rotation_rmse_deg;
  f.segments_10m = ten.segments;
  return f;
}

OutcomeCounts CountOutcomes(const SlamRun& run) {
  OutcomeCounts c;
  for (const nav::LaserSlamUpdate& u : run.updates) {
    c.accepted += u.outcome == nav::MatchOutcome::kAccepted;
    c.gated += u.outcome == nav::MatchOutcome::kGated;
    c.ambiguous += u.outcome == nav::MatchOutcome::kAmbiguous;
    c.no_match += u.outcome == nav::MatchOutcome::kNoMatch;
    c.stale_predictions += u.prediction == nav::PredictionSource::kStale;
    c.catch_up_predictions += u.prediction == nav::PredictionSource::kCatchUp;
    c.widened += u.widened;
  }
  return c;
}

Suite LoadSuite(const std::string& path) {
  const glue::IniFile ini = glue::IniFile::Load(path);
  const fs::path dir = fs::absolute(path).parent_path();
  Suite suite;
  suite.path = path;
  const fs::path data = Resolve(dir, ini.GetString("suite", "data"));
  suite.raw_like_tool = Resolve(dir, ini.GetString("suite", "raw_like_tool"));
  suite.laser_slam_config = Resolve(dir, ini.GetString("suite", "laser_slam_config"));
  suite.icp_slam = ini.GetBool("suite", "icp_slam");
  if (ini.Has("suite", "graph")) suite.graph = ini.GetBool("suite", "graph");
  for (const std::string& name : ini.SectionsInFileOrder()) {
    if (name == "suite") continue;
    SuiteEntry e;
    e.name = name;
    e.kind = ini.GetString(name, "kind");
    if (e.kind != "carmen" && e.kind != "carmen_corrected" && e.kind != "rawlog") {
      throw glue::ConfigError(path + ":" + std::to_string(ini.KeyLine(name, "kind")) + ": [" + name + "] kind = " +
                              e.kind + ": expected carmen, carmen_corrected or rawlog");
    }
    e.log = Resolve(data, ini.GetString(name, "log"));
    const std::string reference = ini.GetString(name, "reference");
    if (reference == "corrected") {
      if (e.kind != "carmen_corrected") {
        throw glue::ConfigError(path + ":" + std::to_string(ini.KeyLine(name, "reference")) + ": [" + name +
                                "] reference = corrected needs kind = carmen_corrected");
      }
      e.reference = e.log;
    } else if (reference == "icp-slam") {
      if (!suite.icp_slam) {
        throw glue::ConfigError(path + ":" + std::to_string(ini.KeyLine(name, "reference")) + ": [" + name +
                                "] reference = icp-slam needs [suite] icp_slam = true");
      }
      e.reference = "icp-slam";
    } else {
      e.reference = Resolve(data, reference);
    }
    if (e.kind == "carmen_corrected") {
      e.noise = ini.GetDouble(name, "noise");
      e.noise_seed = ini.GetInt(name, "seed");
      e.every = ini.GetInt(name, "every");
      if (!(e.noise >= 0) || e.every < 1) {
        throw glue::ConfigError(path + ":" + std::to_string(ini.SectionLine(name)) + ": [" + name +
                                "] noise must be >= 0 and every >= 1");
      }
    }
    if (ini.Has(name, "laser_max_range_m")) {
      e.laser_max_range_m = ini.GetDouble(name, "laser_max_range_m");
      const std::string where = path + ":" + std::to_string(ini.KeyLine(name, "laser_max_range_m")) + ": [" + name + "] ";
      if (e.kind == "rawlog") throw glue::ConfigError(where + "laser_max_range_m applies to CARMEN logs only");
      if (!(e.laser_max_range_m > 0)) throw glue::ConfigError(where + "laser_max_range_m must be > 0 [m]");
      if (e.reference == "icp-slam") throw glue::ConfigError(where + "laser_max_range_m cannot have icp-slam as reference");
    }
    e.goal_ate_m = ini.GetDouble(name, "goal_ate_m");
    e.no_worse_than_dead_reckoning = ini.GetBool(name, "no_worse_than_dead_reckoning");
    if (ini.Has(name, "graph_goal_ate_m")) e.graph_goal_ate_m = ini.GetDouble(name, "graph_goal_ate_m");
    suite.entries.push_back(e);
  }
  ini.CheckAllUsed();
  if (suite.entries.empty()) throw glue::ConfigError(path + ": no runs (a section per run besides [suite])");
  return suite;
}

namespace {

// The missing input of an entry, if any ("" when everything is there).
std::string MissingInput(const Suite& suite, const SuiteEntry& e) {
  if (!fs::is_regular_file(e.log)) return e.log;
  if (e.reference != "icp-slam" && !fs::is_regular_file(e.reference)) return e.reference;
  if (e.kind == "carmen_corrected" && !fs::is_regular_file(suite.raw_like_tool)) return suite.raw_like_tool;
  return "";
}

// The map consistency of `estimate` (one pose per scan of `run`; null: the reference's own poses)
// over the scans `reference` has.
std::optional<double> ConsistencyOver(const SlamLog& log, const SlamRun& run, const std::vector<nav::Pose2>* estimate,
                                      const Reference& reference) {
  std::vector<std::optional<nav::Pose2>> poses(run.utime.size());
  for (size_t i = 0; i < run.utime.size() && (!estimate || i < estimate->size()); ++i) {
    if (const auto truth = reference.Find(run.ranges_key[i], run.utime[i])) poses[i] = estimate ? (*estimate)[i] : *truth;
  }
  const MapConsistency c = ComputeMapConsistency(log, poses);
  if (c.scans == 0) return std::nullopt;
  return c.median_m;
}

SuiteResult RunEntry(const Suite& suite, const SuiteEntry& e, const nav::LaserSlamOptions& options,
                     const SlamBackendChoice& backend, const fs::path& dir, const SuiteOptions& so) {
  SuiteResult r;
  r.entry = e;
  fs::create_directories(dir);
  // The log the SLAM reads, and what icp-slam reads.
  std::string input = e.log;
  if (e.kind == "carmen_corrected") {
    input = (dir / "raw.clf").string();
    const std::vector<std::string> argv = {FindProgram("python3", "python3"), suite.raw_like_tool, e.log, input,
                                           "--noise", Fixed(e.noise, 3), "--seed", std::to_string(e.noise_seed),
                                           "--every", std::to_string(e.every)};
    const std::string log = (dir / "raw_like.log").string();
    CheckExit(RunProgram(argv, log, 300), argv, log);
  }
  const std::string lcm_log = (dir / "log.lcmlog").string();
  {
    importers::LcmLogSink sink(lcm_log);
    importers::ImportReport report;
    if (e.kind == "rawlog") {
      report = importers::ImportRawlog(input, sink, importers::RawlogOptions{});
    } else {
      importers::CarmenOptions carmen;
      if (e.laser_max_range_m > 0) carmen.flaser_max_range_m = e.laser_max_range_m;
      report = importers::ImportCarmenFile(input, sink, carmen);
    }
    sink.Close();
    if (!report.errors.empty()) throw std::runtime_error(input + ": " + report.errors.front());
  }
  const SlamLog log = LoadSlamLog(lcm_log, false);
  r.scans = log.scans;
  const SlamRun ekf_run = RunSlam(log, options);
  const SlamRun thesis = RunSlam(log, nav::ThesisLaserSlamOptions(options));
  std::optional<GraphSlamRun> graph_run;
  if (suite.graph || backend.graph) graph_run = RunGraphSlam(log, options, backend.options);
  // The configured back end is "laser SLAM" in the table and its goals.
  const SlamRun& run = backend.graph ? graph_run->run : ekf_run;
  r.backend = backend.graph ? "graph" : "ekf";
  r.slam_ms_per_scan = run.ms_per_scan();
  r.ekf_ms_per_scan = ekf_run.ms_per_scan();
  r.thesis_ms_per_scan = thesis.ms_per_scan();
  r.outcomes = CountOutcomes(run);
  std::optional<IcpSlamRun> icp;
  std::optional<IcpSlamComparison> cmp;
  if ((suite.icp_slam && e.laser_max_range_m == 0) || e.reference == "icp-slam") {  // icp-slam as the reference runs it whatever icp_slam says
    IcpSlamOptions icp_options = so.icp;
    icp_options.progress = false;
    icp = RunIcpSlam(input, (dir / "icp-slam").string(), icp_options);
    cmp = CompareWithIcpSlam(run.utime, run.slam, icp->poses);
    r.icp_slam_ms_per_scan = icp->ms_per_scan();
    r.icp_slam_ran = true;
  }
  Reference reference;
  if (e.reference == "icp-slam") {
    reference.path = "icp-slam";
    reference.by_time = icp->poses;
  } else {
    reference = LoadReference(e.reference, &log);
  }
  r.slam = MeasureAte(run.slam, run, reference);
  r.thesis = MeasureAte(thesis.slam, thesis, reference);
  r.dead_reckoning = MeasureAte(run.dead_reckoning, run, reference);
  r.ekf = MeasureAte(ekf_run.slam, ekf_run, reference);
  r.ekf_rpe = MeasureRpe(ekf_run.slam, ekf_run, reference);
  r.ekf_consistency_m = ConsistencyOver(log, ekf_run, &ekf_run.slam, reference);
  r.reference_consistency_m = ConsistencyOver(log, ekf_run, nullptr, reference);
  r.reference_check = CheckReference(log, reference);
  r.odometry = SlamOdometryCalibration(ekf_run);
  r.reference_odometry = ReferenceOdometryCalibration(ekf_run, reference, options);
  WriteReferenceCheckCsv((dir / "reference_suspects.csv").string(), r.reference_check);
  if (graph_run) {
    const GraphSlamRun& g = *graph_run;
    r.graph_ran = true;
    r.graph = MeasureAte(g.run.slam, g.run, reference);
    r.graph_live = MeasureAte(g.live, g.run, reference);
    r.graph_rpe = MeasureRpe(g.run.slam, g.run, reference);
    r.graph_consistency_m = ConsistencyOver(log, g.run, &g.run.slam, reference);
    r.graph_front_ms_per_scan = g.front_ms_per_scan();
    r.graph_back_ms_per_scan = g.back_ms_per_scan();
    r.graph_back_max_ms = g.back_max_ms;
    r.keyframes = g.keyframes;
    r.corrections = g.corrections;
    r.largest_correction_m = g.largest_correction_m;
    r.closures = CheckClosures(g, reference);
    WriteClosuresCsv((dir / "closures.csv").string(), g, reference);
    {
      // Every scan's poses: the reference's (where it has one), the EKF's, the graph's (optimized and live).
      std::ofstream t(dir / "trajectories.csv");
      t << "scan,utime,reference_x_m,reference_y_m,reference_theta_rad,ekf_x_m,ekf_y_m,ekf_theta_rad,graph_x_m,"
           "graph_y_m,graph_theta_rad,live_x_m,live_y_m,live_theta_rad,dead_reckoning_x_m,dead_reckoning_y_m,"
           "dead_reckoning_theta_rad\n";
      t.precision(9);
      for (size_t i = 0; i < g.run.slam.size() && i < ekf_run.slam.size(); ++i) {
        t << i + 1 << "," << g.run.utime[i] << ",";
        if (const auto ref = reference.Find(g.run.ranges_key[i], g.run.utime[i])) {
          t << ref->x_m << "," << ref->y_m << "," << ref->theta_rad << ",";
        } else {
          t << ",,,";
        }
        for (const nav::Pose2* p : {&ekf_run.slam[i], &g.run.slam[i], &g.live[i], &g.run.dead_reckoning[i]}) {
          t << p->x_m << "," << p->y_m << "," << p->theta_rad << (p == &g.run.dead_reckoning[i] ? "\n" : ",");
        }
      }
    }
    std::vector<std::string> failed;
    if (!r.graph.measured) failed.push_back("no scan paired with the reference");
    if (e.graph_goal_ate_m > 0 && r.graph.measured && r.graph.rmse_m > e.graph_goal_ate_m) {
      failed.push_back("ATE " + Fixed(r.graph.rmse_m, 3) + " > " + Fixed(e.graph_goal_ate_m, 2) + " m");
    }
    if (r.closures.wrong > 0) failed.push_back(std::to_string(r.closures.wrong) + " wrong closures");
    if (e.no_worse_than_dead_reckoning && r.graph.measured && r.dead_reckoning.measured &&
        r.graph.rmse_m > r.dead_reckoning.rmse_m) {
      failed.push_back("worse than dead reckoning");
    }
    r.graph_pass = failed.empty();
    for (const std::string& f : failed) r.graph_failed += (r.graph_failed.empty() ? "" : "; ") + f;
    // The graph's map (its optimized keyframes) with its trajectory, the EKF's and the reference.
    std::vector<std::vector<nav::Pose2>> graph_tracks = {g.run.slam, ekf_run.slam};
    std::vector<std::string> graph_names = {"graph back end", "EKF"};
    const auto graph_pairs = PairWithReference(g.run.slam, g.run, reference);
    if (graph_pairs.size() >= 2) {
      const nav::Pose2 to_graph = nav::AlignSE2(graph_pairs).Inverse();
      std::vector<nav::Pose2> ref_track;
      for (const auto& [est, truth] : graph_pairs) ref_track.push_back(to_graph.Compose(truth));
      graph_tracks.push_back(ref_track);
      graph_names.push_back(e.reference == "icp-slam" ? "reference (icp-slam)" : "reference");
    }
    const std::string graph_title = e.name + ": graph back end ATE " + Fixed(r.graph.rmse_m, 3) + " m (EKF " +
                                    Fixed(r.ekf.rmse_m, 3) + "), closures " + std::to_string(r.closures.accepted) +
                                    " accepted / " + std::to_string(r.closures.rejected) + " rejected / " +
                                    std::to_string(r.closures.wrong) + " wrong";
    plot::SavePng(DrawRun(graph_tracks, graph_names, g.run.map, graph_title), (dir / "graph_map.png").string());
    r.graph_png = e.name + "/graph_map.png";
  }
  std::vector<std::vector<nav::Pose2>> tracks = {run.slam, run.dead_reckoning};
  std::vector<std::string> names = {backend.graph ? "laser slam (graph)" : "laser slam", "dead reckoning"};
  if (cmp) {
    std::vector<nav::Pose2> icp_track;
    std::vector<nav::Pose2> icp_estimate(run.slam.size());
    std::vector<nav::Pose2> ours;
    SlamRun paired;  // the scans icp-slam has a pose for
    for (size_t i = 0; i < run.slam.size(); ++i) {
      if (!cmp->icp_at_scans[i]) continue;
      paired.utime.push_back(run.utime[i]);
      paired.ranges_key.push_back(run.ranges_key[i]);
      icp_track.push_back(*cmp->icp_at_scans[i]);
    }
    r.icp_slam = MeasureAte(icp_track, paired, reference);
    const nav::Pose2 to_slam = cmp->slam_to_icp.Inverse();
    std::vector<nav::Pose2> drawn;
    for (const nav::Pose2& p : icp_track) drawn.push_back(to_slam.Compose(p));
    tracks.push_back(drawn);
    names.push_back("icp-slam (MRPT)");
  }
  // The reference, in the SLAM frame.
  const auto pairs = PairWithReference(run.slam, run, reference);
  if (pairs.size() >= 2) {
    const nav::Pose2 to_slam = nav::AlignSE2(pairs).Inverse();
    std::vector<nav::Pose2> ref_track;
    for (const auto& [est, truth] : pairs) ref_track.push_back(to_slam.Compose(truth));
    tracks.push_back(ref_track);
    names.push_back(e.reference == "icp-slam" ? "reference (icp-slam)" : "reference");
  }
  // Goals.
  std::vector<std::string> failed;
  if (!r.slam.measured) failed.push_back("no scan paired with the reference");
  if (e.goal_ate_m > 0 && r.slam.measured && r.slam.rmse_m > e.goal_ate_m) {
    failed.push_back("ATE " + Fixed(r.slam.rmse_m, 3) + " > " + Fixed(e.goal_ate_m, 2) + " m");
  }
  if (e.no_worse_than_dead_reckoning && r.slam.measured && r.dead_reckoning.measured &&
      r.slam.rmse_m > r.dead_reckoning.rmse_m) {
    failed.push_back("worse than dead reckoning");
  }
  r.pass = failed.empty();
  for (const std::string& f : failed) r.failed += (r.failed.empty() ? "" : "; ") + f;
  const std::string title = e.name + ": ATE laser slam " + Fixed(r.slam.rmse_m, 3) + " m, thesis " +
                            Fixed(r.thesis.rmse_m, 2) + ", dead reckoning " + Fixed(r.dead_reckoning.rmse_m, 2) +
                            (r.icp_slam.measured ? ", icp-slam " + Fixed(r.icp_slam.rmse_m, 2) : "");
  plot::SavePng(DrawRun(tracks, names, run.map, title), (dir / "trajectory.png").string());
  r.png = e.name + "/trajectory.png";
  return r;
}

std::string Cell(const AteFigure& f, int digits = 3) { return f.measured ? Fixed(f.rmse_m, digits) : "-"; }
std::string Cell(const std::optional<double>& v, int digits = 3) { return v ? Fixed(*v, digits) : "-"; }

}  // namespace

void WriteSuiteTable(std::ostream& out, const std::vector<SuiteResult>& results) {
  out << "| run | scans | laser SLAM ATE [m] | max [m] | thesis [m] | icp-slam [m] | dead reckoning [m] | "
         "map consistency ours / reference [m] | ms/scan (icp-slam) | accepted / gated / ambiguous / no match | goal | "
         "result |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const SuiteResult& r : results) {
    if (r.skipped) {
      out << "| " << r.entry.name << " | | | | | | | | | | | skipped: " << r.skip_reason << " |\n";
      continue;
    }
    std::string goal = r.entry.goal_ate_m > 0 ? "<= " + Fixed(r.entry.goal_ate_m, 2) : "";
    if (r.entry.no_worse_than_dead_reckoning) goal += goal.empty() ? "<= DR" : ", <= DR";
    out << "| " << r.entry.name << " | " << r.scans << " | **" << Cell(r.slam) << "** | "
        << (r.slam.measured ? Fixed(r.slam.max_m, 2) : "-") << " | " << Cell(r.thesis) << " | "
        << (r.entry.reference == "icp-slam" ? "(reference)" : Cell(r.icp_slam)) << " | " << Cell(r.dead_reckoning)
        << " | " << Cell(r.backend == "graph" ? r.graph_consistency_m : r.ekf_consistency_m) << " / "
        << Cell(r.reference_consistency_m) << " | " << Fixed(r.slam_ms_per_scan, 2) << " (" << (r.icp_slam_ran ? Fixed(r.icp_slam_ms_per_scan, 2) : "-") << ") | "
        << r.outcomes.accepted << " / " << r.outcomes.gated << " / " << r.outcomes.ambiguous << " / "
        << r.outcomes.no_match << " | " << goal << " | " << (r.pass ? "pass" : "**fail**: " + r.failed) << " |\n";
  }
}

void WriteOdometryTable(std::ostream& out, const std::vector<SuiteResult>& results) {
  out << "\n## Odometry's systematic errors\n\nAs the EKF's matches calibrate them (`odometry_calibration`: "
         "estimated on every run, applied only when set) and as the reference's motion implies them (the same "
         "estimator fed the reference instead of the matches). The raw-like logs' odometry (carmen_raw_like.py) "
         "drifts 1.5 deg/m, turns 2 % and drives 3 % too far per unit of noise.\n\n"
      << "| run | heading drift [deg/m] | turn scale [%] | distance scale [%] | stretches | reference: drift / turn / "
         "distance |\n|---|---|---|---|---|---|\n";
  for (const SuiteResult& r : results) {
    if (r.skipped || !r.odometry.measured) continue;
    const OdometryFigure& o = r.odometry;
    const OdometryFigure& f = r.reference_odometry;
    out << "| " << r.entry.name << " | " << Fixed(o.drift_deg_per_m, 2) << " | " << Fixed(100 * o.turn_scale, 1)
        << " | " << Fixed(100 * o.distance_scale, 1) << " | " << o.stretches << " | "
        << (f.measured ? Fixed(f.drift_deg_per_m, 2) + " / " + Fixed(100 * f.turn_scale, 1) + " / " +
                             Fixed(100 * f.distance_scale, 1)
                       : std::string("-"))
        << " |\n";
  }
}

void WriteGraphTable(std::ostream& out, const std::vector<SuiteResult>& results) {
  out << "| run | EKF ATE [m] | graph ATE [m] | graph live [m] | RPE 1 m EKF / graph [m] | RPE 10 m EKF / graph [m] | "
         "map consistency EKF / graph / reference [m] | closures accepted / rejected / wrong | keyframes | "
         "ms/scan front + back (max back) | graph goal | result |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  const auto rpe = [](const RpeFigure& f, bool ten) {
    if (!f.measured || (ten && f.segments_10m == 0)) return std::string("-");
    return Fixed(ten ? f.translation_10m_m : f.translation_1m_m, 3);
  };
  for (const SuiteResult& r : results) {
    if (r.skipped || !r.graph_ran) continue;
    std::string goal = r.entry.graph_goal_ate_m > 0 ? "<= " + Fixed(r.entry.graph_goal_ate_m, 2) + ", " : "";
    goal += "0 wrong";
    if (r.entry.no_worse_than_dead_reckoning) goal += ", <= DR";
    out << "| " << r.entry.name << " | " << Cell(r.ekf) << " | **" << Cell(r.graph) << "** | " << Cell(r.graph_live)
        << " | " << rpe(r.ekf_rpe, false) << " / " << rpe(r.graph_rpe, false) << " | " << rpe(r.ekf_rpe, true) << " / "
        << rpe(r.graph_rpe, true) << " | " << Cell(r.ekf_consistency_m) << " / " << Cell(r.graph_consistency_m) << " / "
        << Cell(r.reference_consistency_m) << " | " << r.closures.accepted << " / " << r.closures.rejected << " / "
        << r.closures.wrong << " | " << r.keyframes << " | " << Fixed(r.graph_front_ms_per_scan, 2) << " + "
        << Fixed(r.graph_back_ms_per_scan, 2) << " (" << Fixed(r.graph_back_max_ms, 0) << ") | " << goal << " | "
        << (r.graph_pass ? "pass" : "**fail**: " + r.graph_failed) << " |\n";
  }
}

std::vector<SuiteResult> RunSuite(const Suite& suite, const std::string& out_dir, const SuiteOptions& options) {
  LaserSlamConfigChoice choice;
  choice.path = suite.laser_slam_config;
  choice.overrides = options.overrides;
  const nav::LaserSlamOptions slam_options = LoadLaserSlamOptions(choice);
  const SlamBackendChoice backend = LoadSlamBackend(choice);
  const fs::path out(out_dir);
  fs::create_directories(out);
  std::vector<SuiteResult> results;
  const auto t0 = Clock::now();
  size_t index = 0;
  size_t planned = 0;
  for (const SuiteEntry& e : suite.entries) {
    planned += options.only.empty() || std::count(options.only.begin(), options.only.end(), e.name);
  }
  for (const SuiteEntry& e : suite.entries) {
    if (!options.only.empty() && !std::count(options.only.begin(), options.only.end(), e.name)) continue;
    ++index;
    const std::string counter = "[" + std::to_string(index) + "/" + std::to_string(planned) + "] ";
    if (const std::string missing = MissingInput(suite, e); !missing.empty()) {
      SuiteResult r;
      r.entry = e;
      r.skipped = true;
      r.skip_reason = missing + " not found";
      if (options.progress) std::cerr << "eval-slam suite: " << counter << e.name << ": skipped, " << r.skip_reason << "\n";
      results.push_back(r);
      continue;
    }
    const auto t_run = Clock::now();
    SuiteResult r = RunEntry(suite, e, slam_options, backend, out / e.name, options);
    results.push_back(r);
    if (options.progress) {
      std::cerr << "eval-slam suite: " << counter << e.name << ": " << r.scans << " scans, ATE laser slam "
                << Cell(r.slam) << " m (thesis " << Cell(r.thesis, 2) << ", icp-slam " << Cell(r.icp_slam, 2)
                << ", dead reckoning " << Cell(r.dead_reckoning, 2) << "), " << Fixed(r.slam_ms_per_scan, 2)
                << " ms/scan: " << (r.pass ? "pass" : "FAIL (" + r.failed + ")");
      if (r.graph_ran) {
        std::cerr << "; graph back end " << Cell(r.graph) << " m (EKF " << Cell(r.ekf) << "), closures "
                  << r.closures.accepted << " / " << r.closures.rejected << " / " << r.closures.wrong << " wrong, "
                  << Fixed(r.graph_front_ms_per_scan, 2) << " + " << Fixed(r.graph_back_ms_per_scan, 2)
                  << " ms/scan: " << (r.graph_pass ? "pass" : "FAIL (" + r.graph_failed + ")");
      }
      std::cerr << "; map consistency EKF " << Cell(r.ekf_consistency_m) << (r.graph_ran ? ", graph " + Cell(r.graph_consistency_m) : "")
                << ", reference " << Cell(r.reference_consistency_m) << " m"
                << (r.reference_check.suspects.empty() ? std::string()
                                                       : "; reference check: " + DescribeReferenceCheck(r.reference_check))
                << " ["
                << Fixed(std::chrono::duration<double>(Clock::now() - t_run).count(), 1) << " s]\n";
    }
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  int runs = 0, passed = 0, skipped = 0, graph_runs = 0, graph_passed = 0;
  for (const SuiteResult& r : results) {
    skipped += r.skipped;
    runs += !r.skipped;
    passed += !r.skipped && r.pass;
    graph_runs += !r.skipped && r.graph_ran;
    graph_passed += !r.skipped && r.graph_ran && r.graph_pass;
  }
  {
    std::ofstream md(out / "suite.md");
    md << "# Laser SLAM suite: " << suite.path << "\n\n"
       << "Laser SLAM config " << suite.laser_slam_config;
    for (const std::string& o : options.overrides) md << ", " << o;
    md << "; ATE = RMSE of the scan poses after SE(2) alignment with the reference. " << passed << " of " << runs
       << " runs meet their goals" << (skipped ? ", " + std::to_string(skipped) + " skipped" : std::string()) << "; "
       << Fixed(seconds, 0) << " s. Laser SLAM is the config's back end (" << (backend.graph ? "graph" : "ekf")
       << ").\n\n";
    WriteSuiteTable(md, results);
    if (graph_runs > 0) {
      md << "\n## The graph back end beside the EKF\n\n"
         << "ATE of the optimized trajectory (every scan's pose after the last optimization) and of the pose as "
            "published at each scan (live); RPE = translation RMSE over segments of 1 m and 10 m of the "
            "reference's travel; a closure is wrong when its two poses are more than 0.5 m or 5 deg apart in the "
            "reference. "
         << graph_passed << " of " << graph_runs << " runs meet the graph back end's goals.\n\n";
      WriteGraphTable(md, results);
    }
    {
      // The references' own consistency (CheckReference).
      const ReferenceCheckOptions c;
      md << "\n## The references checked against their scans\n\n"
         << "Each reference pose with a scan, against the " << c.window << " scans before it at their reference "
         << "poses: suspect when the scan fits at least " << Fixed(c.min_gain, 2) << " better (share of points within "
         << Fixed(c.near_m, 2) << " m) at another heading within " << Fixed(c.max_turn_deg, 0) << " deg. Odometry made "
         << "from such a reference (carmen_raw_like.py) carries the jump.\n\n";
      int clean = 0, checked = 0;
      for (const SuiteResult& r : results) {
        if (r.skipped) continue;
        ++checked;
        if (r.reference_check.suspects.empty()) {
          ++clean;
          continue;
        }
        md << "- " << r.entry.name << ": " << DescribeReferenceCheck(r.reference_check) << "\n";
      }
      md << (clean == checked ? "" : "\n") << clean << " of " << checked << " runs' references: no suspect pose.\n";
    }
    WriteOdometryTable(md, results);
    // Map consistency per run: the EKF's, the graph's and the reference's, side by side.
    std::vector<plot::BarGroup> groups;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const SuiteResult& r : results) {
      if (r.skipped) continue;
      groups.push_back({r.entry.name,
                        {r.ekf_consistency_m.value_or(nan), r.graph_ran ? r.graph_consistency_m.value_or(nan) : nan,
                         r.reference_consistency_m.value_or(nan)}});
    }
    double highest = 0;
    for (const plot::BarGroup& g : groups) {
      for (const double v : g.values) {
        if (std::isfinite(v)) highest = std::max(highest, v);
      }
    }
    if (highest > 0) {
      plot::Axes axes;
      axes.y_min = 0;
      axes.y_max = 1.35 * highest;  // room for the legend above the bars
      axes.title = "Map consistency per run (lower is sharper; needs no reference)";
      axes.y_label = "median distance to scans seen again [m]";
      plot::SavePng(plot::BarChart(axes, {"EKF", "graph back end", "reference"}, groups,
                                   {std::max(800, 120 * static_cast<int>(groups.size())), 500}),
                    (out / "consistency.png").string());
      md << "\n## Map consistency\n\nThe median distance of a scan's points to the scans seen again at that place "
            "(over the scans the reference has), for each trajectory: a figure that needs no reference.\n\n"
            "![map consistency per run](consistency.png)\n";
    }
  }
  {
    std::ofstream csv(out / "suite.csv");
    csv << "run,kind,noise,seed,every,scans,skipped,laser_slam_ate_rmse_m,laser_slam_ate_max_m,thesis_ate_rmse_m,"
           "icp_slam_ate_rmse_m,dead_reckoning_ate_rmse_m,laser_slam_ms_per_scan,thesis_ms_per_scan,"
           "icp_slam_ms_per_scan,accepted,gated,ambiguous,no_match,stale_predictions,catch_up_predictions,"
           "goal_ate_m,no_worse_than_dead_reckoning,pass,backend,ekf_ate_rmse_m,ekf_rpe_1m_m,ekf_rpe_10m_m,"
           "graph_ate_rmse_m,graph_ate_max_m,graph_live_ate_rmse_m,graph_rpe_1m_m,graph_rpe_1m_deg,graph_rpe_10m_m,"
           "graph_rpe_10m_deg,loop_candidates,loop_accepted,loop_rejected,loop_wrong,loop_switched_off,keyframes,"
           "corrections,graph_front_ms_per_scan,graph_back_ms_per_scan,graph_back_max_ms,graph_goal_ate_m,graph_pass,"
           "ekf_map_consistency_m,graph_map_consistency_m,reference_map_consistency_m,laser_max_range_m,"
           "odometry_drift_deg_per_m,odometry_turn_scale,odometry_distance_scale,odometry_stretches,"
           "reference_odometry_drift_deg_per_m,reference_odometry_turn_scale,reference_odometry_distance_scale\n";
    const auto num = [](const AteFigure& f, bool max = false) {
      return f.measured ? Fixed(max ? f.max_m : f.rmse_m, 4) : std::string();
    };
    for (const SuiteResult& r : results) {
      const SuiteEntry& e = r.entry;
      csv << e.name << "," << e.kind << "," << e.noise << "," << e.noise_seed << "," << e.every << "," << r.scans
          << "," << (r.skipped ? 1 : 0) << "," << num(r.slam) << "," << num(r.slam, true) << "," << num(r.thesis)
          << "," << num(r.icp_slam) << "," << num(r.dead_reckoning) << "," << Fixed(r.slam_ms_per_scan, 3) << ","
          << Fixed(r.thesis_ms_per_scan, 3) << "," << (r.icp_slam_ran ? Fixed(r.icp_slam_ms_per_scan, 3) : "") << "," << r.outcomes.accepted
          << "," << r.outcomes.gated << "," << r.outcomes.ambiguous << "," << r.outcomes.no_match << ","
          << r.outcomes.stale_predictions << "," << r.outcomes.catch_up_predictions << "," << e.goal_ate_m << ","
          << (e.no_worse_than_dead_reckoning ? 1 : 0) << "," << (r.skipped ? "" : r.pass ? "1" : "0") << ","
          << r.backend << "," << num(r.ekf) << "," << (r.ekf_rpe.measured ? Fixed(r.ekf_rpe.translation_1m_m, 4) : "")
          << "," << (r.ekf_rpe.measured ? Fixed(r.ekf_rpe.translation_10m_m, 4) : "") << ",";
      if (r.graph_ran) {
        csv << num(r.graph) << "," << num(r.graph, true) << "," << num(r.graph_live) << ","
            << Fixed(r.graph_rpe.translation_1m_m, 4) << "," << Fixed(r.graph_rpe.rotation_1m_deg, 3) << ","
            << Fixed(r.graph_rpe.translation_10m_m, 4) << "," << Fixed(r.graph_rpe.rotation_10m_deg, 3) << ","
            << r.closures.candidates << "," << r.closures.accepted << "," << r.closures.rejected << ","
            << r.closures.wrong << "," << r.closures.switched_off << "," << r.keyframes << "," << r.corrections << ","
            << Fixed(r.graph_front_ms_per_scan, 3) << "," << Fixed(r.graph_back_ms_per_scan, 3) << ","
            << Fixed(r.graph_back_max_ms, 1) << "," << e.graph_goal_ate_m << "," << (r.graph_pass ? "1" : "0");
      } else {
        csv << ",,,,,,,,,,,,,,,,,,";
      }
      const auto opt = [](const std::optional<double>& v) { return v ? Fixed(*v, 4) : std::string(); };
      csv << "," << opt(r.ekf_consistency_m) << "," << opt(r.graph_consistency_m) << ","
          << opt(r.reference_consistency_m) << "," << (e.laser_max_range_m > 0 ? Fixed(e.laser_max_range_m, 2) : "");
      const auto odo = [&](const OdometryFigure& f, bool stretches) {
        if (!f.measured) return std::string(stretches ? ",,,," : ",,,");
        return "," + Fixed(f.drift_deg_per_m, 3) + "," + Fixed(f.turn_scale, 4) + "," + Fixed(f.distance_scale, 4) +
               (stretches ? "," + std::to_string(f.stretches) : "");
      };
      csv << odo(r.odometry, true) << odo(r.reference_odometry, false) << "\n";
    }
  }
  {
    // Keys in the order they are set (`results` is the suite's results here: the writer by its full name).
    snapnav::results::Json j;
    j["suite"] = suite.path;
    j["laser_slam_config"] = suite.laser_slam_config;
    j["laser_slam_overrides"] = options.overrides;
    j["runs"] = runs;
    j["runs_passed"] = passed;
    j["runs_skipped"] = skipped;
    j["backend"] = backend.graph ? "graph" : "ekf";
    j["graph_runs"] = graph_runs;
    j["graph_runs_passed"] = graph_passed;
    j["seconds"] = seconds;
    for (const SuiteResult& r : results) {
      const std::string k = r.entry.name + "_";
      j[k + "skipped"] = r.skipped;
      if (r.skipped) continue;
      j[k + "scans"] = r.scans;
      if (r.entry.laser_max_range_m > 0) j[k + "laser_max_range_m"] = r.entry.laser_max_range_m;
      if (r.slam.measured) {
        j[k + "laser_slam_ate_rmse_m"] = r.slam.rmse_m;
        j[k + "laser_slam_ate_max_m"] = r.slam.max_m;
      }
      if (r.thesis.measured) j[k + "thesis_ate_rmse_m"] = r.thesis.rmse_m;
      if (r.icp_slam.measured) j[k + "icp_slam_ate_rmse_m"] = r.icp_slam.rmse_m;
      if (r.dead_reckoning.measured) j[k + "dead_reckoning_ate_rmse_m"] = r.dead_reckoning.rmse_m;
      j[k + "laser_slam_ms_per_scan"] = r.slam_ms_per_scan;
      if (r.icp_slam_ran) j[k + "icp_slam_ms_per_scan"] = r.icp_slam_ms_per_scan;
      j[k + "accepted_scans"] = r.outcomes.accepted;
      j[k + "gated_scans"] = r.outcomes.gated;
      j[k + "ambiguous_scans"] = r.outcomes.ambiguous;
      j[k + "no_match_scans"] = r.outcomes.no_match;
      j[k + "pass"] = r.pass;
      j[k + "png"] = r.png;
      if (r.ekf.measured) j[k + "ekf_ate_rmse_m"] = r.ekf.rmse_m;
      if (r.ekf_consistency_m) j[k + "ekf_map_consistency_m"] = *r.ekf_consistency_m;
      if (r.graph_consistency_m) j[k + "graph_map_consistency_m"] = *r.graph_consistency_m;
      if (r.reference_consistency_m) j[k + "reference_map_consistency_m"] = *r.reference_consistency_m;
      j[k + "reference_checked_poses"] = r.reference_check.checked;
      j[k + "reference_suspect_poses"] = r.reference_check.suspects.size();
      for (const auto& [prefix, f] : {std::pair<std::string, const OdometryFigure*>{"odometry_", &r.odometry},
                                      {"reference_odometry_", &r.reference_odometry}}) {
        if (!f->measured) continue;
        j[k + prefix + "drift_deg_per_m"] = f->drift_deg_per_m;
        j[k + prefix + "turn_scale"] = f->turn_scale;
        j[k + prefix + "distance_scale"] = f->distance_scale;
        j[k + prefix + "stretches"] = f->stretches;
      }
      if (r.ekf_rpe.measured) {
        j[k + "ekf_rpe_1m_m"] = r.ekf_rpe.translation_1m_m;
        j[k + "ekf_rpe_10m_m"] = r.ekf_rpe.translation_10m_m;
      }
      if (r.graph_ran) {
        if (r.graph.measured) {
          j[k + "graph_ate_rmse_m"] = r.graph.rmse_m;
          j[k + "graph_ate_max_m"] = r.graph.max_m;
        }
        if (r.graph_live.measured) j[k + "graph_live_ate_rmse_m"] = r.graph_live.rmse_m;
        if (r.graph_rpe.measured) {
          j[k + "graph_rpe_1m_m"] = r.graph_rpe.translation_1m_m;
          j[k + "graph_rpe_1m_deg"] = r.graph_rpe.rotation_1m_deg;
          j[k + "graph_rpe_10m_m"] = r.graph_rpe.translation_10m_m;
          j[k + "graph_rpe_10m_deg"] = r.graph_rpe.rotation_10m_deg;
        }
        j[k + "loop_candidates"] = r.closures.candidates;
        j[k + "loop_accepted"] = r.closures.accepted;
        j[k + "loop_rejected"] = r.closures.rejected;
        j[k + "loop_wrong"] = r.closures.wrong;
        j[k + "loop_switched_off"] = r.closures.switched_off;
        j[k + "keyframes"] = r.keyframes;
        j[k + "corrections"] = r.corrections;
        j[k + "graph_front_ms_per_scan"] = r.graph_front_ms_per_scan;
        j[k + "graph_back_ms_per_scan"] = r.graph_back_ms_per_scan;
        j[k + "graph_back_max_ms"] = r.graph_back_max_ms;
        j[k + "graph_pass"] = r.graph_pass;
        j[k + "graph_png"] = r.graph_png;
      }
    }
    snapnav::results::WriteJsonFile((out / "summary.json").string(), j);
  }
  if (options.progress) {
    if (graph_runs > 0) {
      std::cerr << "eval-slam suite: graph back end: " << graph_passed << " of " << graph_runs
                << " runs meet its goals\n";
    }
    std::cerr << "eval-slam suite: " << passed << " of " << runs << " runs meet their goals"
              << (skipped ? ", " + std::to_string(skipped) + " skipped" : std::string()) << " (" << Fixed(seconds, 0)
              << " s); " << (out / "suite.md").string() << ", suite.csv, summary.json\n";
  }
  return results;
}

}  // namespace snapnav::eval
