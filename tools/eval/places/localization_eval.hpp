#pragma once
// Place-cell localization evaluated the way the thesis does (5.1.3, 5.1.4, 5.2.2, fig. 5.9):
// memories explored in a simulated scene (the scene's grid database, a sparser manual route,
// random exploration at several novelty thresholds), 30 random test positions off the grid
// with random headings, and the position error of every distance measure, with and without
// the distance filter, nearest cell against the interpolated estimate.
//
// Views are made once per image (raw omni image rendered and unwrapped: the real pipeline) and
// shared by every memory and configuration, so measures and filters are compared on the same
// views.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "exploration.hpp"
#include "homing_eval.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::eval {

// The distance measures under test: "bearing-smallest", "bearing-ransac", "count", "vline".
struct MeasureVariant {
  std::string name;
  nav::PlaceMeasure measure = nav::PlaceMeasure::kBearingDifference;
  nav::MatchRefinement refinement = nav::MatchRefinement::kSmallestDistance;
};
std::optional<MeasureVariant> ParseMeasureVariant(const std::string& name);
const std::vector<std::string>& MeasureVariantNames();

// Errors of one set of estimates against the truth.
struct ErrorStats {
  double mean_m = 0, median_m = 0, max_m = 0;
  double mean_heading_deg = 0, max_heading_deg = 0;  // over answered queries
};
// position_errors: one per query; heading_errors_rad: NaN where there was no answer.
ErrorStats Summarize(const std::vector<double>& position_errors_m, const std::vector<double>& heading_errors_rad);

struct LocalizationEvalOptions {
  nav::sim::OmniCameraOptions camera;
  nav::sim::ImageEffectsOptions effects;
  nav::sim::DriveOptions drive;
  nav::PlaceViewOptions view;
  nav::VocabularyOptions vocabulary;
  // Base options of every query (measure, refinement, filter.enabled and estimate are set per
  // configuration); also the options of the exploration's novelty test (with `explore_measure`).
  nav::LocalizerOptions localizer;
  std::string explore_measure = "bearing-smallest";

  std::vector<std::string> memories = {"grid", "route", "random"};
  std::vector<std::string> measures = MeasureVariantNames();
  std::vector<bool> filters = {true, false};
  int tests = 30;
  double min_grid_distance_m = 0.03;    // test positions are at least this far from a grid position
  double prediction_sigma_m = 0.25;     // odometry prediction = truth + N(0, sigma^2) per axis
  double route_row_spacing_m = 0.6;     // manual route: serpentine rows
  double route_spacing_m = 0.4;         // manual route: a cell every this much travel
  RandomWalkOptions walk;
  std::vector<double> thresholds = {0.08, 0.05, 0.03};  // novelty thresholds, sparse to dense (measure units)
  bool odometry_poses = false;          // cell positions from the exploration's odometry, not the truth
  double people_dt_s = 2.0;             // grid and test views: the people walk this long between images
  uint64_t seed = 1;
  std::string save_test_panoramas_dir;  // non-empty: the test positions' panoramas as test_N.png there
  std::string mask = "none";            // self-occlusion mask of the raw images (homing_eval.hpp UseMask): none | calibrated | truth | FILE
  // The thesis' protocol beside ours (5.2.2 and the 169 locations of 4.4): every grid image (every
  // leave_one_out_stride-th) is a query against the grid memory with its own cell removed, so the
  // nearest cell is one grid spacing away. Needs the grid memory.
  bool leave_one_out = false;
  int leave_one_out_stride = 1;
  void Validate() const;                // throws std::invalid_argument
};

// One memory under test.
struct EvalMemory {
  std::string name;          // grid, route, random1 (sparsest) ...
  std::string description;
  double threshold = 0;      // random exploration: the novelty threshold (0 for grid and route)
  int explored_views = 0;    // views the exploration looked at
  double cells_per_m2 = 0;   // cells / the area
  double explore_seconds = 0;
  std::unique_ptr<nav::PlaceCellMemory> memory;
  std::vector<nav::Pose2> true_cell_poses;  // where each cell's view was really taken
  std::vector<std::vector<Eigen::Vector2d>> trajectories;  // exploration paths (true), per run
};

// One test position.
struct EvalTest {
  nav::Pose2 truth;
  Eigen::Vector2d predicted = Eigen::Vector2d::Zero();
  nav::PlaceView view;
};

