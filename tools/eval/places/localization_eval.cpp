#include "localization_eval.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "place_view_maker.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

Eigen::Vector2d Xy(const nav::Pose2& p) { return {p.x_m, p.y_m}; }

std::string EstimateName(nav::PlaceEstimate e) { return nav::PlaceEstimateName(e); }

// Key-safe form of a label: "bearing-smallest" -> "bearing_smallest".
std::string Key(std::string s) {
  for (char& c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return s;
}

}  // namespace

const std::vector<std::string>& MeasureVariantNames() {
  static const std::vector<std::string> names = {"bearing-smallest", "bearing-ransac", "count", "vline"};
  return names;
}

std::optional<MeasureVariant> ParseMeasureVariant(const std::string& name) {
  if (name == "bearing-smallest" || name == "bearing") {
    return MeasureVariant{"bearing-smallest", nav::PlaceMeasure::kBearingDifference, nav::MatchRefinement::kSmallestDistance};
  }
  if (name == "bearing-ransac") {
    return MeasureVariant{name, nav::PlaceMeasure::kBearingDifference, nav::MatchRefinement::kRansac};
  }
  if (name == "count") return MeasureVariant{name, nav::PlaceMeasure::kMatchCount, nav::MatchRefinement::kSmallestDistance};
  if (name == "vline") return MeasureVariant{name, nav::PlaceMeasure::kVlineTemplate, nav::MatchRefinement::kSmallestDistance};
  return std::nullopt;
}

ErrorStats Summarize(const std::vector<double>& position_errors_m, const std::vector<double>& heading_errors_rad) {
  ErrorStats s;
  if (!position_errors_m.empty()) {
    std::vector<double> e = position_errors_m;
    double sum = 0;
    for (double v : e) sum += v;
    s.mean_m = sum / e.size();
    std::sort(e.begin(), e.end());
    s.median_m = e.size() % 2 ? e[e.size() / 2] : (e[e.size() / 2 - 1] + e[e.size() / 2]) / 2;
    s.max_m = e.back();
  }
  double sum = 0;
  int n = 0;
  for (double h : heading_errors_rad) {
    if (std::isnan(h)) continue;
    sum += std::abs(h);
    s.max_heading_deg = std::max(s.max_heading_deg, std::abs(h) * 180 / M_PI);
    ++n;
  }
  s.mean_heading_deg = n ? sum / n * 180 / M_PI : kNaN;
  if (!n) s.max_heading_deg = kNaN;
  return s;
}

void LocalizationEvalOptions::Validate() const {
  camera.Validate();
  effects.Validate();
  drive.Validate();
  view.Validate();
  vocabulary.Validate();
  localizer.Validate();
  walk.Validate();
  if (!ParseMeasureVariant(explore_measure)) throw std::invalid_argument("explore_measure '" + explore_measure + "' is unknown");
  for (const auto& m : measures) {
    if (!ParseMeasureVariant(m)) throw std::invalid_argument("measure '" + m + "' is unknown (bearing-smallest, bearing-ransac, count, vline)");
  }
  for (const auto& m : memories) {
    if (m != "grid" && m != "route" && m != "random") throw std::invalid_argument("memory '" + m + "' is unknown (grid, route, random)");
  }
  if (memories.empty() || measures.empty() || filters.empty()) throw std::invalid_argument("memories, measures and filters must not be empty");
  if (tests < 1) throw std::invalid_argument("tests must be >= 1");
  if (!(prediction_sigma_m >= 0)) throw std::invalid_argument("prediction_sigma_m must be >= 0");
  if (!(route_row_spacing_m > 0) || !(route_spacing_m > 0)) throw std::invalid_argument("route spacings must be positive");
  if (std::find(memories.begin(), memories.end(), "random") != memories.end() && thresholds.empty()) {
    throw std::invalid_argument("random exploration needs at least one threshold");
  }
  for (double t : thresholds) {
    if (!(t > 0)) throw std::invalid_argument("thresholds must be positive");
  }
  if (!(people_dt_s > 0)) throw std::invalid_argument("people_dt_s must be positive");
  if (leave_one_out && std::find(memories.begin(), memories.end(), "grid") == memories.end()) {
    throw std::invalid_argument("the leave-one-out protocol needs the grid memory (memories: grid)");
  }
  if (leave_one_out_stride < 1) throw std::invalid_argument("leave_one_out_stride must be >= 1");
}

std::string ConfigResult::Label() const {
  return memory + " " + measure + (filter ? " filter " : " no-filter ") + EstimateName(estimate);
}

const ConfigResult* LocalizationEvalResult::Find(const std::string& memory, const std::string& measure, bool filter,
                                                 nav::PlaceEstimate estimate) const {
  for (const auto& r : results) {
    if (r.memory == memory && r.measure == measure && r.filter == filter && r.estimate == estimate) return &r;
  }
  return nullptr;
}

const ConfigResult* LocalizationEvalResult::FindLeaveOneOut(const std::string& measure, bool filter,
                                                            nav::PlaceEstimate estimate) const {
  for (const auto& r : leave_one_out) {
    if (r.measure == measure && r.filter == filter && r.estimate == estimate) return &r;
  }
  return nullptr;
}

std::optional<double> TargetMeanErrorM(const std::string& scene) {
  if (scene == "indoor13") return 0.10;
  if (scene == "people11") return 0.15;
  return std::nullopt;
}

