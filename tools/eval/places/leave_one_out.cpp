// The thesis' leave-one-out protocol (5.2.2): each grid image is a query against the grid memory
// without its own cell (a memory of the other cells, its vocabulary trained on them), so the nearest
// cell is one grid spacing away. The distance filter gets the truth + N(0, prediction_sigma^2) per
// axis as the snapnav protocol's queries.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "localization_eval.hpp"
#include "report_text.hpp"

namespace snapnav::eval {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

Eigen::Vector2d Xy(const nav::Pose2& p) { return {p.x_m, p.y_m}; }

}  // namespace

void AddLeaveOneOut(const LocalizationEvalOptions& options, const std::function<void(const std::string&, bool)>& say,
                    LocalizationEvalResult* result) {
  const EvalMemory* grid = nullptr;
  for (const auto& m : result->memories) {
    if (m.name == "grid") grid = &m;
  }
  if (!grid) throw std::invalid_argument("the leave-one-out protocol needs the grid memory");
  const auto& cells = grid->memory->cells();
  std::mt19937_64 rng(options.seed + 43);
  std::normal_distribution<double> noise(0.0, options.prediction_sigma_m);
  std::vector<int> queries;
  std::vector<Eigen::Vector2d> predicted;
  for (int q = 0; q < static_cast<int>(cells.size()); q += options.leave_one_out_stride) {
    queries.push_back(q);
    const double dx = options.prediction_sigma_m > 0 ? noise(rng) : 0.0;
    const double dy = options.prediction_sigma_m > 0 ? noise(rng) : 0.0;
    predicted.push_back(Xy(cells[q].pose) + Eigen::Vector2d(dx, dy));
    result->leave_one_out_queries.push_back(cells[q].pose);
  }
  struct Acc {
    ConfigResult nearest, interp;
    nav::LocalizerOptions lo;
    std::vector<double> heading_errors;
    double seconds = 0, candidates = 0;
  };
  std::vector<Acc> accs;
  for (const auto& measure_name : options.measures) {
    const auto variant = *ParseMeasureVariant(measure_name);
    for (bool filter : options.filters) {
      Acc a;
      a.lo = options.localizer;
      a.lo.measure.measure = variant.measure;
      a.lo.measure.refinement = variant.refinement;
      a.lo.filter.enabled = filter;
      a.lo.estimate = nav::PlaceEstimate::kInterpolated;
      for (auto* r : {&a.nearest, &a.interp}) {
        r->memory = "grid";
        r->measure = variant.name;
        r->filter = filter;
        r->cells = static_cast<int>(cells.size()) - 1;
        r->cells_per_m2 = r->cells / result->area.area_m2();
      }
      a.nearest.estimate = nav::PlaceEstimate::kNearestCell;
      a.interp.estimate = nav::PlaceEstimate::kInterpolated;
      accs.push_back(std::move(a));
    }
  }
  const auto t0 = Clock::now();
  for (size_t k = 0; k < queries.size(); ++k) {
    const int q = queries[k];
    nav::PlaceCellMemory memory(options.view, options.camera.panorama, options.vocabulary);
    for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
      if (i != q) memory.Add(cells[i].pose, cells[i].utime, cells[i].view);
    }
    memory.BuildIndex();
    const nav::Pose2& truth = cells[q].pose;
    for (auto& a : accs) {
      const std::optional<nav::Pose2> pred =
          a.lo.filter.enabled ? std::optional<nav::Pose2>(nav::Pose2{predicted[k].x(), predicted[k].y(), truth.theta_rad})
                              : std::nullopt;
      const auto tq = Clock::now();
      const auto loc = memory.Localize(cells[q].view, pred, a.lo);
      a.seconds += Seconds(tq);
      Eigen::Vector2d near_xy = predicted[k], interp_xy = predicted[k];
      double heading_error = kNaN;
      if (loc) {
        near_xy = Xy(memory.cell(loc->cell).pose);
        interp_xy = Xy(loc->pose);
        heading_error = nav::WrapAngle(loc->pose.theta_rad - truth.theta_rad);
        a.candidates += loc->candidates;
      } else {
        ++a.nearest.failures;
        ++a.interp.failures;
      }
      a.heading_errors.push_back(heading_error);
      a.nearest.estimates.push_back(near_xy);
      a.interp.estimates.push_back(interp_xy);
      a.nearest.position_errors_m.push_back((near_xy - Xy(truth)).norm());
      a.interp.position_errors_m.push_back((interp_xy - Xy(truth)).norm());
    }
    if (say && ((k + 1) % 10 == 0 || k + 1 == queries.size())) {
      say("leave-one-out queries " + std::to_string(k + 1) + "/" + std::to_string(queries.size()), k + 1 != queries.size());
    }
  }
  for (auto& a : accs) {
    const int answered = static_cast<int>(queries.size()) - a.interp.failures;
    for (auto* r : {&a.nearest, &a.interp}) {
      r->errors = Summarize(r->position_errors_m, a.heading_errors);
      r->ms_per_query = 1000 * a.seconds / queries.size();
      r->mean_candidates = answered ? a.candidates / answered : 0;
    }
    if (say) {
      say("leave-one-out " + a.interp.measure + (a.interp.filter ? " filter" : " no filter") + ": mean error " +
              Fixed(a.interp.errors.mean_m, 3) + " m interpolated, " + Fixed(a.nearest.errors.mean_m, 3) + " m nearest",
          false);
    }
    result->leave_one_out.push_back(std::move(a.nearest));
    result->leave_one_out.push_back(std::move(a.interp));
  }
  // How far each query is from the nearest cell it may find: the other grid cells; for snapnav's
  // test positions, every grid cell.
  auto nearest = [&](const Eigen::Vector2d& p, int skip) {
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
      if (i != skip) best = std::min(best, (Xy(cells[i].pose) - p).norm());
    }
    return best;
  };
  double sum = 0;
  for (int q : queries) sum += nearest(Xy(cells[q].pose), q);
  result->leave_one_out_nearest_cell_m = sum / queries.size();
  sum = 0;
  for (const auto& t : result->tests) sum += nearest(Xy(t.truth), -1);
  result->tests_nearest_cell_m = result->tests.empty() ? 0 : sum / result->tests.size();
  if (say) say("leave-one-out: " + std::to_string(queries.size()) + " queries in " + Fixed(Seconds(t0), 0) + " s", false);
}

}  // namespace snapnav::eval
