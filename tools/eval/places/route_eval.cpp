#include "route_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "homing_eval.hpp"
#include "place_view_maker.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "timing.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;

Eigen::Vector2d Xy(const nav::Pose2& p) { return {p.x_m, p.y_m}; }

void Say(const std::function<void(const std::string&, bool)>& progress, const std::string& text, bool replace = false) {
  if (progress) progress(text, replace);
}

double RouteLength(const std::vector<Eigen::Vector2d>& w) {
  double l = 0;
  for (size_t i = 1; i < w.size(); ++i) l += (w[i] - w[i - 1]).norm();
  return l;
}

// What the closed loop needs from the place cells (nullptr members: the odometry-only baseline).
struct Perception {
  const nav::PlaceCellMemory* memory = nullptr;
  PlaceViewMaker* maker = nullptr;
  std::vector<int> waypoint_cell;                           // per waypoint: its cell (-1: none close)
  std::vector<std::unique_ptr<nav::LandmarkHomer>> homers;  // per waypoint (null without a cell)
};

// The scene's people walk in a World of their own (its robot parked outside the room), so they
// never block the robot: the simulator's people stop for the robot and the robot is blocked by
// them, which deadlocks a robot without obstacle avoidance (the thesis' had none either). A
// person closer to the camera than its radius plus kPersonClearanceM is not drawn (it steps aside).
constexpr double kPersonClearanceM = 0.15;
class Crowd {
 public:
  Crowd(const nav::sim::Scene& scene, const nav::sim::DriveOptions& drive, uint64_t seed)
      : world_(scene, drive, nav::sim::LaserOptions{}, seed), active_(scene.people.count > 0) {
    world_.SetTruePose({-100, -100, 0});
  }
  void Advance(double dt_s) {
    if (active_ && dt_s > 0) world_.Step(0, 0, dt_s);
  }
  std::vector<nav::sim::Cylinder> Around(const nav::Pose2& robot) const {
    std::vector<nav::sim::Cylinder> visible;
    for (const auto& p : world_.people()) {
      if ((p.center - Xy(robot)).norm() > p.radius_m + kPersonClearanceM) visible.push_back(p);
    }
    return visible;
  }

 private:
  nav::sim::World world_;
  bool active_;
};