std::string DescribeOptions(const LocalizationEvalOptions& o) {
  std::ostringstream s;
  s << "features " << nav::LandmarkMethodName(o.view.features.method) << ", interpolate_radius_m "
    << o.localizer.interpolate_radius_m << ", residual_cap_rad " << o.localizer.measure.residual_cap_rad << "\n"
    << "memories";
  for (const auto& m : o.memories) s << " " << m;
  s << "; measures";
  for (const auto& m : o.measures) s << " " << m;
  s << "; filters";
  for (bool b : o.filters) s << " " << (b ? "on" : "off");
  s << "\ntests " << o.tests << " (at least " << o.min_grid_distance_m << " m off the grid), prediction_sigma_m "
    << o.prediction_sigma_m << ", pose source " << (o.odometry_poses ? "odometry" : "truth") << ", seed " << o.seed
    << "\nroute: rows " << o.route_row_spacing_m << " m apart, a cell every " << o.route_spacing_m << " m\n"
    << "random walk: " << o.walk.runs << " runs x " << o.walk.steps << " steps of " << o.walk.step_m
    << " m, turn sigma " << o.walk.turn_sigma_rad << " rad, border margin " << o.walk.border_margin_m
    << " m; novelty measure " << o.explore_measure << ", thresholds";
  for (double t : o.thresholds) s << " " << t;
  s << "\ncamera " << (o.camera.optics.enabled ? "realistic" : "clean") << ", mask " << o.mask;
  s << "\nrobot: heading drift " << o.drive.heading_drift_deg_per_m << " deg/m, odometry noise "
    << o.drive.odometry_linear_noise_frac << " (distance), " << o.drive.odometry_angular_noise_frac << " (turn)\n";
  return s.str();
}