// A configuration's outcome over the test positions.
struct ConfigResult {
  std::string memory, measure;
  bool filter = true;
  nav::PlaceEstimate estimate = nav::PlaceEstimate::kInterpolated;
  int cells = 0;
  double cells_per_m2 = 0;
  ErrorStats errors;
  double ms_per_query = 0;  // Localize() only (views are made beforehand)
  int failures = 0;         // no answer: the prediction's error is counted, the heading left out
  double mean_candidates = 0;
  std::vector<Eigen::Vector2d> estimates;  // per test position
  std::vector<double> position_errors_m;
  std::string Label() const;  // "grid bearing-smallest filter interpolated"
};

struct LocalizationEvalResult {
  std::string scene;
  Area area;
  std::vector<EvalMemory> memories;
  std::vector<EvalTest> tests;
  std::vector<ConfigResult> results;
  // The leave-one-out protocol (options.leave_one_out): memory "grid", one result per measure x
  // filter x estimate over leave_one_out_queries grid images.
  std::vector<ConfigResult> leave_one_out;
  std::vector<nav::Pose2> leave_one_out_queries;
  double leave_one_out_nearest_cell_m = 0;  // mean distance of a query to the nearest cell left in the memory
  double tests_nearest_cell_m = 0;          // ... of snapnav's test positions to the nearest grid cell
  int views_made = 0;
  double extract_ms_per_view = 0;   // MakePlaceView
  double render_ms_per_view = 0;    // render + unwrap
  double mean_landmarks = 0;
  double total_seconds = 0;
  // The default configuration (bearing-smallest, filter on, interpolated, grid) and the thesis'
  // (the same with the nearest cell); nullptr when not evaluated.
  const ConfigResult* Find(const std::string& memory, const std::string& measure, bool filter,
                           nav::PlaceEstimate estimate) const;
  const ConfigResult* FindLeaveOneOut(const std::string& measure, bool filter, nav::PlaceEstimate estimate) const;
};

// The thesis' leave-one-out protocol (5.2.2; the 169 locations of 4.4 on a 13x13 grid): each image
// of result's grid memory is a query against the grid memory without its own cell, for every
// measure x filter of options; the configurations go into result->leave_one_out. Throws
// std::invalid_argument when result has no grid memory. `say` gets progress lines (may be empty).
void AddLeaveOneOut(const LocalizationEvalOptions& options, const std::function<void(const std::string&, bool)>& say,
                    LocalizationEvalResult* result);

// Renders, explores, localizes. `progress` gets one line of text per step (and "\r" updates).
LocalizationEvalResult RunLocalizationEval(const nav::sim::Scene& scene, const LocalizationEvalOptions& options,
                                           const std::function<void(const std::string&, bool)>& progress = {});

// A lab's own image grid (grid_folder.hpp): its images (as panoramas of options.camera.panorama,
// with their mask) become the grid memory, and the leave-one-out protocol runs over them
// (options.measures x options.filters). No rendering: options.camera's optics and the scene
// options are not used.
LocalizationEvalResult RunGridFolderLocalization(const std::string& name, const std::vector<nav::Pose2>& poses,
                                                 const std::vector<cv::Mat>& panoramas, const cv::Mat& panorama_mask,
                                                 const LocalizationEvalOptions& options,
                                                 const std::function<void(const std::string&, bool)>& progress = {});
// Its report.md and summary.json (leave_one_out_* keys as WriteLocalizationOutputs).
void WriteGridFolderOutputs(const LocalizationEvalResult& result, const LocalizationEvalOptions& options,
                            const std::string& out_dir, const std::string& options_text);

// The target mean error of a scene (issue 6: indoor13 0.10 m, people11 0.15 m); nullopt for others.
std::optional<double> TargetMeanErrorM(const std::string& scene);

// report.md, results.csv, queries.csv, summary.json and the figures into `out_dir`. Returns the
// figure file names.
std::vector<std::string> WriteLocalizationOutputs(const LocalizationEvalResult& result,
                                                  const LocalizationEvalOptions& options, const std::string& out_dir,
                                                  const std::string& options_text);

// The evaluation settings (memories, measures, tests, exploration), for the start-up print and report.md.
std::string DescribeOptions(const LocalizationEvalOptions& options);

// Map of a memory's cells, the test positions and a configuration's estimates (a line from each
// truth to its estimate), with the exploration paths.
cv::Mat DrawLocalizationMap(const LocalizationEvalResult& result, const EvalMemory& memory,
                            const ConfigResult* config, const std::string& title);

}  // namespace snapnav::eval