RouteRun RunClosedLoop(const nav::sim::Scene& scene, const RouteEvalOptions& o, const nav::Route& route,
                       const Perception& perception, const std::string& name,
                       const std::function<void(const std::string&, bool)>& progress) {
  RouteRun run;
  run.name = name;
  const bool places = perception.memory != nullptr;
  nav::sim::Scene empty = scene;  // the robot's world: the scene without its people
  empty.people.count = 0;
  nav::sim::World world(empty, o.drive, nav::sim::LaserOptions{}, o.seed + 17);
  Crowd crowd(scene, o.drive, o.seed + 29);
  const nav::Pose2 start{route.waypoints[0].x(), route.waypoints[0].y(), o.start_heading_rad};
  world.SetTruePose(start);
  nav::PoseTracker tracker(o.tracker);
  tracker.Initialize(0, start);
  nav::RouteFollower follower(o.follower);
  follower.SetRoute(route, 1);  // the robot stands on waypoint 0 (the thesis' start)
  nav::Pose2 odometry = start;

  const int physics_per_control = static_cast<int>(std::lround(o.physics_rate_hz / o.control_rate_hz));
  const double dt = 1.0 / o.physics_rate_hz;
  const double max_time_s = o.max_time_s > 0
                                ? o.max_time_s
                                : o.laps * (2.0 * RouteLength(route.waypoints) / o.follower.max_linear_mps + 120.0);
  nav::DriveCommand command;
  double sum_tracking = 0, step_ms = 0;
  int localization_due = 0;
  double next_report_s = 0;
  while (world.time_s() < max_time_s) {
    const auto t_step = Clock::now();
    const int64_t utime = static_cast<int64_t>(std::llround(world.time_s() * 1e6));
    const nav::sim::OdometryReading odo = world.TakeOdometry();
    tracker.AddOdometry(utime, odo.delta);
    odometry = odometry.Compose(odo.delta);
    const nav::Pose2 truth = world.true_pose();

    std::optional<nav::PlaceView> view;
    auto ensure_view = [&]() -> const nav::PlaceView& {
      if (!view) {
        view = perception.maker->Make(truth, crowd.Around(truth), "", &run.ms_render, &run.ms_view);
        ++run.views;
      }
      return *view;
    };
    if (places && localization_due == 0) {
      const nav::PlaceView& v = ensure_view();
      const auto t0 = Clock::now();
      const auto loc = perception.memory->Localize(v, tracker.pose(), o.localizer);
      ++run.localizations;
      if (loc) {
        const nav::FixOutcome outcome = tracker.AddFix(utime, loc->pose, loc->covariance);
        run.fixes.push_back(Xy(loc->pose));
        run.fix_accepted.push_back(outcome == nav::FixOutcome::kAccepted || outcome == nav::FixOutcome::kReset ||
                                   outcome == nav::FixOutcome::kInitialized);
      } else {
        ++run.no_answer;
      }
      run.ms_localize += MsSince(t0);
    }
    if (places) localization_due = (localization_due + 1) % o.localize_every;

    // Final approach: homing towards the waypoint's snapshot.
    const int wp = follower.waypoint();
    if (places && o.use_homing && follower.state() != nav::FollowState::kFinished && wp >= 0 && perception.homers[wp] &&
        o.follower.homing_radius_m > 0 &&
        (route.waypoints[wp] - Xy(tracker.pose())).norm() < o.follower.homing_radius_m) {
      const nav::PlaceView& v = ensure_view();
      const auto t0 = Clock::now();
      ++run.homing_calls;
      const auto h = perception.homers[wp]->Home(v.landmarks);
      const auto c = perception.memory->Compare(v, {perception.waypoint_cell[wp]}, o.localizer.measure);
      const bool seen = !c.empty() && c.front().seen;
      if (h) {
        ++run.homing_estimates;
        nav::HomingInput in;
        in.utime = utime;
        in.direction_rad = h->estimate.direction_rad;
        in.arrived = o.homing_arrived_rad > 0 && seen && c.front().distance < o.homing_arrived_rad;
        follower.SetHoming(in);
      }
      run.ms_homing += MsSince(t0);
      HomingSample hs;
      const Eigen::Vector2d to = route.waypoints[wp] - Xy(truth);
      hs.true_distance_m = to.norm();
      hs.true_direction_rad = nav::WrapAngle(std::atan2(to.y(), to.x()) - truth.theta_rad);
      hs.estimate = h.has_value();
      hs.direction_rad = h ? h->estimate.direction_rad : 0;
      hs.error_rad = h ? std::abs(nav::WrapAngle(hs.direction_rad - hs.true_direction_rad)) : M_PI;
      hs.bearing_distance_rad = seen ? c.front().distance : -1;
      hs.matches = h ? h->matches : 0;
      run.homing.push_back(hs);
    }

    const int laps_before = follower.laps();
    const nav::FollowStep step = follower.Update(utime, tracker.pose());
    if (step.homing_used) ++run.homing_steps;
    if (step.homing_refused) ++run.homing_refused;
    if (step.arrival != nav::ArrivalReason::kNone) {
      WaypointArrival a;
      a.lap = laps_before + 1;
      a.waypoint = step.arrived_waypoint;
      a.time_s = world.time_s();
      a.truth = Xy(truth);
      a.estimate = Xy(tracker.pose());
      a.odometry = Xy(odometry);
      a.error_m = (a.truth - route.waypoints[a.waypoint]).norm();
      a.estimate_error_m = (a.estimate - a.truth).norm();
      a.reason = nav::ArrivalReasonName(step.arrival);
      run.arrivals.push_back(a);
      Say(progress, name + ": lap " + std::to_string(a.lap) + " waypoint " + std::to_string(a.waypoint) +
                        " at t=" + Fixed(a.time_s, 1) + " s: error " + Fixed(a.error_m * 100, 1) +
                        " cm (tracked estimate off by " + Fixed(a.estimate_error_m * 100, 1) + " cm, odometry " +
                        Fixed((a.odometry - a.truth).norm() * 100, 1) + " cm; by " + a.reason + ")");
    }
    command = step.command;
    run.truth.push_back(truth);
    run.estimate.push_back(tracker.pose());
    run.odometry.push_back(odometry);
    const double tracking = (Xy(tracker.pose()) - Xy(truth)).norm();
    sum_tracking += tracking;
    run.tracking_error_max_m = std::max(run.tracking_error_max_m, tracking);
    ++run.control_steps;
    if (follower.state() == nav::FollowState::kFinished) {
      run.finished = true;
      step_ms += MsSince(t_step);
      break;
    }
    for (int i = 0; i < physics_per_control; ++i) world.Step(command.linear_mps, command.angular_radps, dt);
    crowd.Advance(physics_per_control * dt);
    step_ms += MsSince(t_step);
    if (world.time_s() >= next_report_s) {
      Say(progress,
          name + ": t=" + Fixed(world.time_s(), 0) + " s, lap " + std::to_string(follower.laps() + 1) + "/" +
              std::to_string(o.laps) + ", waypoint " + std::to_string(follower.waypoint()) + ", " +
              nav::FollowStateName(follower.state()) + ", tracked estimate off by " + Fixed(tracking * 100, 1) +
              " cm, " + Fixed(step_ms / run.control_steps, 1) + " ms/step",
          true);
      next_report_s += 5;
    }
  }
  run.laps_completed = follower.laps();
  run.sim_time_s = world.time_s();
  run.distance_m = world.distance_m();
  run.collisions = world.collisions();
  run.fixes_accepted = tracker.fixes_accepted();
  run.fixes_rejected = tracker.fixes_rejected();
  run.resets = tracker.resets();
  run.tracking_error_mean_m = run.control_steps ? sum_tracking / run.control_steps : 0;
  run.odometry_error_final_m = run.truth.empty() ? 0 : (Xy(run.odometry.back()) - Xy(run.truth.back())).norm();
  run.ms_per_step = run.control_steps ? step_ms / run.control_steps : 0;
  auto per = [](double total, int n) { return n > 0 ? total / n : 0.0; };
  run.ms_render = per(run.ms_render, run.views);
  run.ms_view = per(run.ms_view, run.views);
  run.ms_localize = per(run.ms_localize, run.localizations);
  run.ms_homing = per(run.ms_homing, run.homing_calls);
  Say(progress, name + ": " + std::to_string(run.laps_completed) + " laps, " + std::to_string(run.arrivals.size()) +
                    " waypoints in " + Fixed(run.sim_time_s, 0) + " s simulated, " + Fixed(run.ms_per_step, 1) +
                    " ms per control step" + (run.finished ? "" : " (time limit reached)"));
  return run;
}