// ---------------------------------------------------------------------------------------------
LocalizationEvalResult RunLocalizationEval(const nav::sim::Scene& scene, const LocalizationEvalOptions& options,
                                           const std::function<void(const std::string&, bool)>& progress) {
  options.Validate();
  const auto t_start = Clock::now();
  auto say = [&](const std::string& text, bool transient = false) {
    if (progress) progress(text, transient);
  };
  auto counter = [&](const std::string& what, int done, int total) {
    if (done == total || done % 10 == 0) say(what + " " + std::to_string(done) + "/" + std::to_string(total), done != total);
  };
  auto wants = [&](const std::string& m) {
    return std::find(options.memories.begin(), options.memories.end(), m) != options.memories.end();
  };
  LocalizationEvalResult result;
  result.scene = scene.name;
  result.area = GridArea(scene.grid);
  const Area& area = result.area;
  PlaceViewMaker maker(scene, options.camera, options.effects, options.mask, options.view, options.seed);
  const nav::PanoramaModel& pm = options.camera.panorama;
  auto new_memory = [&]() { return std::make_unique<nav::PlaceCellMemory>(options.view, pm, options.vocabulary); };

  // Grid memory: the scene's image database (heading 0 everywhere, people walking between images).
  if (wants("grid")) {
    EvalMemory m;
    m.name = "grid";
    m.memory = new_memory();
    const auto t0 = Clock::now();
    Crowd crowd(scene, options.seed);
    const int total = scene.grid.nx * scene.grid.ny;
    for (int iy = 0; iy < scene.grid.ny; ++iy) {
      for (int ix = 0; ix < scene.grid.nx; ++ix) {
        const Eigen::Vector2d p = scene.grid.Position(ix, iy);
        const nav::Pose2 pose{p.x(), p.y(), 0.0};
        const auto people = crowd.Advance(options.people_dt_s, pose, options.drive.robot_radius_m);
        m.memory->Add(pose, static_cast<int64_t>(m.memory->size()) * 2'000'000, maker.Make(pose, people));
        m.true_cell_poses.push_back(pose);
        counter("grid views", m.memory->size(), total);
      }
    }
    m.explored_views = total;
    m.explore_seconds = Seconds(t0);
    m.description = "the scene's grid database, " + std::to_string(scene.grid.nx) + "x" + std::to_string(scene.grid.ny) +
                    " at " + Fixed(scene.grid.spacing_m * 100, 0) + " cm";
    result.memories.push_back(std::move(m));
  }
  // Manual route: a serpentine over the area, a cell every route_spacing_m.
  if (wants("route")) {
    EvalMemory m;
    m.name = "route";
    m.memory = new_memory();
    const auto t0 = Clock::now();
    const auto samples = DriveRoute(scene, ManualRouteWaypoints(area, options.route_row_spacing_m), options.drive,
                                    options.route_spacing_m, options.seed + 11);
    std::vector<Eigen::Vector2d> path;
    for (size_t i = 0; i < samples.size(); ++i) {
      const auto& s = samples[i];
      m.memory->Add(options.odometry_poses ? s.odometry : s.truth, s.utime, maker.Make(s.truth, s.people));
      m.true_cell_poses.push_back(s.truth);
      path.push_back(Xy(s.truth));
      counter("route views", static_cast<int>(i) + 1, static_cast<int>(samples.size()));
    }
    m.trajectories.push_back(path);
    m.explored_views = static_cast<int>(samples.size());
    m.explore_seconds = Seconds(t0);
    m.description = "manual route: serpentine, rows " + Fixed(options.route_row_spacing_m, 2) + " m apart, a cell every " +
                    Fixed(options.route_spacing_m, 2) + " m";
    result.memories.push_back(std::move(m));
  }
  // Random exploration (5.1.4): one walk, its views offered to ExploreStep at each threshold.
  if (wants("random")) {
    const auto t0 = Clock::now();
    const auto samples = RandomWalk(scene, area, options.drive, options.walk, options.seed + 23);
    std::vector<nav::PlaceView> views;
    views.reserve(samples.size());
    std::vector<std::vector<Eigen::Vector2d>> paths(options.walk.runs);
    for (size_t i = 0; i < samples.size(); ++i) {
      views.push_back(maker.Make(samples[i].truth, samples[i].people));
      paths[samples[i].run].push_back(Xy(samples[i].truth));
      counter("random walk views", static_cast<int>(i) + 1, static_cast<int>(samples.size()));
    }
    const double walk_seconds = Seconds(t0);
    std::vector<double> thresholds = options.thresholds;
    std::sort(thresholds.begin(), thresholds.end(), std::greater<double>());
    nav::LocalizerOptions explore = options.localizer;
    const auto variant = *ParseMeasureVariant(options.explore_measure);
    explore.measure.measure = variant.measure;
    explore.measure.refinement = variant.refinement;
    for (size_t k = 0; k < thresholds.size(); ++k) {
      EvalMemory m;
      m.name = "random" + std::to_string(k + 1);
      m.threshold = thresholds[k];
      m.memory = new_memory();
      m.trajectories = paths;
      const auto t1 = Clock::now();
      for (size_t i = 0; i < samples.size(); ++i) {
        const auto& s = samples[i];
        if (nav::ExploreStep(*m.memory, options.odometry_poses ? s.odometry : s.truth, s.utime, views[i], thresholds[k],
                             explore) >= 0) {
          m.true_cell_poses.push_back(s.truth);
        }
        counter(m.name + " exploration (threshold " + Fixed(thresholds[k], 3) + ", " + std::to_string(m.memory->size()) +
                    " cells)",
                static_cast<int>(i) + 1, static_cast<int>(samples.size()));
      }
      m.explored_views = static_cast<int>(samples.size());
      m.explore_seconds = Seconds(t1) + walk_seconds;
      m.description = "random exploration, " + std::to_string(options.walk.runs) + " runs x " +
                      std::to_string(options.walk.steps) + " steps of " + Fixed(options.walk.step_m * 100, 0) +
                      " cm, novelty threshold " + Fixed(thresholds[k], 3) + " (" + options.explore_measure + ")";
      result.memories.push_back(std::move(m));
    }
  }
  for (auto& m : result.memories) {
    m.cells_per_m2 = m.memory->size() / area.area_m2();
    const auto t0 = Clock::now();
    m.memory->BuildIndex();
    say("memory " + m.name + ": " + std::to_string(m.memory->size()) + " cells (" + Fixed(m.cells_per_m2, 1) +
        " per m^2), index built in " + Fixed(Seconds(t0) * 1000, 0) + " ms");
  }

  // Test positions: off the grid, random headings, people walking; the odometry prediction.
  {
    Crowd crowd(scene, options.seed + 31);
    std::mt19937_64 rng(options.seed + 37);
    std::normal_distribution<double> noise(0.0, options.prediction_sigma_m);
    const auto poses = RandomTestPoses(area, scene.grid, options.tests, options.min_grid_distance_m, options.seed + 41);
    for (size_t i = 0; i < poses.size(); ++i) {
      EvalTest t;
      t.truth = poses[i];
      const double dx = options.prediction_sigma_m > 0 ? noise(rng) : 0.0;
      const double dy = options.prediction_sigma_m > 0 ? noise(rng) : 0.0;
      t.predicted = Xy(t.truth) + Eigen::Vector2d(dx, dy);
      std::string png;
      if (!options.save_test_panoramas_dir.empty()) {
        fs::create_directories(options.save_test_panoramas_dir);
        png = (fs::path(options.save_test_panoramas_dir) / ("test_" + std::to_string(i) + ".png")).string();
      }
      t.view = maker.Make(t.truth, crowd.Advance(options.people_dt_s, t.truth, options.drive.robot_radius_m), png);
      result.tests.push_back(std::move(t));
      counter("test views", static_cast<int>(i) + 1, static_cast<int>(poses.size()));
    }
  }
  result.views_made = maker.views();
  result.extract_ms_per_view = maker.extract_ms();
  result.render_ms_per_view = maker.render_ms();
  result.mean_landmarks = maker.mean_landmarks();
  say("views: " + std::to_string(maker.views()) + " made, " + Fixed(maker.mean_landmarks(), 0) + " landmarks each, " +
      Fixed(maker.render_ms(), 1) + " ms render+unwrap, " + Fixed(maker.extract_ms(), 1) + " ms MakePlaceView");

  // Localization: every memory x measure x filter; nearest and interpolated from the same query
  // (the nearest-cell estimate is the best cell's position, which Localize also reports).
  const int total = static_cast<int>(result.memories.size() * options.measures.size() * options.filters.size());
  int done = 0;
  for (const auto& m : result.memories) {
    for (const auto& measure_name : options.measures) {
      const auto variant = *ParseMeasureVariant(measure_name);
      for (bool filter : options.filters) {
        nav::LocalizerOptions lo = options.localizer;
        lo.measure.measure = variant.measure;
        lo.measure.refinement = variant.refinement;
        lo.filter.enabled = filter;
        lo.estimate = nav::PlaceEstimate::kInterpolated;
        ConfigResult nearest, interp;
        for (auto* r : {&nearest, &interp}) {
          r->memory = m.name;
          r->measure = variant.name;
          r->filter = filter;
          r->cells = m.memory->size();
          r->cells_per_m2 = m.cells_per_m2;
        }
        nearest.estimate = nav::PlaceEstimate::kNearestCell;
        interp.estimate = nav::PlaceEstimate::kInterpolated;
        std::vector<double> heading_errors;
        double seconds = 0, candidates = 0;
        for (const auto& t : result.tests) {
          const std::optional<nav::Pose2> predicted =
              filter ? std::optional<nav::Pose2>(nav::Pose2{t.predicted.x(), t.predicted.y(), t.truth.theta_rad})
                     : std::nullopt;
          const auto t0 = Clock::now();
          const auto loc = m.memory->Localize(t.view, predicted, lo);
          seconds += Seconds(t0);
          Eigen::Vector2d near_xy = t.predicted, interp_xy = t.predicted;
          double heading_error = kNaN;
          if (loc) {
            near_xy = Xy(m.memory->cell(loc->cell).pose);
            interp_xy = Xy(loc->pose);
            heading_error = nav::WrapAngle(loc->pose.theta_rad - t.truth.theta_rad);
            candidates += loc->candidates;
          } else {
            ++nearest.failures;
            ++interp.failures;
          }
          heading_errors.push_back(heading_error);
          nearest.estimates.push_back(near_xy);
          interp.estimates.push_back(interp_xy);
          nearest.position_errors_m.push_back((near_xy - Xy(t.truth)).norm());
          interp.position_errors_m.push_back((interp_xy - Xy(t.truth)).norm());
        }
        const int answered = static_cast<int>(result.tests.size()) - interp.failures;
        for (auto* r : {&nearest, &interp}) {
          r->errors = Summarize(r->position_errors_m, heading_errors);
          r->ms_per_query = 1000 * seconds / result.tests.size();
          r->mean_candidates = answered ? candidates / answered : 0;
        }
        ++done;
        say("[" + std::to_string(done) + "/" + std::to_string(total) + "] " + m.name + " " + variant.name +
            (filter ? " filter" : " no filter") + ": mean error " + Fixed(interp.errors.mean_m, 3) + " m interpolated, " +
            Fixed(nearest.errors.mean_m, 3) + " m nearest, heading " + Fixed(interp.errors.mean_heading_deg, 1) +
            " deg, " + Fixed(interp.ms_per_query, 1) + " ms/query" +
            (interp.failures ? ", " + std::to_string(interp.failures) + " without an answer" : ""));
        result.results.push_back(std::move(nearest));
        result.results.push_back(std::move(interp));
      }
    }
  }
  if (options.leave_one_out) AddLeaveOneOut(options, say, &result);
  result.total_seconds = Seconds(t_start);
  return result;
}

