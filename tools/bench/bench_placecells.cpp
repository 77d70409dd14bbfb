// bench-placecells: the cost of one place-cell localization query (PlaceCellMemory::Localize)
// against memories of 100, 1,000 and 10,000 cells on one core, with the vocabulary-tree index,
// beside the exhaustive comparison against every cell measured in the same process.
//
// Views are real: panoramas of a simulated scene (raw omni images rendered and unwrapped, as the
// placecells process gets them) at random positions, made into PlaceViews with the placecells
// config. The first `--base-cells` views are the memory of the smallest size. Larger memories add
// synthetic cells made from them (documented in bench.md): copy k of base cell b stands in a
// copy of the room k x 10 m away (rooms on a 10 m lattice, 10 per row), its position jittered by
// N(0, 5 cm); each landmark is kept with probability 0.9, its column moved by N(0, 1 px) and each
// descriptor value by N(0, 6) (rounded, clamped to [0, 255]), so no two cells are alike and the
// vocabulary sees as many distinct descriptors as a larger building would give; the lines,
// windows and signature are the base cell's. Queries are the other rendered views (positions
// off the cells, in the first room), with the odometry prediction = truth + N(0, 0.25 m) per axis.
//
// Figures: median over --runs of the mean ms per query (MakePlaceView excluded, reported
// separately), the growth per 10x cells, the exhaustive baseline (every cell compared, same
// Localize) and its ratio, memory per cell, index build time. Goal: <= 50 ms at 1,000 cells.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

#include <opencv2/core/utility.hpp>

#include "bench_timing.hpp"
#include "homing_eval.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "stats.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/place_cells.hpp"
#include "snapnav/nav/places/place_cells.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using Clock = std::chrono::steady_clock;
using eval::Fixed;
using eval::Median;

constexpr double kGoalMsAt1000 = 50;
constexpr double kRoomPitchM = 10;  // synthetic cells: copies of the room on a 10 m lattice
constexpr int kRoomsPerRow = 10;

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }


// A synthetic view from a real one (see the file comment).
nav::PlaceView Perturb(const nav::PlaceView& base, std::mt19937_64& rng) {
  std::bernoulli_distribution keep(0.9);
  std::normal_distribution<double> column(0.0, 1.0), value(0.0, 6.0);
  nav::PlaceView v;
  v.landmarks.method = base.landmarks.method;
  v.landmarks.width_px = base.landmarks.width_px;
  v.landmarks.height_px = base.landmarks.height_px;
  std::vector<int> rows;
  for (int i = 0; i < base.landmarks.size(); ++i) {
    if (keep(rng)) rows.push_back(i);
  }
  const cv::Mat& d = base.landmarks.descriptors;
  v.landmarks.descriptors.create(static_cast<int>(rows.size()), d.cols, CV_32F);
  v.windows.create(static_cast<int>(rows.size()), base.windows.cols, base.windows.type());
  const float width = static_cast<float>(base.landmarks.width_px);
  for (size_t k = 0; k < rows.size(); ++k) {
    nav::Landmark l = base.landmarks.landmarks[rows[k]];
    l.x_px = std::fmod(l.x_px + static_cast<float>(column(rng)) + width, width);
    v.landmarks.landmarks.push_back(l);
    const float* in = d.ptr<float>(rows[k]);
    float* out = v.landmarks.descriptors.ptr<float>(static_cast<int>(k));
    for (int c = 0; c < d.cols; ++c) {
      out[c] = static_cast<float>(std::clamp(std::round(in[c] + value(rng)), 0.0, 255.0));
    }
    if (!base.windows.empty()) base.windows.row(rows[k]).copyTo(v.windows.row(static_cast<int>(k)));
  }
  v.vlines = base.vlines;
  v.signature = base.signature;
  return v;
}

struct SizeResult {
  int cells = 0;
  double build_ms = 0;
  double ms_per_query = 0;
  double mean_error_m = 0;
  double candidates = 0;
  double bytes_per_cell = 0;
  double exhaustive_ms = -1;  // < 0: not measured
  double exhaustive_error_m = 0;
};