// As the report prints it: 6 significant digits; null for NaN.
results::Json Json(double v) { return results::Significant(v); }

struct HomingBin {
  double lo_m, hi_m;
  int samples = 0, estimates = 0, seen = 0;
  double error_deg = 0, bearing_distance_rad = 0;
};
// The homing samples by true distance to the waypoint: mean direction error and bearing distance.
std::vector<HomingBin> HomingBins(const std::vector<HomingSample>& samples) {
  std::vector<HomingBin> bins = {{0, 0.05}, {0.05, 0.10}, {0.10, 0.20}, {0.20, 1e9}};
  for (const auto& h : samples) {
    for (auto& b : bins) {
      if (h.true_distance_m < b.lo_m || h.true_distance_m >= b.hi_m) continue;
      ++b.samples;
      if (h.estimate) {
        ++b.estimates;
        b.error_deg += h.error_rad * 180 / M_PI;
      }
      if (h.bearing_distance_rad >= 0) {
        ++b.seen;
        b.bearing_distance_rad += h.bearing_distance_rad;
      }
    }
  }
  for (auto& b : bins) {
    if (b.estimates) b.error_deg /= b.estimates;
    if (b.seen) b.bearing_distance_rad /= b.seen;
  }
  return bins;
}

double MeanHomingErrorDeg(const std::vector<HomingSample>& samples) {
  double sum = 0;
  int n = 0;
  for (const auto& h : samples) {
    if (!h.estimate) continue;
    sum += h.error_rad * 180 / M_PI;
    ++n;
  }
  return n ? sum / n : std::nan("");
}

}  // namespace

void RouteEvalOptions::Validate() const {
  view.Validate();
  localizer.Validate();
  vocabulary.Validate();
  homing.Validate();
  tracker.Validate();
  follower.Validate();
  drive.Validate();
  if (route != 1 && route != 2) throw std::invalid_argument("route must be 1 or 2");
  if (laps < 1) throw std::invalid_argument("laps must be >= 1");
  if (!(tolerance_m > 0)) throw std::invalid_argument("tolerance_m must be positive");
  if (cell_step < 1) throw std::invalid_argument("cell_step must be >= 1");
  if (!(homing_arrived_rad >= 0)) throw std::invalid_argument("homing_arrived_rad must be >= 0");
  if (!(physics_rate_hz > 0) || !(control_rate_hz > 0) || control_rate_hz > physics_rate_hz) {
    throw std::invalid_argument("rates must be positive, the control rate at most the physics rate");
  }
  const double ratio = physics_rate_hz / control_rate_hz;
  if (std::abs(ratio - std::round(ratio)) > 1e-9) {
    throw std::invalid_argument("the control rate must divide the physics rate");
  }
  if (localize_every < 1) throw std::invalid_argument("localize_every must be >= 1");
  if (!(people_dt_s > 0)) throw std::invalid_argument("people_dt_s must be positive");
  if (!(max_time_s >= 0)) throw std::invalid_argument("max_time_s must be >= 0");
}

void RouteSquare(const nav::sim::GridSpec& grid, Eigen::Vector2d* origin, double* size_m) {
  if (grid.nx < 2 || grid.ny < 2) throw std::invalid_argument("the scene's grid needs at least 2 x 2 positions");
  *origin = {grid.origin_x_m, grid.origin_y_m};
  *size_m = std::min(grid.nx - 1, grid.ny - 1) * grid.spacing_m;
}