LocalizationEvalResult RunGridFolderLocalization(const std::string& name, const std::vector<nav::Pose2>& poses,
                                                 const std::vector<cv::Mat>& panoramas, const cv::Mat& panorama_mask,
                                                 const LocalizationEvalOptions& options,
                                                 const std::function<void(const std::string&, bool)>& progress) {
  options.Validate();
  if (poses.size() != panoramas.size() || poses.size() < 2) {
    throw std::invalid_argument("grid folder localization: at least 2 images, one pose each");
  }
  const auto t_start = Clock::now();
  auto say = [&](const std::string& text, bool transient = false) {
    if (progress) progress(text, transient);
  };
  LocalizationEvalResult result;
  result.scene = name;
  result.area.min = result.area.max = Xy(poses.front());
  for (const auto& p : poses) {
    result.area.min = result.area.min.cwiseMin(Xy(p));
    result.area.max = result.area.max.cwiseMax(Xy(p));
  }
  EvalMemory m;
  m.name = "grid";
  m.description = "the grid folder " + name + ", " + std::to_string(poses.size()) + " images";
  m.memory = std::make_unique<nav::PlaceCellMemory>(options.view, options.camera.panorama, options.vocabulary);
  double extract_s = 0;
  int64_t landmarks = 0;
  const cv::Mat clearance = nav::MaskClearance(panorama_mask);
  for (size_t i = 0; i < poses.size(); ++i) {
    const auto t0 = Clock::now();
    nav::PlaceView v = nav::MakePlaceView(panoramas[i], options.view, panorama_mask, clearance);
    extract_s += Seconds(t0);
    landmarks += v.landmarks.size();
    m.memory->Add(poses[i], static_cast<int64_t>(i) * 2'000'000, std::move(v));
    m.true_cell_poses.push_back(poses[i]);
    if ((i + 1) % 10 == 0 || i + 1 == poses.size()) {
      say("views " + std::to_string(i + 1) + "/" + std::to_string(poses.size()), i + 1 != poses.size());
    }
  }
  m.explored_views = static_cast<int>(poses.size());
  m.cells_per_m2 = result.area.area_m2() > 0 ? m.memory->size() / result.area.area_m2() : 0;
  result.memories.push_back(std::move(m));
  result.views_made = static_cast<int>(poses.size());
  result.extract_ms_per_view = 1000 * extract_s / poses.size();
  result.mean_landmarks = static_cast<double>(landmarks) / poses.size();
  AddLeaveOneOut(options, say, &result);
  result.total_seconds = Seconds(t_start);
  return result;
}

