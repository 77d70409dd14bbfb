// bench-compare (./snapnav bench compare): ms per update of each method of the SLAM comparison
// (dead reckoning, laser SLAM, RatSLAM, fused SLAM with its place-cell front end) on one core, the
// median over several runs of the same simulated run (eval::RunComparison), against the budget of
// 10 Hz frames and scans (100 ms per period).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include <opencv2/core.hpp>

#include "compare_config.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "stats.hpp"
#include "slam_compare.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

const double kNaN = std::nan("");

// The median of the runs' figures; NaN (null in the JSON) for none.
double Median(const std::vector<double>& v) { return eval::Median(v, kNaN); }

results::Json Json(double v) { return results::Rounded(v, 5); }

std::string Margin(double ms) { return ms > 0.1 ? eval::Fixed(100.0 / ms, 0) + "x" : "> 1000x"; }

int Main(int argc, char** argv) {
  std::string scene = "corridor", out_dir = "logs/bench-compare";
  int runs = 5;
  double duration_s = 60;
  eval::CompareConfigPaths paths;
  eval::CompareOptions o;
  glue::Flags flags("bench-compare",
                    "Time per update of every method of the SLAM comparison on one core (run it under taskset -c 0;\n"
                    "./snapnav bench compare does): the same simulated run (--scene, --duration-s) --runs times, the\n"
                    "median of each method's mean ms per update: dead reckoning per odometry message, laser SLAM and\n"
                    "fused SLAM per scan, fused SLAM per visual measurement (the filter) and its place-cell front end\n"
                    "(view + query, the placecells process' work) per fix, RatSLAM per frame. The budget is 100 ms per\n"
                    "10 Hz frame period; the margin is budget / ms per period. Writes bench.json and bench.md.");
  flags.AddString("scene", &scene, "scene of the run");
  flags.AddDouble("duration-s", &duration_s, "simulated seconds per run");
  flags.AddInt("runs", &runs, "runs (the median is reported)");
  flags.AddDouble("visual-rate-hz", &o.visual_rate_hz, "place-cell fixes per simulated second");
  flags.AddDouble("ratslam-rate-hz", &o.ratslam_rate_hz, "frames per simulated second given to RatSLAM");
  flags.AddString("out", &out_dir, "output folder");
  if (!flags.Parse(argc, argv)) return 0;
  if (runs < 1 || !(duration_s > 0)) throw glue::FlagError("--runs >= 1 and --duration-s > 0");
  cv::setNumThreads(1);  // one core (./snapnav bench pins the process with taskset -c 0)
  const processes::SimConfig sim_config = eval::LoadCompareConfigs(paths, &o);
  o.Validate();
  const auto loaded = processes::LoadSceneFile(processes::SceneFilePath(scene));
  eval::CompareRunOptions run;
  run.name = scene;
  run.sim = eval::SimSlamOptions::FromSimConfig(sim_config);
  run.sim.scene = scene;
  run.sim.laps = 0;
  run.sim.duration_s = duration_s;
  run.sim.kidnap = {};
  std::cerr << "bench-compare: exploring " << scene << " for the place-cell memory\n";
  const eval::RouteMemory memory = eval::ExploreRouteMemory(loaded, o, run.sim);
  std::cerr << "bench-compare: " << memory.memory->size() << " cells; " << runs << " runs of " << duration_s
            << " s simulated\n";

  std::map<std::string, std::vector<double>> per_update, per_frame;
  std::vector<double> view_ms, localize_ms, visual_filter_ms;
  for (int i = 0; i < runs; ++i) {
    const eval::CompareRun r = eval::RunComparison(loaded, memory, run, o);
    for (const auto& m : r.methods) {
      if (!m.ran) continue;
      per_update[m.name].push_back(m.ms_per_update);
      per_frame[m.name].push_back(m.ms_per_frame);
    }
    view_ms.push_back(r.ms_per_view);
    localize_ms.push_back(r.ms_per_localize);
    visual_filter_ms.push_back(r.ms_per_fix_filter);
    std::cerr << "bench-compare: run " << i + 1 << "/" << runs << " done (" << eval::Fixed(r.seconds, 0) << " s)\n";
  }

  const double view = Median(view_ms), localize = Median(localize_ms), filter = Median(visual_filter_ms);
  std::ostringstream md;
  results::Json json;
  md << "# bench compare: " << scene << ", " << duration_s << " s simulated, median of " << runs
     << " runs, one core\n\n| method | ms per update | update | ms per 10 Hz period | margin (100 ms / period) |\n"
        "|---|---|---|---|---|\n";
  json["scene"] = scene;
  json["duration_s"] = results::Significant(duration_s);
  json["runs"] = runs;
  json["visual_rate_hz"] = results::Significant(o.visual_rate_hz);
  json["ratslam_rate_hz"] = results::Significant(o.ratslam_rate_hz);
  const std::map<std::string, std::string> units = {{"dead_reckoning", "odometry message"},
                                                    {"laser_slam", "scan"},
                                                    {"ratslam", "frame (" + eval::Fixed(o.ratslam_rate_hz, 0) + " Hz)"},
                                                    {"fused_slam", "scan"},
                                                    {"fused_no_vision", "scan"}};
  for (const auto& name : eval::CompareMethodNames()) {
    if (!per_update.count(name)) {
      md << "| " << name << " | not run | | | |\n";
      json[name + "_ms_per_update"] = nullptr;
      json[name + "_ms_per_frame"] = nullptr;
      continue;
    }
    const double u = Median(per_update[name]), f = Median(per_frame[name]);
    md << "| " << name << " | " << eval::Fixed(u, 4) << " | " << units.at(name) << " | " << eval::Fixed(f, 3) << " | "
       << Margin(f) << " |\n";
    json[name + "_ms_per_update"] = Json(u);
    json[name + "_ms_per_frame"] = Json(f);
    std::cout << std::left << std::setw(16) << name << std::right << " " << eval::Fixed(u, 4) << " ms per "
              << units.at(name) << ", " << eval::Fixed(f, 3) << " ms per 10 Hz period (margin " << Margin(f) << ")\n";
  }
  // Fused SLAM's visual part: the place-cell front end and the filter's visual update.
  const double scan = per_update.count("fused_slam") ? Median(per_update["fused_slam"]) : std::nan("");
  const double every_frame = scan + view + localize + filter;  // a fix with every 10 Hz frame
  md << "\nFused SLAM's visual measurement: place-cell view " << eval::Fixed(view, 1) << " ms + query "
     << eval::Fixed(localize, 1) << " ms (the placecells process), filter update " << eval::Fixed(filter, 3)
     << " ms; with a fix on every 10 Hz frame the period would take " << eval::Fixed(every_frame, 1) << " ms (margin "
     << eval::Fixed(100.0 / every_frame, 1) << "x); at " << o.visual_rate_hz << " Hz fixes it is the per-period figure above.\n";
  json["place_cells_ms_per_view"] = Json(view);
  json["place_cells_ms_per_localize"] = Json(localize);
  json["fused_slam_ms_per_visual_update"] = Json(filter);
  json["fused_slam_ms_per_frame_with_a_fix_every_frame"] = Json(every_frame);
  std::cout << "fused_slam visual: view " << eval::Fixed(view, 1) << " ms + query " << eval::Fixed(localize, 1)
            << " ms + filter " << eval::Fixed(filter, 3) << " ms per fix; a fix every frame: " << eval::Fixed(every_frame, 1)
            << " ms per period\n";
  fs::create_directories(out_dir);
  std::ofstream(fs::path(out_dir) / "bench.md") << md.str();
  results::WriteJsonFile((fs::path(out_dir) / "bench.json").string(), json);
  std::cerr << "bench-compare: wrote " << (fs::path(out_dir) / "bench.json").string() << " and bench.md\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