ArrivalSummary SummarizeArrivals(const std::vector<WaypointArrival>& arrivals) {
  ArrivalSummary s;
  s.arrivals = static_cast<int>(arrivals.size());
  if (arrivals.empty()) return s;
  std::vector<double> e;
  for (const auto& a : arrivals) e.push_back(a.error_m);
  s.mean_m = std::accumulate(e.begin(), e.end(), 0.0) / e.size();
  s.max_m = *std::max_element(e.begin(), e.end());
  std::vector<double> sorted = e;
  std::sort(sorted.begin(), sorted.end());
  s.median_m =
      sorted.size() % 2 ? sorted[sorted.size() / 2] : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]);
  int max_lap = 0;
  for (const auto& a : arrivals) max_lap = std::max(max_lap, a.lap);
  for (int lap = 1; lap <= max_lap; ++lap) {
    LapErrors l;
    l.lap = lap;
    for (const auto& a : arrivals) {
      if (a.lap != lap) continue;
      ++l.arrivals;
      l.mean_m += a.error_m;
      l.max_m = std::max(l.max_m, a.error_m);
    }
    if (l.arrivals > 0) {
      l.mean_m /= l.arrivals;
      s.laps.push_back(l);
    }
  }
  // Least-squares slope of error over the lap number.
  double mx = 0, my = 0;
  for (const auto& a : arrivals) {
    mx += a.lap;
    my += a.error_m;
  }
  mx /= arrivals.size();
  my /= arrivals.size();
  double sxy = 0, sxx = 0;
  for (const auto& a : arrivals) {
    sxy += (a.lap - mx) * (a.error_m - my);
    sxx += (a.lap - mx) * (a.lap - mx);
  }
  s.growth_m_per_lap = sxx > 0 ? sxy / sxx : 0;
  if (!s.laps.empty()) s.last_minus_first_lap_m = s.laps.back().mean_m - s.laps.front().mean_m;
  return s;
}

RouteEvalResult RunRouteEval(const nav::sim::Scene& scene, const RouteEvalOptions& o,
                             const std::function<void(const std::string&, bool)>& progress) {
  o.Validate();
  RouteEvalResult r;
  r.scene = scene.name;
  r.route = o.route;
  RouteSquare(scene.grid, &r.origin, &r.size_m);
  r.waypoints = nav::ThesisRoute(o.route, r.origin, r.size_m);
  r.waypoints_per_lap = static_cast<int>(r.waypoints.size()) - 1;  // closed: a lap is waypoints 1..n-1
  nav::Route route;
  route.name = "thesis" + std::to_string(o.route);
  route.waypoints = r.waypoints;
  route.loop = true;
  route.laps = o.laps;
  route.tolerance_m = o.tolerance_m;

  // Exploration: the grid (heading 0, like the thesis' databases) and the waypoints.
  PlaceViewMaker maker(scene, o.camera, nav::sim::ImageEffectsOptions{}, o.mask, o.view, o.seed);
  nav::PlaceCellMemory memory(o.view, maker.panorama(), o.vocabulary);
  Crowd crowd(scene, o.drive, o.seed + 5);
  std::vector<nav::Pose2> poses;
  const auto& g = scene.grid;
  for (int iy = 0; iy < g.ny; iy += o.cell_step) {
    for (int ix = 0; ix < g.nx; ix += o.cell_step) {
      const Eigen::Vector2d p = g.Position(ix, iy);
      poses.push_back({p.x(), p.y(), 0});
    }
  }
  if (o.waypoint_cells) {
    for (const auto& w : r.waypoints) {
      bool known = false;
      for (const auto& p : poses) known = known || (Xy(p) - w).norm() < 0.01;
      if (!known) poses.push_back({w.x(), w.y(), 0});
    }
  }
  const auto t_explore = Clock::now();
  double landmarks = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    for (int k = 0; k < static_cast<int>(std::lround(o.people_dt_s * 10)); ++k) crowd.Advance(0.1);
    nav::PlaceView v = maker.Make(poses[i], crowd.Around(poses[i]));
    landmarks += v.landmarks.size();
    memory.Add(poses[i], static_cast<int64_t>(i) * 2'000'000, std::move(v));
    Say(progress, "exploring: cell " + std::to_string(i + 1) + "/" + std::to_string(poses.size()), true);
  }
  memory.BuildIndex();
  r.explore_seconds = std::chrono::duration<double>(Clock::now() - t_explore).count();
  r.mean_landmarks = poses.empty() ? 0 : landmarks / poses.size();
  r.cells = poses;
  Say(progress, "exploring: " + std::to_string(memory.size()) + " cells (" + Fixed(r.mean_landmarks, 0) +
                    " landmarks each) in " + Fixed(r.explore_seconds, 1) + " s");

  Perception perception;
  perception.memory = &memory;
  perception.maker = &maker;
  for (const auto& w : r.waypoints) {
    int best = -1;
    double best_d = 0.02;  // a cell this close is the waypoint's snapshot
    for (int c = 0; c < memory.size(); ++c) {
      const double d = (Xy(memory.cell(c).pose) - w).norm();
      if (d < best_d) {
        best_d = d;
        best = c;
      }
    }
    perception.waypoint_cell.push_back(best);
    if (best >= 0) {
      perception.homers.push_back(std::make_unique<nav::LandmarkHomer>(o.homing, maker.panorama()));
      // The memory keeps SIFT descriptors compacted to CV_8U; matching wants CV_32F.
      nav::LandmarkSet home = memory.cell(best).view.landmarks;
      if (!home.descriptors.empty() && home.descriptors.type() != CV_32F) {
        cv::Mat f;
        home.descriptors.convertTo(f, CV_32F);
        home.descriptors = f;
      }
      perception.homers.back()->SetHome(std::move(home));
    } else {
      perception.homers.push_back(nullptr);
    }
  }

  r.run = RunClosedLoop(scene, o, route, perception, "place cells", progress);
  r.baseline = RunClosedLoop(scene, o, route, Perception{}, "odometry only", progress);
  r.summary = SummarizeArrivals(r.run.arrivals);
  r.baseline_summary = SummarizeArrivals(r.baseline.arrivals);
  return r;
}