// ---------------------------------------------------------------------------------------------
cv::Mat DrawLocalizationMap(const LocalizationEvalResult& result, const EvalMemory& memory, const ConfigResult* config,
                            const std::string& title) {
  const Area& a = result.area;
  double xmin = a.min.x() - 0.3, xmax = a.max.x() + 0.3, ymin = a.min.y() - 0.3, ymax = a.max.y() + 0.3;
  for (const auto& c : memory.memory->cells()) {
    xmin = std::min(xmin, c.pose.x_m - 0.1); xmax = std::max(xmax, c.pose.x_m + 0.1);
    ymin = std::min(ymin, c.pose.y_m - 0.1); ymax = std::max(ymax, c.pose.y_m + 0.1);
  }
  const int size = 760, top = 80, bottom = 40;
  const double scale = (size - 40) / std::max(xmax - xmin, ymax - ymin);
  cv::Mat img(top + size + bottom, size, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround(20 + (p.x() - xmin) * scale)),
                     static_cast<int>(std::lround(top + size - 20 - (p.y() - ymin) * scale)));
  };
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(img, title, {12, 24}, font, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, memory.description, {12, 46}, font, 0.45, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  if (config) {
    cv::putText(img,
                config->Label() + ": mean " + Fixed(config->errors.mean_m, 3) + " m, max " + Fixed(config->errors.max_m, 3) +
                    " m",
                {12, 68}, font, 0.45, cv::Scalar(40, 40, 200), 1, cv::LINE_AA);
  }
  cv::rectangle(img, px({a.min.x(), a.max.y()}), px({a.max.x(), a.min.y()}), cv::Scalar(210, 210, 210), 1);
  for (const auto& path : memory.trajectories) {
    for (size_t i = 1; i < path.size(); ++i) cv::line(img, px(path[i - 1]), px(path[i]), cv::Scalar(215, 215, 215), 1, cv::LINE_AA);
  }
  // Cells at their stored positions (blue), and where they were really taken when that differs.
  for (size_t i = 0; i < memory.memory->cells().size(); ++i) {
    const auto& c = memory.memory->cell(static_cast<int>(i));
    if (i < memory.true_cell_poses.size() && (Xy(memory.true_cell_poses[i]) - Xy(c.pose)).norm() > 0.01) {
      cv::line(img, px(Xy(memory.true_cell_poses[i])), px(Xy(c.pose)), cv::Scalar(230, 190, 150), 1, cv::LINE_AA);
    }
    cv::circle(img, px(Xy(c.pose)), 3, cv::Scalar(200, 110, 30), cv::FILLED, cv::LINE_AA);
  }
  for (size_t i = 0; i < result.tests.size(); ++i) {
    const cv::Point t = px(Xy(result.tests[i].truth));
    if (config && i < config->estimates.size()) {
      const cv::Point e = px(config->estimates[i]);
      cv::line(img, t, e, cv::Scalar(40, 40, 220), 2, cv::LINE_AA);
      cv::drawMarker(img, e, cv::Scalar(40, 40, 220), cv::MARKER_TILTED_CROSS, 9, 2, cv::LINE_AA);
    }
    cv::circle(img, t, 5, cv::Scalar(40, 150, 40), 2, cv::LINE_AA);
  }
  const int ly = top + size + 24;
  cv::circle(img, {24, ly - 5}, 3, cv::Scalar(200, 110, 30), cv::FILLED, cv::LINE_AA);
  cv::putText(img, "cells (" + std::to_string(memory.memory->size()) + ")", {32, ly}, font, 0.45, cv::Scalar(200, 110, 30), 1, cv::LINE_AA);
  cv::circle(img, {170, ly - 5}, 5, cv::Scalar(40, 150, 40), 2, cv::LINE_AA);
  cv::putText(img, "test positions", {180, ly}, font, 0.45, cv::Scalar(40, 150, 40), 1, cv::LINE_AA);
  cv::drawMarker(img, {310, ly - 5}, cv::Scalar(40, 40, 220), cv::MARKER_TILTED_CROSS, 9, 2, cv::LINE_AA);
  cv::putText(img, "estimates", {320, ly}, font, 0.45, cv::Scalar(40, 40, 220), 1, cv::LINE_AA);
  if (!memory.trajectories.empty()) {
    cv::line(img, {420, ly - 5}, {445, ly - 5}, cv::Scalar(200, 200, 200), 2);
    cv::putText(img, "exploration", {450, ly}, font, 0.45, cv::Scalar(150, 150, 150), 1, cv::LINE_AA);
  }
  const int bar = static_cast<int>(0.5 * scale);
  cv::line(img, {size - 30 - bar, ly - 4}, {size - 30, ly - 4}, cv::Scalar(0, 0, 0), 2);
  cv::putText(img, "0.5 m", {size - 30 - bar, ly - 10}, font, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return img;
}

namespace {

// Error against cell density (fig. 5.9) for one filter setting: a line per measure.
cv::Mat DensityChart(const LocalizationEvalResult& r, const LocalizationEvalOptions& o, bool filter) {
  std::vector<plot::Series> series;
  auto add = [&](const std::string& measure, nav::PlaceEstimate estimate) {
    plot::Series s{measure + (estimate == nav::PlaceEstimate::kNearestCell ? " (nearest cell)" : ""), {}, {}};
    std::vector<std::pair<double, double>> points;
    for (const auto& c : r.results) {
      if (c.measure == measure && c.filter == filter && c.estimate == estimate) points.push_back({c.cells_per_m2, c.errors.mean_m});
    }
    std::sort(points.begin(), points.end());
    for (const auto& [x, y] : points) {
      s.x.push_back(x);
      s.y.push_back(y);
    }
    if (!points.empty()) series.push_back(s);
  };
  for (const auto& m : o.measures) add(ParseMeasureVariant(m)->name, nav::PlaceEstimate::kInterpolated);
  add("bearing-smallest", nav::PlaceEstimate::kNearestCell);
  plot::Axes axes;
  axes.title = std::string(filter ? "(a) with" : "(b) without") + " distance filter (" + r.scene + ")";
  axes.x_label = "cells per m^2";
  axes.y_label = "mean localization error [m]";
  axes.y_from_zero = true;
  return plot::LineChart(axes, series, {700, 480});
}

std::string OnOff(bool b) { return b ? "on" : "off"; }

// A JSON number (null when not finite).
// As the report prints it: 4 digits after the point; null for NaN.
template <typename T>
results::Json Num(T v) {
  return results::Rounded(v, 4);
}

}  // namespace

std::vector<std::string> WriteLocalizationOutputs(const LocalizationEvalResult& r, const LocalizationEvalOptions& o,
                                                  const std::string& out_dir, const std::string& options_text) {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  std::vector<std::string> figures;
  auto save = [&](const cv::Mat& img, const std::string& name) {
    plot::SavePng(img, (out / name).string());
    figures.push_back(name);
  };
  // The default configuration: bearing-smallest (else the first measure), filter on (if evaluated),
  // interpolated, on the grid memory (else the first).
  std::string dm = ParseMeasureVariant(o.measures.front())->name;
  for (const auto& m : o.measures) {
    if (ParseMeasureVariant(m)->name == "bearing-smallest") dm = "bearing-smallest";
  }
  const bool df = std::find(o.filters.begin(), o.filters.end(), true) != o.filters.end();
  const std::string dmem = r.memories.empty() ? "" : (r.Find("grid", dm, df, nav::PlaceEstimate::kInterpolated) ? "grid" : r.memories.front().name);
  const ConfigResult* def = r.Find(dmem, dm, df, nav::PlaceEstimate::kInterpolated);
  const ConfigResult* thesis = r.Find(dmem, dm, df, nav::PlaceEstimate::kNearestCell);
  const auto target = TargetMeanErrorM(r.scene);

  // Figures: error against density (fig. 5.9), maps of each memory with the default configuration.
  {
    std::vector<cv::Mat> panels;
    for (bool f : o.filters) panels.push_back(DensityChart(r, o, f));
    cv::Mat all;
    cv::hconcat(panels, all);
    save(all, "error_vs_density.png");
  }
  for (const auto& m : r.memories) {
    const ConfigResult* c = r.Find(m.name, dm, df, nav::PlaceEstimate::kInterpolated);
    save(DrawLocalizationMap(r, m, c, r.scene + " " + m.name + ": " + std::to_string(m.memory->size()) + " cells"),
         "map_" + m.name + ".png");
  }

  // results.csv and queries.csv.
  {
    std::ofstream csv(out / "results.csv");
    csv << "scene,memory,cells,cells_per_m2,threshold,measure,filter,estimate,mean_error_m,median_error_m,max_error_m,"
           "mean_heading_error_deg,max_heading_error_deg,ms_per_query,failures,mean_candidates\n";
    for (const auto& c : r.results) {
      double threshold = 0;
      for (const auto& m : r.memories) {
        if (m.name == c.memory) threshold = m.threshold;
      }
      csv << r.scene << "," << c.memory << "," << c.cells << "," << Fixed(c.cells_per_m2, 3) << "," << threshold << ","
          << c.measure << "," << OnOff(c.filter) << "," << EstimateName(c.estimate) << "," << Fixed(c.errors.mean_m, 4)
          << "," << Fixed(c.errors.median_m, 4) << "," << Fixed(c.errors.max_m, 4) << ","
          << Fixed(c.errors.mean_heading_deg, 2) << "," << Fixed(c.errors.max_heading_deg, 2) << ","
          << Fixed(c.ms_per_query, 2) << "," << c.failures << "," << Fixed(c.mean_candidates, 1) << "\n";
    }
    std::ofstream q(out / "queries.csv");
    q << "memory,measure,filter,estimate,test,true_x_m,true_y_m,true_theta_rad,predicted_x_m,predicted_y_m,estimate_x_m,"
         "estimate_y_m,error_m\n";
    for (const auto& c : r.results) {
      for (size_t i = 0; i < r.tests.size() && i < c.estimates.size(); ++i) {
        const auto& t = r.tests[i];
        q << c.memory << "," << c.measure << "," << OnOff(c.filter) << "," << EstimateName(c.estimate) << "," << i << ","
          << Fixed(t.truth.x_m, 4) << "," << Fixed(t.truth.y_m, 4) << "," << Fixed(t.truth.theta_rad, 4) << ","
          << Fixed(t.predicted.x(), 4) << "," << Fixed(t.predicted.y(), 4) << "," << Fixed(c.estimates[i].x(), 4) << ","
          << Fixed(c.estimates[i].y(), 4) << "," << Fixed(c.position_errors_m[i], 4) << "\n";
      }
    }
  }

  // report.md.
  std::ostringstream md;
  md << "# Place-cell localization: " << r.scene << "\n\n"
     << "Thesis 5.1.4, 5.2.2, fig. 5.9. " << r.tests.size() << " test positions at random off-grid positions of the "
     << Fixed(r.area.max.x() - r.area.min.x(), 2) << " x " << Fixed(r.area.max.y() - r.area.min.y(), 2)
     << " m grid area, random headings" << (r.scene == "people11" ? ", people walking" : "")
     << "; odometry prediction = truth + N(0, " << o.prediction_sigma_m << " m) per axis (used by the distance filter "
     << "only; without the filter no prediction is given, so the candidates come from the vocabulary alone).\n"
     << "Views: raw omni images rendered and unwrapped, " << r.views_made << " views, " << Fixed(r.mean_landmarks, 0)
     << " landmarks each; render + unwrap " << Fixed(r.render_ms_per_view, 1) << " ms, MakePlaceView "
     << Fixed(r.extract_ms_per_view, 1) << " ms per view (not in ms/query). Run time " << Fixed(r.total_seconds, 0)
     << " s.\n\n";
  if (def) {
    md << "## Result\n\n| configuration | mean error [m] | median | max | heading error [deg] | ms/query | target |\n"
       << "|---|---|---|---|---|---|---|\n"
       << "| **default**: " << def->Label() << " | **" << Fixed(def->errors.mean_m, 3) << "** | "
       << Fixed(def->errors.median_m, 3) << " | " << Fixed(def->errors.max_m, 3) << " | "
       << Fixed(def->errors.mean_heading_deg, 1) << " | " << Fixed(def->ms_per_query, 1) << " | "
       << (target ? "<= " + Fixed(*target, 2) + " m: " + (def->errors.mean_m <= *target ? "met" : "**missed**") : "-")
       << " |\n";
    if (thesis) {
      md << "| thesis (nearest cell): " << thesis->Label() << " | " << Fixed(thesis->errors.mean_m, 3) << " | "
         << Fixed(thesis->errors.median_m, 3) << " | " << Fixed(thesis->errors.max_m, 3) << " | "
         << Fixed(thesis->errors.mean_heading_deg, 1) << " | " << Fixed(thesis->ms_per_query, 1) << " | |\n";
    }
    md << "| thesis' own figure (5.2.2, SIFT count measure, nearest cell) | 0.196 | | | | | |\n\n";
  }
  if (!r.leave_one_out.empty()) {
    // The protocols side by side: the same grid memory, the same views, the same configurations.
    const ConfigResult* ldef = r.FindLeaveOneOut(dm, df, nav::PlaceEstimate::kInterpolated);
    const ConfigResult* lnear = r.FindLeaveOneOut(dm, df, nav::PlaceEstimate::kNearestCell);
    const ConfigResult* gdef = r.Find("grid", dm, df, nav::PlaceEstimate::kInterpolated);
    const ConfigResult* gnear = r.Find("grid", dm, df, nav::PlaceEstimate::kNearestCell);
    md << "## Protocols (thesis 5.2.2 and 4.4 beside ours)\n\n"
       << "Grid memory, " << dm << (df ? ", filter on" : ", no filter") << ". snapnav: random off-grid test positions, "
       << "the whole grid kept; leave-one-out (thesis 5.2.2, and on a 13x13 grid the 169 locations of 4.4): every "
       << (o.leave_one_out_stride > 1 ? std::to_string(o.leave_one_out_stride) + "th " : "")
       << "grid image a query, its own cell removed from the memory (vocabulary trained without it).\n\n"
       << "| protocol | queries | mean distance to the nearest cell [m] | interpolated: mean error [m] | max | "
          "nearest cell: mean error [m] | max |\n|---|---|---|---|---|---|---|\n";
    auto row = [&](const std::string& name, size_t n, double nearest_m, const ConfigResult* a, const ConfigResult* b) {
      md << "| " << name << " | " << n << " | " << Fixed(nearest_m, 3) << " | " << (a ? Fixed(a->errors.mean_m, 3) : "-")
         << " | " << (a ? Fixed(a->errors.max_m, 3) : "-") << " | " << (b ? Fixed(b->errors.mean_m, 3) : "-") << " | "
         << (b ? Fixed(b->errors.max_m, 3) : "-") << " |\n";
    };
    row("snapnav", r.tests.size(), r.tests_nearest_cell_m, gdef, gnear);
    row("leave-one-out", r.leave_one_out_queries.size(), r.leave_one_out_nearest_cell_m, ldef, lnear);
    md << "| thesis' own figure (5.2.2, SIFT count measure, nearest cell) | | | | | 0.196 | |\n\n"
       << "Leave-one-out, every measure:\n\n| measure | filter | estimate | mean [m] | median | max | heading mean [deg] | "
          "ms/query | n/a |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : r.leave_one_out) {
      md << "| " << c.measure << " | " << OnOff(c.filter) << " | " << EstimateName(c.estimate) << " | "
         << Fixed(c.errors.mean_m, 3) << " | " << Fixed(c.errors.median_m, 3) << " | " << Fixed(c.errors.max_m, 3) << " | "
         << Fixed(c.errors.mean_heading_deg, 1) << " | " << Fixed(c.ms_per_query, 1) << " | " << c.failures << " |\n";
    }
    md << "\n";
  }
  md << "## Memories\n\n| memory | how | cells | cells/m^2 | views explored | bytes/cell | exploration [s] |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const auto& m : r.memories) {
    md << "| " << m.name << " | " << m.description << " | " << m.memory->size() << " | " << Fixed(m.cells_per_m2, 1)
       << " | " << m.explored_views << " | "
       << (m.memory->size() ? std::to_string(m.memory->bytes() / m.memory->size()) : std::string("-")) << " | "
       << Fixed(m.explore_seconds, 1) << " |\n";
  }
  md << "\nCell positions from the " << (o.odometry_poses ? "exploration's odometry" : "ground truth")
     << " (the grid database always has its true positions).\n\n";
  // Fig. 5.9 table: mean error by memory x measure, per filter and estimate.
  for (bool f : o.filters) {
    for (auto e : {nav::PlaceEstimate::kInterpolated, nav::PlaceEstimate::kNearestCell}) {
      md << "## Mean error [m], filter " << OnOff(f) << ", " << EstimateName(e) << "\n\n| memory | cells/m^2 |";
      for (const auto& m : o.measures) md << " " << ParseMeasureVariant(m)->name << " |";
      md << "\n|---|---|";
      for (size_t i = 0; i < o.measures.size(); ++i) md << "---|";
      md << "\n";
      for (const auto& mem : r.memories) {
        md << "| " << mem.name << " | " << Fixed(mem.cells_per_m2, 1) << " |";
        for (const auto& m : o.measures) {
          const ConfigResult* c = r.Find(mem.name, ParseMeasureVariant(m)->name, f, e);
          md << " " << (c ? Fixed(c->errors.mean_m, 3) + (c->failures ? " (" + std::to_string(c->failures) + " n/a)" : "") : "-")
             << " |";
        }
        md << "\n";
      }
      md << "\n";
    }
  }
  md << "## Every configuration\n\nNo answer: the prediction's error is counted and the heading left out (n/a).\n\n"
     << "| memory | measure | filter | estimate | mean [m] | median | max | heading mean [deg] | heading max | ms/query | "
        "candidates | n/a |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : r.results) {
    md << "| " << c.memory << " | " << c.measure << " | " << OnOff(c.filter) << " | " << EstimateName(c.estimate) << " | "
       << Fixed(c.errors.mean_m, 3) << " | " << Fixed(c.errors.median_m, 3) << " | " << Fixed(c.errors.max_m, 3) << " | "
       << Fixed(c.errors.mean_heading_deg, 1) << " | " << Fixed(c.errors.max_heading_deg, 1) << " | "
       << Fixed(c.ms_per_query, 1) << " | " << Fixed(c.mean_candidates, 1) << " | " << c.failures << " |\n";
  }
  md << "\n## Options\n\n```\n" << options_text << "```\n\n## Figures\n\n";
  for (const auto& f : figures) md << "![" << f << "](" << f << ")\n";
  std::ofstream(out / "report.md") << md.str();

  // summary.json: flat keys.
  results::Json j;
  j["scene"] = r.scene;
  j["test_positions"] = r.tests.size();
  j["prediction_sigma_m"] = Num(o.prediction_sigma_m);
  j["pose_source"] = o.odometry_poses ? "odometry" : "truth";
  j["seed"] = o.seed;
  if (def) {
    j["default_configuration"] = def->Label();
    j["mean_localization_error_m"] = Num(def->errors.mean_m);
    j["median_localization_error_m"] = Num(def->errors.median_m);
    j["max_localization_error_m"] = Num(def->errors.max_m);
    j["mean_heading_error_deg"] = Num(def->errors.mean_heading_deg);
    j["ms_per_query"] = Num(def->ms_per_query);
    j["queries_without_answer"] = Num(def->failures);
  }
  if (thesis) {
    j["thesis_configuration"] = thesis->Label();
    j["thesis_configuration_mean_localization_error_m"] = Num(thesis->errors.mean_m);
    j["thesis_configuration_max_localization_error_m"] = Num(thesis->errors.max_m);
  }
  j["thesis_reported_mean_localization_error_m"] = 0.1957;
  if (target) {
    j["target_mean_localization_error_m"] = Num(*target);
    j["target_met"] = def && def->errors.mean_m <= *target;
  }
  j["views"] = Num(r.views_made);
  j["mean_landmarks_per_view"] = Num(r.mean_landmarks);
  j["render_ms_per_view"] = Num(r.render_ms_per_view);
  j["make_view_ms_per_view"] = Num(r.extract_ms_per_view);
  j["total_seconds"] = Num(r.total_seconds);
  for (const auto& m : r.memories) {
    j[m.name + "_cells"] = m.memory->size();
    j[m.name + "_cells_per_m2"] = Num(m.cells_per_m2);
    j[m.name + "_bytes_per_cell"] = m.memory->size() ? m.memory->bytes() / m.memory->size() : 0;
    if (m.threshold > 0) j[m.name + "_threshold"] = Num(m.threshold);
  }
  for (const auto& c : r.results) {
    const std::string k = c.memory + "_" + Key(c.measure) + (c.filter ? "_filter_" : "_nofilter_") + EstimateName(c.estimate);
    j[k + "_mean_error_m"] = Num(c.errors.mean_m);
    j[k + "_max_error_m"] = Num(c.errors.max_m);
    j[k + "_mean_heading_error_deg"] = Num(c.errors.mean_heading_deg);
    j[k + "_ms_per_query"] = Num(c.ms_per_query);
    j[k + "_failures"] = Num(c.failures);
  }
  if (!r.leave_one_out.empty()) {
    j["protocols"] = {"snapnav", "leave-one-out"};
    j["snapnav_mean_nearest_cell_distance_m"] = Num(r.tests_nearest_cell_m);
    j["leave_one_out_queries"] = r.leave_one_out_queries.size();
    j["leave_one_out_mean_nearest_cell_distance_m"] = Num(r.leave_one_out_nearest_cell_m);
    if (const auto* c = r.FindLeaveOneOut(dm, df, nav::PlaceEstimate::kInterpolated)) {
      j["leave_one_out_mean_localization_error_m"] = Num(c->errors.mean_m);
      j["leave_one_out_max_localization_error_m"] = Num(c->errors.max_m);
    }
    if (const auto* c = r.FindLeaveOneOut(dm, df, nav::PlaceEstimate::kNearestCell)) {
      j["leave_one_out_thesis_configuration_mean_localization_error_m"] = Num(c->errors.mean_m);
    }
    for (const auto& c : r.leave_one_out) {
      const std::string k = "leave_one_out_" + Key(c.measure) + (c.filter ? "_filter_" : "_nofilter_") + EstimateName(c.estimate);
      j[k + "_mean_error_m"] = Num(c.errors.mean_m);
      j[k + "_max_error_m"] = Num(c.errors.max_m);
      j[k + "_failures"] = Num(c.failures);
    }
  }
  j["figures"] = figures;
  results::WriteJsonFile((out / "summary.json").string(), j);
  return figures;
}