int Main(int argc, char** argv) {
  std::string scene_name = "indoor13", out_dir, sizes_text = "100,1000,10000", baseline_text = "100,1000";
  std::string config_path = SNAPNAV_CONFIG_DIR "/placecells.ini", sim_path = SNAPNAV_CONFIG_DIR "/sim.ini";
  int base_cells = 100, query_views = 30, runs = 5, per_run = 20, baseline_runs = 3, baseline_per_run = 4, seed = 1;
  int build_runs = 3;
  double prediction_sigma_m = 0.25;
  glue::Flags flags("bench-placecells",
                    "Cost of one place-cell localization query on one core against memories of 100, 1,000 and\n"
                    "10,000 cells (vocabulary-tree candidates), beside the exhaustive comparison with every cell\n"
                    "(same process), from real views of a simulated scene; larger memories are made of perturbed\n"
                    "copies of the real cells in copies of the room (bench.md says how). Median of --runs runs;\n"
                    "view extraction is reported apart. Goal: <= 50 ms at 1,000 cells. Writes bench.md and\n"
                    "bench.json into --out.");
  flags.AddString("scene", &scene_name, "scene the views are rendered in");
  flags.AddString("config", &config_path, "place-cell config (view, localizer, vocabulary)");
  flags.AddString("sim-config", &sim_path, "simulator config (camera)");
  flags.AddString("sizes", &sizes_text, "memory sizes (cells); the first is made of real views only");
  flags.AddString("baseline-sizes", &baseline_text, "sizes at which the exhaustive comparison is timed");
  flags.AddInt("base-cells", &base_cells, "real views rendered for the memory");
  flags.AddInt("query-views", &query_views, "real views rendered for the queries");
  flags.AddInt("runs", &runs, "runs per figure (median)");
  flags.AddInt("queries", &per_run, "queries per run");
  flags.AddInt("baseline-runs", &baseline_runs, "runs of the exhaustive baseline");
  flags.AddInt("baseline-queries", &baseline_per_run, "queries per run of the exhaustive baseline");
  flags.AddInt("build-runs", &build_runs, "index builds per size (median)");
  flags.AddDouble("prediction-sigma-m", &prediction_sigma_m, "odometry prediction noise per axis [m]");
  flags.AddInt("seed", &seed, "seed of positions, perturbations and prediction noise");
  flags.AddString("out", &out_dir, "folder for bench.md and bench.json");
  if (!flags.Parse(argc, argv)) return 0;
  std::vector<int> sizes, baseline_sizes;
  for (const auto& s : glue::SplitList(sizes_text)) sizes.push_back(std::stoi(s));
  for (const auto& s : glue::SplitList(baseline_text)) baseline_sizes.push_back(std::stoi(s));
  std::sort(sizes.begin(), sizes.end());
  if (sizes.empty() || sizes.front() < 1) throw glue::FlagError("--sizes must list positive sizes");
  if (base_cells < 1 || query_views < 1 || runs < 1 || per_run < 1 || baseline_runs < 1 || baseline_per_run < 1 ||
      build_runs < 1) {
    throw glue::FlagError("--base-cells, --query-views, --runs, --queries, --baseline-* and --build-runs must be >= 1");
  }
  if (sizes.front() > base_cells) throw glue::FlagError("the smallest --sizes must be at most --base-cells");
  cv::setNumThreads(1);  // one core (./snapnav bench pins the process with taskset -c 0)

  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(sim_path), "");
  const auto ini = glue::IniFile::Load(config_path);
  const nav::PlaceViewOptions view_options = glue::ReadPlaceViewOptions(ini);
  const nav::LocalizerOptions lo = glue::ReadLocalizerOptions(ini);
  const nav::VocabularyOptions vocabulary = glue::ReadVocabularyOptions(ini);
  std::cerr << "bench-placecells: config " << config_path << ":\n";
  glue::PrintPlaceViewOptions(std::cerr, view_options);
  glue::PrintLocalizerOptions(std::cerr, lo);
  glue::PrintVocabularyOptions(std::cerr, vocabulary);
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  if (scene.grid.nx < 2 || scene.grid.ny < 2) throw std::runtime_error("scene '" + scene.name + "' has no grid");

  // Real views: cells at random positions around the grid, queries inside it.
  eval::ViewRenderer renderer(scene, sim.camera, static_cast<uint64_t>(seed));
  eval::CameraPipeline pipeline;
  std::mt19937_64 rng(static_cast<uint64_t>(seed));
  const Eigen::Vector2d lo_xy = scene.grid.Position(0, 0), hi_xy = scene.grid.Position(scene.grid.nx - 1, scene.grid.ny - 1);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI);
  auto random_pose = [&](double margin) {
    std::uniform_real_distribution<double> ux(lo_xy.x() - margin, hi_xy.x() + margin), uy(lo_xy.y() - margin, hi_xy.y() + margin);
    const double x = ux(rng), y = uy(rng);
    return nav::Pose2{x, y, heading(rng)};
  };
  std::vector<nav::Pose2> cell_poses, query_poses;
  std::vector<nav::PlaceView> cell_views, query_views_v;
  std::vector<double> extract_ms;
  double landmarks = 0;
  const int total = base_cells + query_views;
  for (int i = 0; i < total; ++i) {
    const nav::Pose2 pose = i < base_cells ? random_pose(0.2) : random_pose(0.0);
    const cv::Mat pano = renderer.ToPanorama(renderer.Sensor(pose, eval::CameraPipeline::Input::kRaw, {}), pipeline);
    const auto t0 = Clock::now();
    nav::PlaceView v = nav::MakePlaceView(pano, view_options);
    extract_ms.push_back(1000 * Seconds(t0));
    landmarks += v.landmarks.size();
    (i < base_cells ? cell_poses : query_poses).push_back(pose);
    (i < base_cells ? cell_views : query_views_v).push_back(std::move(v));
    if ((i + 1) % 10 == 0 || i + 1 == total) {
      std::cerr << "bench-placecells: views " << i + 1 << "/" << total << (i + 1 == total ? "\n" : "\r") << std::flush;
    }
  }
  double view_bytes = 0;
  for (const auto& v : cell_views) view_bytes += static_cast<double>(v.bytes());
  view_bytes /= cell_views.size();
  std::normal_distribution<double> noise(0.0, prediction_sigma_m);
  std::vector<nav::Pose2> predicted;
  for (const auto& q : query_poses) predicted.push_back({q.x_m + noise(rng), q.y_m + noise(rng), q.theta_rad});

  // Memories: grown in place from the smallest size, one synthetic cell at a time.
  nav::PlaceCellMemory memory(view_options, sim.camera.panorama, vocabulary);
  std::mt19937_64 perturb_rng(static_cast<uint64_t>(seed) + 101);
  std::normal_distribution<double> jitter(0.0, 0.05);
  std::vector<SizeResult> size_results;
  int next_copy = 0;
  for (int size : sizes) {
    while (memory.size() < size) {
      const int n = memory.size();
      if (n < sizes.front()) {
        memory.Add(cell_poses[n], n, cell_views[n]);
        continue;
      }
      const int b = next_copy % sizes.front();
      const int copy = 1 + next_copy / sizes.front();
      ++next_copy;
      const nav::Pose2& p = cell_poses[b];
      const nav::Pose2 pose{p.x_m + kRoomPitchM * (copy % kRoomsPerRow) + jitter(perturb_rng),
                            p.y_m + kRoomPitchM * (copy / kRoomsPerRow) + jitter(perturb_rng), p.theta_rad};
      memory.Add(pose, n, Perturb(cell_views[b], perturb_rng));
      if (memory.size() % 500 == 0) {
        std::cerr << "bench-placecells: memory " << memory.size() << "/" << size << "\r" << std::flush;
      }
    }
    SizeResult r;
    r.cells = size;
    std::vector<double> builds;
    for (int k = 0; k < build_runs; ++k) {
      const auto t0 = Clock::now();
      memory.BuildIndex();
      builds.push_back(1000 * Seconds(t0));
    }
    r.build_ms = Median(builds);
    r.bytes_per_cell = static_cast<double>(memory.bytes()) / size;
    const int q = static_cast<int>(query_views_v.size());
    // Accuracy and candidates, one pass over the queries (the index must still find the room).
    auto pass = [&](const nav::LocalizerOptions& o, double* candidates) {
      double err = 0;
      for (int i = 0; i < q; ++i) {
        const auto loc = memory.Localize(query_views_v[i], predicted[i], o);
        const nav::Pose2 est = loc ? loc->pose : predicted[i];
        err += std::hypot(est.x_m - query_poses[i].x_m, est.y_m - query_poses[i].y_m);
        if (candidates && loc) *candidates += loc->candidates;
      }
      if (candidates) *candidates /= q;
      return err / q;
    };
    r.mean_error_m = pass(lo, &r.candidates);
    r.ms_per_query = 1000 * bench::MedianSecondsPerCall(runs, per_run, [&](int i) {
      (void)memory.Localize(query_views_v[i % q], predicted[i % q], lo);
    });
    std::cerr << "bench-placecells: " << size << " cells: " << Fixed(r.ms_per_query, 2) << " ms/query ("
              << Fixed(r.candidates, 1) << " candidates, mean error " << Fixed(r.mean_error_m, 3) << " m), index build "
              << Fixed(r.build_ms, 0) << " ms, " << Fixed(r.bytes_per_cell / 1024, 1) << " KiB/cell\n";
    if (std::find(baseline_sizes.begin(), baseline_sizes.end(), size) != baseline_sizes.end()) {
      nav::LocalizerOptions ex = lo;
      ex.exhaustive_below = size;  // every cell is a candidate
      r.exhaustive_error_m = pass(ex, nullptr);
      r.exhaustive_ms = 1000 * bench::MedianSecondsPerCall(baseline_runs, baseline_per_run, [&](int i) {
        (void)memory.Localize(query_views_v[i % q], predicted[i % q], ex);
      });
      std::cerr << "bench-placecells: " << size << " cells, exhaustive: " << Fixed(r.exhaustive_ms, 1)
                << " ms/query (mean error " << Fixed(r.exhaustive_error_m, 3) << " m)\n";
    }
    size_results.push_back(r);
  }

  // Report.
  const double extract = Median(extract_ms);
  std::ostringstream md;
  md << "# Place-cell localization query, one core (scene " << scene.name << ")\n\n"
     << "One `PlaceCellMemory::Localize` per query: vocabulary-tree candidates (" << lo.candidates << " by votes + "
     << lo.near_candidates << " nearest the prediction), measure " << nav::PlaceMeasureName(lo.measure.measure) << " ("
     << nav::MatchRefinementName(lo.measure.refinement) << "), distance filter "
     << (lo.filter.enabled ? "on" : "off") << ", estimate " << nav::PlaceEstimateName(lo.estimate)
     << "; config " << config_path << ". Median of " << runs << " runs x " << per_run
     << " queries (exhaustive: " << baseline_runs << " x " << baseline_per_run << "). The view of the query (MakePlaceView: "
     << nav::LandmarkMethodName(view_options.features.method) << ", windows, lines, signature) is made beforehand: median "
     << Fixed(extract, 1) << " ms per panorama, " << Fixed(landmarks / total, 0) << " landmarks.\n\n"
     << "| cells | ms/query | per 10x cells | candidates | mean error [m] | exhaustive ms/query | exhaustive / indexed | "
        "exhaustive error [m] | index build [ms] | bytes/cell |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < size_results.size(); ++i) {
    const auto& r = size_results[i];
    std::string growth = "-";
    if (i > 0) {
      const double decades = std::log10(static_cast<double>(r.cells) / size_results[i - 1].cells);
      if (decades > 0) growth = Fixed(std::pow(r.ms_per_query / size_results[i - 1].ms_per_query, 1 / decades), 2) + "x";
    }
    md << "| " << r.cells << " | " << Fixed(r.ms_per_query, 2) << " | " << growth << " | " << Fixed(r.candidates, 1)
       << " | " << Fixed(r.mean_error_m, 3) << " | " << (r.exhaustive_ms >= 0 ? Fixed(r.exhaustive_ms, 1) : "-") << " | "
       << (r.exhaustive_ms >= 0 ? Fixed(r.exhaustive_ms / r.ms_per_query, 1) + "x" : "-") << " | "
       << (r.exhaustive_ms >= 0 ? Fixed(r.exhaustive_error_m, 3) : "-") << " | " << Fixed(r.build_ms, 0) << " | "
       << Fixed(r.bytes_per_cell, 0) << " |\n";
  }
  const SizeResult* at1000 = nullptr;
  for (const auto& r : size_results) {
    if (r.cells == 1000) at1000 = &r;
  }
  md << "\nGoal: at most " << kGoalMsAt1000 << " ms per query at 1,000 cells: "
     << (at1000 ? (at1000->ms_per_query <= kGoalMsAt1000 ? "met" : "**missed**") + std::string(" (") +
                      Fixed(at1000->ms_per_query, 2) + " ms)"
                : std::string("not measured"))
     << ". Growth per 10x cells: the ms/query ratio per decade of size (sub-linear: below 10x).\n\n"
     << "Memory: a view as made takes " << Fixed(view_bytes / 1024, 1)
     << " KiB (PlaceView::bytes: landmarks and CV_32F descriptors, windows, lines, signature); a cell in the memory "
        "keeps SIFT descriptors as 8 bits; bytes/cell = PlaceCellMemory::bytes() / cells (cells, templates and the "
        "vocabulary index).\n\n"
     << "Memories: the first " << sizes.front() << " cells are real views at random positions in and around the grid of "
     << scene.name << " (random headings). Larger memories add synthetic cells: copy k of real cell b stands in a copy "
        "of the room k x " << kRoomPitchM << " m away (" << kRoomsPerRow << " rooms per row), position jittered by N(0, "
        "5 cm); each landmark kept with probability 0.9, its column moved by N(0, 1 px), each descriptor value by N(0, "
        "6) rounded and clamped to [0, 255]; lines, windows and signature are the real cell's. Every copy looks like its "
        "room (perceptual aliasing at its worst), so the vocabulary's votes spread over the copies and the cells "
        "nearest the prediction find the right room. Queries: " << query_views << " real views at other random "
        "positions of the first room, prediction = truth + N(0, " << prediction_sigma_m << " m) per axis. "
        "Exhaustive: the same Localize with every cell a candidate (exhaustive_below = cells).\n";
  std::cout << md.str();
  if (!out_dir.empty()) {
    fs::create_directories(out_dir);
    std::ofstream(fs::path(out_dir) / "bench.md") << md.str();
    results::Json j;
    j["scene"] = scene.name;
    j["runs"] = runs;
    j["queries_per_run"] = per_run;
    j["make_view_ms"] = results::Rounded(extract, 4);
    j["landmarks_per_view"] = results::Rounded(landmarks / total, 4);
    j["view_bytes"] = results::Rounded(view_bytes, 4);
    for (size_t i = 0; i < size_results.size(); ++i) {
      const auto& r = size_results[i];
      const std::string k = "cells_" + std::to_string(r.cells);
      j[k + "_ms_per_query"] = results::Rounded(r.ms_per_query, 4);
      j[k + "_candidates"] = results::Rounded(r.candidates, 4);
      j[k + "_mean_error_m"] = results::Rounded(r.mean_error_m, 4);
      j[k + "_index_build_ms"] = results::Rounded(r.build_ms, 4);
      j[k + "_bytes_per_cell"] = results::Rounded(r.bytes_per_cell, 4);
      if (r.exhaustive_ms >= 0) {
        j[k + "_exhaustive_ms_per_query"] = results::Rounded(r.exhaustive_ms, 4);
        j[k + "_exhaustive_over_indexed"] = results::Rounded(r.exhaustive_ms / r.ms_per_query, 4);
        j[k + "_exhaustive_mean_error_m"] = results::Rounded(r.exhaustive_error_m, 4);
      }
      if (i > 0) {
        const double decades = std::log10(static_cast<double>(r.cells) / size_results[i - 1].cells);
        if (decades > 0) {
          j["growth_per_10x_" + std::to_string(size_results[i - 1].cells) + "_to_" + std::to_string(r.cells)] =
              results::Rounded(std::pow(r.ms_per_query / size_results[i - 1].ms_per_query, 1 / decades), 4);
        }
      }
    }
    j["goal_ms_at_1000"] = results::Rounded(kGoalMsAt1000, 4);
    if (at1000) j["goal_met"] = at1000->ms_per_query <= kGoalMsAt1000;
    results::WriteJsonFile((fs::path(out_dir) / "bench.json").string(), j);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