// ------------------------------------------------------------------------------------ figures
cv::Mat DrawRouteMap(const RouteEvalResult& r, const std::string& title) {
  constexpr int kSize = 900, kTop = 40, kMargin = 30, kLegend = 260;
  // Bounds: the route square, the cells and the true and tracked paths (odometry may wander off:
  // it is clipped by the image).
  Eigen::Vector2d lo = r.origin, hi = r.origin + Eigen::Vector2d(r.size_m, r.size_m);
  auto grow = [&](const Eigen::Vector2d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  };
  for (const auto& c : r.cells) grow(Xy(c));
  for (const auto& p : r.run.truth) grow(Xy(p));
  for (const auto& p : r.run.estimate) grow(Xy(p));
  lo -= Eigen::Vector2d(0.3, 0.3);
  hi += Eigen::Vector2d(0.3, 0.3);
  const double scale = (kSize - 2 * kMargin) / std::max(hi.x() - lo.x(), hi.y() - lo.y());
  cv::Mat img(kSize + kTop, kSize + kLegend, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround(kMargin + (p.x() - lo.x()) * scale)),
                     static_cast<int>(std::lround(kTop + kSize - kMargin - (p.y() - lo.y()) * scale)));
  };
  cv::putText(img, title, {10, 26}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 0}, 1, cv::LINE_AA);
  for (const auto& c : r.cells) cv::circle(img, px(Xy(c)), 2, {190, 190, 190}, cv::FILLED, cv::LINE_AA);
  auto polyline = [&](const std::vector<nav::Pose2>& path, const cv::Scalar& colour, int thickness) {
    for (size_t i = 1; i < path.size(); ++i)
      cv::line(img, px(Xy(path[i - 1])), px(Xy(path[i])), colour, thickness, cv::LINE_AA);
  };
  const cv::Scalar truth_c(40, 40, 40), odo_c(60, 60, 220), est_c(200, 110, 30), fix_c(60, 170, 60), rej_c(0, 140, 255),
      wp_c(0, 120, 230), base_c(180, 120, 200);
  polyline(r.baseline.truth, base_c, 1);
  polyline(r.run.odometry, odo_c, 1);
  polyline(r.run.estimate, est_c, 1);
  polyline(r.run.truth, truth_c, 2);
  for (size_t i = 0; i < r.run.fixes.size(); ++i) {
    const bool ok = r.run.fix_accepted[i];
    if (ok) {
      cv::circle(img, px(r.run.fixes[i]), 2, fix_c, cv::FILLED, cv::LINE_AA);
    } else {
      cv::drawMarker(img, px(r.run.fixes[i]), rej_c, cv::MARKER_CROSS, 7, 1, cv::LINE_AA);
    }
  }
  for (size_t i = 0; i < r.waypoints.size(); ++i) {
    const cv::Point c = px(r.waypoints[i]);
    cv::circle(img, c, static_cast<int>(std::lround(kTargetWaypointErrorM * scale)), wp_c, 1, cv::LINE_AA);
    cv::circle(img, c, 4, wp_c, cv::FILLED, cv::LINE_AA);
    if (i + 1 < r.waypoints.size()) {
      cv::putText(img, std::to_string(i), c + cv::Point(8, -8), cv::FONT_HERSHEY_SIMPLEX, 0.5, wp_c, 1, cv::LINE_AA);
    }
  }
  for (const auto& a : r.run.arrivals)
    cv::drawMarker(img, px(a.truth), {0, 0, 0}, cv::MARKER_TILTED_CROSS, 8, 1, cv::LINE_AA);
  // Legend (right of the map) and scale bar.
  const std::vector<std::pair<std::string, cv::Scalar>> legend = {{"ground truth", truth_c},
                                                                  {"tracked estimate", est_c},
                                                                  {"odometry (dead reckoning)", odo_c},
                                                                  {"place-cell fix (accepted)", fix_c},
                                                                  {"place-cell fix (rejected)", rej_c},
                                                                  {"odometry-only run (truth)", base_c},
                                                                  {"waypoint, 15 cm circle", wp_c},
                                                                  {"arrival (truth)", {0, 0, 0}}};
  int y = kTop + 20;
  for (const auto& [name, colour] : legend) {
    cv::line(img, {kSize, y - 4}, {kSize + 25, y - 4}, colour, 2, cv::LINE_AA);
    cv::putText(img, name, {kSize + 32, y}, cv::FONT_HERSHEY_SIMPLEX, 0.42, {0, 0, 0}, 1, cv::LINE_AA);
    y += 18;
  }
  const int bar = static_cast<int>(std::lround(0.5 * scale));
  cv::line(img, {kMargin, kTop + kSize - 12}, {kMargin + bar, kTop + kSize - 12}, {0, 0, 0}, 2);
  cv::putText(img, "0.5 m", {kMargin + bar + 6, kTop + kSize - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1,
              cv::LINE_AA);
  return img;
}