void WriteGridFolderOutputs(const LocalizationEvalResult& r, const LocalizationEvalOptions& o, const std::string& out_dir,
                            const std::string& options_text) {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  const ConfigResult* def = r.FindLeaveOneOut("bearing-smallest", true, nav::PlaceEstimate::kInterpolated);
  const ConfigResult* near = r.FindLeaveOneOut("bearing-smallest", true, nav::PlaceEstimate::kNearestCell);
  std::ostringstream md;
  md << "# Place-cell localization: grid folder " << r.scene << "\n\n"
     << "Leave-one-out (thesis 5.2.2): each of " << r.leave_one_out_queries.size() << " images a query against the "
     << "others (its own removed; mean distance to the nearest other image " << Fixed(r.leave_one_out_nearest_cell_m, 3)
     << " m). " << r.views_made << " views, " << Fixed(r.mean_landmarks, 0) << " landmarks each, MakePlaceView "
     << Fixed(r.extract_ms_per_view, 1) << " ms per view. Run time " << Fixed(r.total_seconds, 0) << " s.\n\n"
     << "| measure | filter | estimate | mean [m] | median | max | heading mean [deg] | ms/query | n/a |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : r.leave_one_out) {
    md << "| " << c.measure << " | " << OnOff(c.filter) << " | " << EstimateName(c.estimate) << " | "
       << Fixed(c.errors.mean_m, 3) << " | " << Fixed(c.errors.median_m, 3) << " | " << Fixed(c.errors.max_m, 3) << " | "
       << Fixed(c.errors.mean_heading_deg, 1) << " | " << Fixed(c.ms_per_query, 1) << " | " << c.failures << " |\n";
  }
  md << "| thesis' own figure (5.2.2, SIFT count measure, nearest cell) | | | 0.196 | | | | | |\n\n## Options\n\n```\n"
     << options_text << "```\n";
  std::ofstream(out / "report.md") << md.str();
  results::Json j;
  j["grid"] = r.scene;
  j["images"] = Num(r.views_made);
  j["protocols"] = {"leave-one-out"};
  j["leave_one_out_queries"] = r.leave_one_out_queries.size();
  j["leave_one_out_mean_nearest_cell_distance_m"] = Num(r.leave_one_out_nearest_cell_m);
  j["prediction_sigma_m"] = Num(o.prediction_sigma_m);
  j["seed"] = o.seed;
  if (def) {
    j["leave_one_out_mean_localization_error_m"] = Num(def->errors.mean_m);
    j["leave_one_out_max_localization_error_m"] = Num(def->errors.max_m);
  }
  if (near) j["leave_one_out_thesis_configuration_mean_localization_error_m"] = Num(near->errors.mean_m);
  for (const auto& c : r.leave_one_out) {
    const std::string k = "leave_one_out_" + Key(c.measure) + (c.filter ? "_filter_" : "_nofilter_") + EstimateName(c.estimate);
    j[k + "_mean_error_m"] = Num(c.errors.mean_m);
    j[k + "_max_error_m"] = Num(c.errors.max_m);
    j[k + "_failures"] = Num(c.failures);
  }
  j["thesis_reported_mean_localization_error_m"] = 0.1957;
  results::WriteJsonFile((out / "summary.json").string(), j);
}

}  // namespace snapnav::eval