void WriteRouteOutputs(const RouteEvalResult& r, const RouteEvalOptions& o, const std::string& out_dir,
                       const std::string& options_text) {
  const fs::path out(out_dir);
  fs::create_directories(out);
  const ArrivalSummary& s = r.summary;
  const ArrivalSummary& b = r.baseline_summary;
  const bool meets_error = s.arrivals > 0 && s.max_m <= kTargetWaypointErrorM;
  const bool no_growth = s.laps.size() < 2 || s.last_minus_first_lap_m <= 0.03;
  const bool all_laps = r.run.laps_completed >= o.laps;

  plot::SavePng(DrawRouteMap(r, r.scene + ", thesis route " + std::to_string(r.route) + ", " +
                                    std::to_string(r.run.laps_completed) + " laps: waypoint error mean " +
                                    Fixed(s.mean_m * 100, 1) + " cm, max " + Fixed(s.max_m * 100, 1) + " cm"),
                (out / "trajectory.png").string());
  {
    plot::Axes axes;
    axes.title = "Waypoint error at each arrival (" + r.scene + ", route " + std::to_string(r.route) + ")";
    axes.x_label = "arrival (laps of " + std::to_string(r.waypoints_per_lap) + " waypoints)";
    axes.y_label = "true distance to the waypoint [m]";
    axes.y_from_zero = true;
    plot::Series pc{"place cells + odometry + homing", {}, {}}, dr{"odometry only", {}, {}},
        target{"target 0.15 m", {}, {}};
    for (size_t i = 0; i < r.run.arrivals.size(); ++i) {
      pc.x.push_back(static_cast<double>(i + 1));
      pc.y.push_back(r.run.arrivals[i].error_m);
    }
    for (size_t i = 0; i < r.baseline.arrivals.size(); ++i) {
      dr.x.push_back(static_cast<double>(i + 1));
      dr.y.push_back(r.baseline.arrivals[i].error_m);
    }
    const double n = static_cast<double>(std::max(r.run.arrivals.size(), r.baseline.arrivals.size()));
    target.x = {1, std::max(2.0, n)};
    target.y = {kTargetWaypointErrorM, kTargetWaypointErrorM};
    plot::SavePng(plot::LineChart(axes, {pc, dr, target}), (out / "waypoint_errors.png").string());
  }
  {
    std::ofstream csv(out / "arrivals.csv");
    csv << "run,lap,waypoint,time_s,true_x_m,true_y_m,waypoint_x_m,waypoint_y_m,error_m,estimate_error_m,"
           "odometry_error_m,reason\n";
    for (const RouteRun* run : {&r.run, &r.baseline}) {
      for (const auto& a : run->arrivals) {
        csv << (run == &r.run ? "place_cells" : "odometry_only") << "," << a.lap << "," << a.waypoint << "," << a.time_s
            << "," << a.truth.x() << "," << a.truth.y() << "," << r.waypoints[a.waypoint].x() << ","
            << r.waypoints[a.waypoint].y() << "," << a.error_m << "," << a.estimate_error_m << ","
            << (a.odometry - a.truth).norm() << "," << a.reason << "\n";
      }
    }
  }
  {
    std::ofstream csv(out / "homing.csv");
    csv << "true_distance_m,true_direction_rad,estimate,direction_rad,error_rad,bearing_distance_rad,matches\n";
    for (const auto& h : r.run.homing) {
      csv << h.true_distance_m << "," << h.true_direction_rad << "," << (h.estimate ? 1 : 0) << "," << h.direction_rad
          << "," << h.error_rad << "," << h.bearing_distance_rad << "," << h.matches << "\n";
    }
  }
  {
    results::Json j;
    j["scene"] = r.scene;
    j["route"] = r.route;
    j["seed"] = o.seed;
    j["route_square_size_m"] = Json(r.size_m);
    j["waypoints_per_lap"] = r.waypoints_per_lap;
    j["laps_requested"] = o.laps;
    j["laps_completed"] = r.run.laps_completed;
    j["arrivals"] = s.arrivals;
    j["tolerance_m"] = Json(o.tolerance_m);
    j["waypoint_error_mean_m"] = Json(s.mean_m);
    j["waypoint_error_median_m"] = Json(s.median_m);
    j["waypoint_error_max_m"] = Json(s.max_m);
    for (const auto& l : s.laps) {
      j["lap" + std::to_string(l.lap) + "_waypoint_error_mean_m"] = Json(l.mean_m);
      j["lap" + std::to_string(l.lap) + "_waypoint_error_max_m"] = Json(l.max_m);
    }
    j["error_growth_m_per_lap"] = Json(s.growth_m_per_lap);
    j["last_minus_first_lap_mean_m"] = Json(s.last_minus_first_lap_m);
    j["tracking_error_mean_m"] = Json(r.run.tracking_error_mean_m);
    j["tracking_error_max_m"] = Json(r.run.tracking_error_max_m);
    j["odometry_drift_final_m"] = Json(r.run.odometry_error_final_m);
    j["dead_reckoning_laps_completed"] = r.baseline.laps_completed;
    j["dead_reckoning_waypoint_error_mean_m"] = Json(b.mean_m);
    j["dead_reckoning_waypoint_error_max_m"] = Json(b.max_m);
    for (const auto& l : b.laps) j["dead_reckoning_lap" + std::to_string(l.lap) + "_waypoint_error_mean_m"] = Json(l.mean_m);
    j["dead_reckoning_error_growth_m_per_lap"] = Json(b.growth_m_per_lap);
    j["cells"] = r.cells.size();
    j["mean_landmarks_per_view"] = Json(r.mean_landmarks);
    j["localizations"] = r.run.localizations;
    j["localizations_without_answer"] = r.run.no_answer;
    j["fixes_accepted"] = r.run.fixes_accepted;
    j["fixes_rejected"] = r.run.fixes_rejected;
    j["tracker_resets"] = r.run.resets;
    j["homing_calls"] = r.run.homing_calls;
    j["homing_estimates"] = r.run.homing_estimates;
    j["homing_steps"] = r.run.homing_steps;
    j["homing_refused_steps"] = r.run.homing_refused;
    j["homing_direction_error_mean_deg"] = Json(MeanHomingErrorDeg(r.run.homing));
    j["control_steps"] = r.run.control_steps;
    j["sim_time_s"] = Json(r.run.sim_time_s);
    j["distance_m"] = Json(r.run.distance_m);
    j["collisions"] = r.run.collisions;
    j["ms_per_step"] = Json(r.run.ms_per_step);
    j["ms_render_per_view"] = Json(r.run.ms_render);
    j["ms_place_view_per_view"] = Json(r.run.ms_view);
    j["ms_per_localization"] = Json(r.run.ms_localize);
    j["ms_per_homing"] = Json(r.run.ms_homing);
    j["explore_seconds"] = Json(r.explore_seconds);
    j["target_waypoint_error_m"] = Json(kTargetWaypointErrorM);
    j["meets_waypoint_error_target"] = meets_error;
    j["meets_no_growth_target"] = no_growth;
    j["completed_all_laps"] = all_laps;
    results::WriteJsonFile((out / "summary.json").string(), j);
  }
  {
    std::ofstream md(out / "report.md");
    md << "# Route following: " << r.scene << ", thesis route " << r.route << " (figure 5.5 "
       << (r.route == 1 ? "left" : "right") << ")\n\n"
       << "The robot starts on waypoint 0 and follows the route for " << o.laps << " laps (a lap: waypoints 1.."
       << r.waypoints_per_lap << "; the figure's 100 units = " << Fixed(r.size_m, 2)
       << " m here, 3.5 m in the thesis). It localizes with " << r.cells.size() << " place cells (grid every "
       << o.cell_step << " position(s)" << (o.waypoint_cells ? " and the waypoints" : "")
       << "), drives by odometry between fixes and arrives "
       << (o.use_homing ? "with landmark homing towards the waypoint's snapshot" : "by the tracked position")
       << ". People (scenes with people) walk through the views but do not block the robot"
       << ". Control error: heading drift " << o.drive.heading_drift_deg_per_m << " deg/m (thesis 5.3.1); seed "
       << o.seed << ".\n\n"
       << "## Targets (issue 6)\n\n| target | measured | met |\n|---|---|---|\n"
       << "| every waypoint within 15 cm | max " << Fixed(s.max_m * 100, 1) << " cm, mean " << Fixed(s.mean_m * 100, 1)
       << " cm | " << (meets_error ? "yes" : "**no**") << " |\n"
       << "| no growth of the error over the laps | last lap mean - first lap mean "
       << Fixed(s.last_minus_first_lap_m * 100, 1) << " cm, slope " << Fixed(s.growth_m_per_lap * 100, 2)
       << " cm/lap | " << (no_growth ? "yes" : "**no**") << " |\n"
       << "| all laps | " << r.run.laps_completed << "/" << o.laps << " | " << (all_laps ? "yes" : "**no**") << " |\n\n"
       << "## Waypoint error per lap\n\n| lap | place cells: mean [cm] | max [cm] | odometry only: mean [cm] | max "
          "[cm] |\n"
       << "|---|---|---|---|---|\n";
    const size_t nl = std::max(s.laps.size(), b.laps.size());
    for (size_t i = 0; i < nl; ++i) {
      md << "| " << i + 1 << " | " << (i < s.laps.size() ? Fixed(s.laps[i].mean_m * 100, 1) : "-") << " | "
         << (i < s.laps.size() ? Fixed(s.laps[i].max_m * 100, 1) : "-") << " | "
         << (i < b.laps.size() ? Fixed(b.laps[i].mean_m * 100, 1) : "-") << " | "
         << (i < b.laps.size() ? Fixed(b.laps[i].max_m * 100, 1) : "-") << " |\n";
    }
    md << "| all | " << Fixed(s.mean_m * 100, 1) << " | " << Fixed(s.max_m * 100, 1) << " | "
       << Fixed(b.mean_m * 100, 1) << " | " << Fixed(b.max_m * 100, 1) << " |\n\n"
       << "Growth (least-squares slope over the lap number): place cells " << Fixed(s.growth_m_per_lap * 100, 2)
       << " cm/lap, odometry only " << Fixed(b.growth_m_per_lap * 100, 2) << " cm/lap.\n\n"
       << "![trajectory](trajectory.png)\n\n![waypoint errors](waypoint_errors.png)\n\n"
       << "## Arrivals (place cells)\n\n| lap | waypoint | t [s] | error [cm] | tracked estimate off by [cm] | "
          "odometry off by [cm] | by |\n"
       << "|---|---|---|---|---|---|---|\n";
    for (const auto& a : r.run.arrivals) {
      md << "| " << a.lap << " | " << a.waypoint << " | " << Fixed(a.time_s, 1) << " | " << Fixed(a.error_m * 100, 1)
         << " | " << Fixed(a.estimate_error_m * 100, 1) << " | " << Fixed((a.odometry - a.truth).norm() * 100, 1)
         << " | " << a.reason << " |\n";
    }
    md << "\n## Run\n\n"
       << "- simulated " << Fixed(r.run.sim_time_s, 0) << " s, " << Fixed(r.run.distance_m, 1) << " m driven, "
       << r.run.collisions << " blocked physics steps, " << r.run.control_steps << " control steps at "
       << o.control_rate_hz << " Hz\n"
       << "- localizations " << r.run.localizations << " (every " << o.localize_every << " step(s)), without answer "
       << r.run.no_answer << "; fixes accepted " << r.run.fixes_accepted << ", rejected by the gate "
       << r.run.fixes_rejected << ", tracker resets " << r.run.resets << "\n"
       << "- tracked estimate against the truth over all steps: mean " << Fixed(r.run.tracking_error_mean_m * 100, 1)
       << " cm, max " << Fixed(r.run.tracking_error_max_m * 100, 1) << " cm; odometry alone ends "
       << Fixed(r.run.odometry_error_final_m * 100, 1) << " cm off\n"
       << "- homing: " << r.run.homing_calls << " calls, " << r.run.homing_estimates << " estimates, "
       << r.run.homing_steps << " steps steered by it, " << r.run.homing_refused
       << " steps where its direction deviated too far from the tracked one\n"
       << "- wall time: " << Fixed(r.run.ms_per_step, 1) << " ms per control step (render + unwrap "
       << Fixed(r.run.ms_render, 1) << " ms, MakePlaceView " << Fixed(r.run.ms_view, 1) << " ms, Localize "
       << Fixed(r.run.ms_localize, 1) << " ms, homing " << Fixed(r.run.ms_homing, 1) << " ms per call); exploration "
       << Fixed(r.explore_seconds, 1) << " s for " << r.cells.size() << " cells (" << Fixed(r.mean_landmarks, 0)
       << " landmarks per view)\n\n"
       << "## Homing in the final approach\n\n"
       << "Every homing call within homing_radius_m of the waypoint (by the tracked position), by the true distance: "
          "the "
          "landmark ALV's direction error and the bearing distance (5.1.1) of the view to the waypoint's cell (the "
          "measure --homing-arrived-rad thresholds).\n\n"
       << "| true distance [cm] | calls | with a direction | direction error [deg] | bearing distance [rad] |\n"
       << "|---|---|---|---|---|\n";
    for (const auto& bin : HomingBins(r.run.homing)) {
      md << "| " << Fixed(bin.lo_m * 100, 0) << (bin.hi_m < 1e8 ? "-" + Fixed(bin.hi_m * 100, 0) : "+") << " | "
         << bin.samples << " | " << bin.estimates << " | " << (bin.estimates ? Fixed(bin.error_deg, 1) : "-") << " | "
         << (bin.seen ? Fixed(bin.bearing_distance_rad, 4) : "-") << " |\n";
    }
    md << "\n## Options\n\n```\n" << options_text << "```\n";
  }
}

}  // namespace snapnav::eval
