#include "slam_compare.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include "homing_eval.hpp"
#include "localization_eval.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "slam_plot.hpp"
#include "stats.hpp"
#include "timing.hpp"
#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/plot/plot.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Distance(const nav::Pose2& a, const nav::Pose2& b) { return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m); }

// RatSLAM beside the simulation.
class RatSlamRunner {
 public:
  RatSlamRunner(const nav::RatSlamOptions& options, const nav::Pose2& start) : slam_(options, start) {}
  void Odometry(const nav::Pose2& delta, double dt_s) { slam_.OnOdometry(delta, dt_s); }
  void Frame(const cv::Mat& gray, const cv::Mat& mask) { slam_.OnImage(gray, mask); }
  nav::Pose2 pose() const { return slam_.pose(); }
  int64_t loop_closures() const { return static_cast<int64_t>(slam_.loop_closures()); }
  int64_t experiences() const { return static_cast<int64_t>(slam_.experience_map().experiences().size()); }

 private:
  nav::RatSlam slam_;
};

// RPE over the pairs, leaving out the segments that span `split` (a kidnapping: the truth jumps,
// no method can follow it in one segment): the parts before and after, pooled.
nav::RpeResult PooledRpe(const std::vector<std::pair<nav::Pose2, nav::Pose2>>& pairs, double delta_m,
                         std::optional<size_t> split) {
  if (!split || *split == 0 || *split >= pairs.size()) return nav::ComputeRpe(pairs, delta_m);
  const std::vector<std::pair<nav::Pose2, nav::Pose2>> a(pairs.begin(), pairs.begin() + static_cast<long>(*split));
  const std::vector<std::pair<nav::Pose2, nav::Pose2>> b(pairs.begin() + static_cast<long>(*split), pairs.end());
  const nav::RpeResult ra = nav::ComputeRpe(a, delta_m), rb = nav::ComputeRpe(b, delta_m);
  nav::RpeResult r;
  r.delta_m = delta_m;
  r.segments = ra.segments + rb.segments;
  if (r.segments == 0) return r;
  const double na = ra.segments, nb = rb.segments, n = r.segments;
  r.translation_rmse_m = std::sqrt((na * ra.translation_rmse_m * ra.translation_rmse_m +
                                    nb * rb.translation_rmse_m * rb.translation_rmse_m) / n);
  r.translation_mean_m = (na * ra.translation_mean_m + nb * rb.translation_mean_m) / n;
  r.translation_max_m = std::max(ra.translation_max_m, rb.translation_max_m);
  r.rotation_rmse_deg = std::sqrt((na * ra.rotation_rmse_deg * ra.rotation_rmse_deg +
                                   nb * rb.rotation_rmse_deg * rb.rotation_rmse_deg) / n);
  r.rotation_max_deg = std::max(ra.rotation_max_deg, rb.rotation_max_deg);
  return r;
}

void Measure(MethodResult* m, const std::vector<nav::Pose2>& truth, double rpe_delta_m, std::optional<size_t> split) {
  std::vector<std::pair<nav::Pose2, nav::Pose2>> pairs;
  m->error_m.clear();
  for (size_t i = 0; i < m->poses.size() && i < truth.size(); ++i) {
    pairs.emplace_back(m->poses[i], truth[i]);
    m->error_m.push_back(Distance(m->poses[i], truth[i]));
  }
  if (pairs.size() < 2) throw std::runtime_error("compare: fewer than 2 scans to measure " + m->name + " on");
  m->errors.ate = nav::ComputeAte(pairs);
  m->errors.ate_aligned = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
  m->errors.rpe = PooledRpe(pairs, rpe_delta_m, split);
}

// The time from `from_s` until the error is below `bound_m` and stays there for `hold_s` (or to
// the end of the run); NaN when it never does. `first` gets the first time back under the bound.
double RecoveryTime(const std::vector<double>& time_s, const std::vector<double>& error_m, double from_s,
                    double bound_m, double hold_s, double* first) {
  *first = kNaN;
  for (size_t i = 0; i < time_s.size(); ++i) {
    if (time_s[i] < from_s || !(error_m[i] < bound_m)) continue;
    if (std::isnan(*first)) *first = time_s[i] - from_s;
    bool holds = true;
    for (size_t j = i; j < time_s.size() && time_s[j] <= time_s[i] + hold_s; ++j) {
      if (!(error_m[j] < bound_m)) {
        holds = false;
        break;
      }
    }
    if (holds) return time_s[i] - from_s;
  }
  return kNaN;
}

}  // namespace

const std::vector<std::string>& CompareMethodNames() {
  static const std::vector<std::string> names = {"dead_reckoning", "laser_slam", "ratslam", "fused_slam",
                                                  "fused_no_vision"};
  return names;
}

bool RatSlamAvailable() { return true; }

void CompareOptions::Validate() const {
  camera.Validate();
  effects.Validate();
  if (!(visual_rate_hz > 0) || !(ratslam_rate_hz > 0)) throw std::invalid_argument("compare: rates must be positive");
  if (!(cell_spacing_m > 0)) throw std::invalid_argument("compare: cell_spacing_m must be positive");
  if (!(rpe_delta_m > 0)) throw std::invalid_argument("compare: rpe_delta_m must be positive");
  if (!(recovery_error_m > 0) || !(recovery_hold_s >= 0)) {
    throw std::invalid_argument("compare: recovery_error_m must be positive, recovery_hold_s >= 0");
  }
  view.Validate();
  localizer.Validate();
  vocabulary.Validate();
  ratslam.Validate();
  laser.Validate();
  fused.Validate();
}

const MethodResult& CompareRun::method(const std::string& name) const {
  for (const auto& m : methods) {
    if (m.name == name) return m;
  }
  throw std::invalid_argument("compare: no method " + name);
}

CompareRun RunComparison(const nav::sim::Scene& scene, const RouteMemory& memory, const CompareRunOptions& run,
                         const CompareOptions& options, const std::function<void(const std::string&)>& progress) {
  options.Validate();
  const auto wall0 = Clock::now();
  CompareRun out;
  out.name = run.name;
  out.scene = scene.name;
  out.memory_cells = memory.memory->size();
  out.memory_cell_error_mean_m = memory.cell_error_mean_m;
  out.memory_cell_error_max_m = memory.cell_error_max_m;
  out.memory_explore_pose = ExplorePoseName(options.explore_pose);
  out.people = scene.people.count;
  out.recovery_error_m = options.recovery_error_m;
  SimSlamOptions sim = run.sim;
  sim.log_path.clear();
  // People occlude camera and laser but do not block the robot (a robot that does not avoid them
  // and people who wait for it deadlock; eval route does the same).
  sim.drive.people_block_robot = false;
  const nav::Pose2 start{scene.start_pose.x(), scene.start_pose.y(), scene.start_pose.z()};

  ViewRenderer renderer(scene, options.camera, sim.seed ^ 0x5eedULL);
  const cv::Mat mask = UseRawMask(memory.raw_mask, renderer);  // the camera's calibration, made with the memory
  const cv::Mat clearance = nav::MaskClearance(mask);
  CameraPipeline pipeline;
  pipeline.input = CameraPipeline::Input::kRaw;
  pipeline.effects = options.effects;
  nav::FusedSlam fused(options.fused, start);
  // The ablation: the same fused SLAM given no visual measurement (its laser with the people
  // test): what the place cells add is fused's error against this one's.
  nav::FusedSlam no_vision(options.fused, start);
  const bool with_ratslam = options.run_ratslam && RatSlamAvailable();
  std::optional<RatSlamRunner> ratslam;
  if (with_ratslam) ratslam.emplace(options.ratslam, start);

  MethodResult fused_result, ratslam_result, no_vision_result;
  double no_vision_ms = 0, no_vision_max_ms = 0;
  double fused_scan_ms = 0, fused_max_ms = 0, filter_visual_ms = 0, view_ms = 0, localize_ms = 0;
  double ratslam_frame_ms = 0, ratslam_odometry_ms = 0, ratslam_max_ms = 0;
  std::vector<double> fix_errors;
  bool scan_pending = false;
  int64_t last_odometry_utime = -1, kidnap_seen_utime = -1;
  const int64_t visual_period_us = std::llround(1e6 / options.visual_rate_hz);
  const int64_t ratslam_period_us = std::llround(1e6 / options.ratslam_rate_hz);
  int64_t next_visual_us = sim.start_utime, next_ratslam_us = sim.start_utime;
  int64_t next_progress_s = 30;

  sim.on_sensor = [&](const SlamStep& s) {
    if (!s.is_scan) {
      fused.Predict(s.utime, s.odometry_delta);
      no_vision.Predict(s.utime, s.odometry_delta);
      if (ratslam) {
        const double dt = last_odometry_utime < 0 ? 0.0 : (s.utime - last_odometry_utime) * 1e-6;
        const auto t0 = Clock::now();
        ratslam->Odometry(s.odometry_delta, dt);
        ratslam_odometry_ms += MsSince(t0);
      }
      last_odometry_utime = s.utime;
      return;
    }
    // A scan for fused SLAM and for its ablation, each timed.
    const auto update = [&](nav::FusedSlam* f, MethodResult* result, double* total_ms, double* max_ms) {
      const auto t0 = Clock::now();
      f->Update(s.points);
      const double ms = MsSince(t0);
      *total_ms += ms;
      *max_ms = std::max(*max_ms, ms);
      ++result->updates;
      result->poses.push_back(f->pose());
    };
    update(&fused, &fused_result, &fused_scan_ms, &fused_max_ms);
    update(&no_vision, &no_vision_result, &no_vision_ms, &no_vision_max_ms);
    out.fused_sigma.push_back(fused.covariance().diagonal().cwiseMax(0.0).cwiseSqrt());
    out.fused_covariance.push_back(fused.covariance());
    out.no_vision_covariance.push_back(no_vision.covariance());
    out.fused_occluded_fraction.push_back(fused.occluded_fraction());
    {
      const double c = std::cos(fused.map_frame().theta_rad), sn = std::sin(fused.map_frame().theta_rad);
      const Eigen::Vector3d& u = fused.robot_offset();
      const Eigen::Matrix3d& uc = fused.robot_offset_covariance();
      Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
      j.topLeftCorner<2, 2>() << c, -sn, sn, c;
      out.fused_map_offset.push_back(j * u);
      out.fused_map_offset_sigma.push_back((j * uc * j.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt());
      const Eigen::Matrix3d lc = j * fused.laser_covariance() * j.transpose();
      out.fused_weakest_constraint.push_back(fused.weakest_constraint());
      out.fused_laser_sigma.push_back(lc.diagonal().cwiseMax(0.0).cwiseSqrt());
    }
    if (ratslam) ratslam_result.poses.push_back(ratslam->pose());
    scan_pending = true;
  };
  sim.on_step = [&](int64_t utime, const nav::sim::World& world) {
    const double t_s = (utime - sim.start_utime) * 1e-6;
    if (scan_pending) {  // the true pose at the scan's time
      out.utime.push_back(utime);
      out.time_s.push_back(t_s);
      out.truth.push_back(world.true_pose());
      scan_pending = false;
    }
    if (world.kidnapped() && !out.kidnapped) {
      out.kidnapped = true;
      kidnap_seen_utime = utime;  // sensors from this step on see the new place
      out.kidnap_at_s = world.kidnapped_at_s();
      if (progress) progress("kidnapped at " + Fixed(out.kidnap_at_s, 1) + " s to (" + Fixed(world.true_pose().x_m) +
                             ", " + Fixed(world.true_pose().y_m) + ")");
    }
    const bool visual_due = utime >= next_visual_us, ratslam_due = ratslam && utime >= next_ratslam_us;
    if (!visual_due && !ratslam_due) return;
    auto t0 = Clock::now();
    const cv::Mat panorama = renderer.ToPanorama(renderer.Sensor(world.true_pose(), pipeline.input, world.people()), pipeline);
    ++out.frames;
    if (visual_due) {
      next_visual_us += visual_period_us;
      t0 = Clock::now();
      const nav::PlaceView view = nav::MakePlaceView(panorama, options.view, mask, clearance);
      view_ms += MsSince(t0);
      t0 = Clock::now();
      std::optional<nav::Pose2> prediction;
      if (options.visual_prediction) prediction = fused.pose();
      const auto loc = memory.memory->Localize(view, prediction, options.localizer);
      localize_ms += MsSince(t0);
      ++out.visual_queries;
      if (!loc) {
        ++out.visual_no_answer;
      } else {
        t0 = Clock::now();
        const nav::VisualUpdate v = fused.AddVisual(utime, loc->pose, loc->covariance);
        filter_visual_ms += MsSince(t0);
        out.fixes.push_back(loc->pose);
        out.fix_outcomes.push_back(nav::VisualOutcomeName(v.outcome));
        out.fix_time_s.push_back(t_s);
        out.fix_truth.push_back(world.true_pose());
        out.fix_mahalanobis2.push_back(v.mahalanobis2);
        out.fix_occluded_fraction.push_back(fused.occluded_fraction());
        double nearest = kNaN;
        for (const auto& person : world.people()) {
          const double dist = std::hypot(person.center.x() - world.true_pose().x_m, person.center.y() - world.true_pose().y_m);
          if (!(dist >= nearest)) nearest = dist;
        }
        out.fix_nearest_person_m.push_back(nearest);
        fix_errors.push_back(Distance(loc->pose, world.true_pose()));
        if (v.outcome == nav::VisualOutcome::kRelocalized) {
          out.relocalization_time_s.push_back(t_s);
          if (progress) progress("relocalised at " + Fixed(t_s, 1) + " s to (" + Fixed(fused.pose().x_m) + ", " +
                                 Fixed(fused.pose().y_m) + ")");
        }
      }
    }
    if (ratslam_due) {
      next_ratslam_us += ratslam_period_us;
      cv::Mat gray;
      if (panorama.channels() == 3) {
        cv::cvtColor(panorama, gray, cv::COLOR_BGR2GRAY);
      } else {
        gray = panorama;
      }
      t0 = Clock::now();
      ratslam->Frame(gray, mask);
      const double ms = MsSince(t0);
      ratslam_frame_ms += ms;
      ratslam_max_ms = std::max(ratslam_max_ms, ms);
      ++ratslam_result.updates;
    }
    if (progress && t_s >= next_progress_s) {
      next_progress_s += 30;
      progress("t " + Fixed(t_s, 0) + " s: fused (" + Fixed(fused.pose().x_m) + ", " + Fixed(fused.pose().y_m) +
               ") truth (" + Fixed(world.true_pose().x_m) + ", " + Fixed(world.true_pose().y_m) + "), fixes " +
               std::to_string(fused.accepted()) + " accepted / " + std::to_string(fused.rejected()) + " rejected");
    }
  };
  const SimulatedSlamLog log = SimulateSlamLog(sim);
  out.duration_s = log.duration_s;
  out.distance_m = log.distance_m;
  out.scans = log.log.scans;
  out.odometry = log.log.odometry;
  out.collisions = log.collisions;
  if (out.truth.size() != fused_result.poses.size()) {
    throw std::runtime_error("compare: " + std::to_string(out.truth.size()) + " true poses for " +
                             std::to_string(fused_result.poses.size()) + " scans");
  }
  if (progress) progress("simulated " + Fixed(out.duration_s, 0) + " s, " + Fixed(out.distance_m, 1) + " m; dead reckoning and laser slam");

  // Dead reckoning and laser-only SLAM over the same log, as eval-slam (start frame -> scene frame).
  const SlamRun slam_run = RunSlam(log.log, options.laser);
  MethodResult dr, laser;
  dr.name = "dead_reckoning";
  laser.name = "laser_slam";
  for (size_t i = 0; i < slam_run.slam.size(); ++i) {
    laser.poses.push_back(start.Compose(slam_run.slam[i]));
    dr.poses.push_back(start.Compose(slam_run.dead_reckoning[i]));
  }
  laser.ran = dr.ran = true;
  laser.updates = static_cast<int64_t>(slam_run.slam.size());
  laser.update_unit = "scan";
  laser.ms_per_update = slam_run.ms_per_scan();
  laser.ms_per_frame = slam_run.ms_per_scan();
  laser.ms_max_update = kNaN;  // RunSlam times the whole run only
  {
    // Dead reckoning's own time (RunSlam does not time it), and laser SLAM's slowest scan.
    nav::DeadReckoning timed({});
    double total = 0, worst = 0;
    for (const SlamStep& s : log.log.steps) {
      if (s.is_scan) continue;
      const auto t0 = Clock::now();
      timed.AddOdometry(s.odometry_delta);
      const double ms = MsSince(t0);
      total += ms;
      worst = std::max(worst, ms);
      ++dr.updates;
    }
    dr.update_unit = "odometry message";
    dr.ms_per_update = dr.updates ? total / static_cast<double>(dr.updates) : 0;
    dr.ms_per_frame = out.scans ? total / static_cast<double>(out.scans) : 0;
    dr.ms_max_update = worst;
  }
  fused_result.name = "fused_slam";
  fused_result.ran = true;
  fused_result.update_unit = "scan";
  fused_result.ms_per_update = fused_result.updates ? fused_scan_ms / static_cast<double>(fused_result.updates) : 0;
  fused_result.ms_max_update = fused_max_ms;
  fused_result.ms_per_frame =
      out.scans ? (fused_scan_ms + filter_visual_ms + view_ms + localize_ms) / static_cast<double>(out.scans) : 0;
  no_vision_result.name = "fused_no_vision";
  no_vision_result.ran = true;
  no_vision_result.update_unit = "scan";
  no_vision_result.ms_per_update =
      no_vision_result.updates ? no_vision_ms / static_cast<double>(no_vision_result.updates) : 0;
  no_vision_result.ms_max_update = no_vision_max_ms;
  no_vision_result.ms_per_frame = out.scans ? no_vision_ms / static_cast<double>(out.scans) : 0;
  ratslam_result.name = "ratslam";
  if (with_ratslam) {
    ratslam_result.ran = true;
    ratslam_result.update_unit = "frame";
    ratslam_result.ms_per_update =
        ratslam_result.updates ? ratslam_frame_ms / static_cast<double>(ratslam_result.updates) : 0;
    ratslam_result.ms_max_update = ratslam_max_ms;
    ratslam_result.ms_per_frame = out.scans ? (ratslam_frame_ms + ratslam_odometry_ms) / static_cast<double>(out.scans) : 0;
    out.ratslam_loop_closures = ratslam->loop_closures();
    out.ratslam_experiences = ratslam->experiences();
  } else {
    ratslam_result.note = "not run (--no-ratslam)";
  }

  // The scan at which the truth jumps (a kidnapping): RPE segments do not span it.
  std::optional<size_t> split;
  if (out.kidnapped) {
    for (size_t i = 0; i < out.utime.size(); ++i) {
      if (out.utime[i] >= kidnap_seen_utime) {
        split = i;
        break;
      }
    }
  }
  for (MethodResult* m : {&dr, &laser, &ratslam_result, &fused_result, &no_vision_result}) {
    if (m->ran) Measure(m, out.truth, options.rpe_delta_m, split);
  }
  {
    // NEES of fused SLAM and of its ablation against the truth.
    const auto nees = [&](const MethodResult& m, const std::vector<Eigen::Matrix3d>& covariance,
                          std::vector<double>* each, double* mean, double* within_95) {
      double sum = 0;
      int within = 0, n = 0;
      each->assign(m.poses.size(), kNaN);
      for (size_t i = 0; i < m.poses.size() && i < out.truth.size() && i < covariance.size(); ++i) {
        const Eigen::Vector3d e(m.poses[i].x_m - out.truth[i].x_m, m.poses[i].y_m - out.truth[i].y_m,
                                nav::WrapAngle(m.poses[i].theta_rad - out.truth[i].theta_rad));
        const Eigen::LDLT<Eigen::Matrix3d> ldlt(covariance[i]);
        const double d2 = e.dot(ldlt.solve(e));
        if (!std::isfinite(d2)) continue;
        (*each)[i] = d2;
        sum += d2;
        within += d2 <= 7.81 ? 1 : 0;
        ++n;
      }
      *mean = n ? sum / n : kNaN;
      *within_95 = n ? static_cast<double>(within) / n : kNaN;
    };
    nees(fused_result, out.fused_covariance, &out.fused_nees, &out.fused_nees_mean, &out.fused_nees_within_95);
    nees(no_vision_result, out.no_vision_covariance, &out.no_vision_nees, &out.no_vision_nees_mean,
         &out.no_vision_nees_within_95);
  }
  if (out.kidnapped) {
    out.recovery_s = RecoveryTime(out.time_s, fused_result.error_m, out.kidnap_at_s, options.recovery_error_m,
                                  options.recovery_hold_s, &out.first_under_s);
  }
  out.methods = {dr, laser, ratslam_result, fused_result, no_vision_result};
  out.map = fused.WorldMapPoints();
  out.visual_accepted = fused.accepted();
  out.visual_rejected = fused.rejected();
  out.relocalizations = fused.relocalizations();
  out.fused_degenerate_scans = fused.degenerate_scans();
  out.relocalizations_refused = fused.refused_relocalizations();
  out.visual_stale = fused.stale();
  out.unmapped_scans = fused.unmapped_scans();
  out.dynamic_points = fused.dynamic_points();
  out.dynamic_overflow_scans = fused.dynamic_overflow_scans();
  const int64_t answered = out.visual_queries - out.visual_no_answer;
  out.ms_per_view = out.visual_queries ? view_ms / static_cast<double>(out.visual_queries) : 0;
  out.ms_per_localize = out.visual_queries ? localize_ms / static_cast<double>(out.visual_queries) : 0;
  out.ms_per_fix_filter = answered ? filter_visual_ms / static_cast<double>(answered) : 0;
  if (!fix_errors.empty()) {
    double sum = 0;
    for (const double e : fix_errors) sum += e;
    out.visual_error_mean_m = sum / static_cast<double>(fix_errors.size());
    out.visual_error_median_m = Median(fix_errors, kNaN);
  }
  out.seconds = MsSince(wall0) / 1000;
  return out;
}

LogComparison CompareOnLog(const std::string& log_path, const std::string& reference_path,
                           const nav::LaserSlamOptions& laser, double rpe_delta_m) {
  LogComparison out;
  out.log = log_path;
  out.reference = reference_path;
  const SlamLog log = LoadSlamLog(log_path, false);
  out.scans = log.scans;
  const SlamRun run = RunSlam(log, laser);
  out.dead_reckoning.name = "dead_reckoning";
  out.laser_slam.name = "laser_slam";
  out.dead_reckoning.ran = out.laser_slam.ran = true;
  out.dead_reckoning.poses = run.dead_reckoning;
  out.laser_slam.poses = run.slam;
  out.laser_slam.updates = static_cast<int64_t>(run.slam.size());
  out.laser_slam.update_unit = "scan";
  out.laser_slam.ms_per_update = out.laser_slam.ms_per_frame = run.ms_per_scan();
  if (reference_path.empty()) return out;
  const Reference reference = LoadReference(reference_path);
  for (MethodResult* m : {&out.dead_reckoning, &out.laser_slam}) {
    const auto pairs = PairWithReference(m->poses, run, reference);
    if (pairs.size() < 2) continue;
    out.has_reference = true;
    m->errors.ate = nav::ComputeAte(pairs);
    m->errors.ate_aligned = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
    m->errors.rpe = nav::ComputeRpe(pairs, rpe_delta_m);
  }
  return out;
}

std::vector<std::pair<std::string, double>> SummaryKeys(const CompareRun& run) {
  std::vector<std::pair<std::string, double>> k = {
      {"duration_s", run.duration_s},
      {"distance_m", run.distance_m},
      {"scans", static_cast<double>(run.scans)},
      {"frames_rendered", static_cast<double>(run.frames)},
      {"people", static_cast<double>(run.people)},
      {"blocked_steps", static_cast<double>(run.collisions)},
      {"memory_cells", static_cast<double>(run.memory_cells)},
      {"memory_cell_error_mean_m", run.memory_cell_error_mean_m},
      {"memory_cell_error_max_m", run.memory_cell_error_max_m}};
  for (const auto& m : run.methods) {
    const double nan = kNaN;
    auto v = [&](double x) { return m.ran ? x : nan; };
    k.push_back({m.name + "_ate_rmse_m", v(m.errors.ate_aligned.rmse_m)});
    k.push_back({m.name + "_ate_max_m", v(m.errors.ate_aligned.max_m)});
    k.push_back({m.name + "_ate_unaligned_rmse_m", v(m.errors.ate.rmse_m)});
    k.push_back({m.name + "_ate_unaligned_max_m", v(m.errors.ate.max_m)});
    k.push_back({m.name + "_ate_unaligned_final_m", v(m.errors.ate.final_m)});
    k.push_back({m.name + "_rpe_translation_rmse_m", v(m.errors.rpe.translation_rmse_m)});
    k.push_back({m.name + "_rpe_rotation_rmse_deg", v(m.errors.rpe.rotation_rmse_deg)});
    if (run.kidnapped) {
      // After fused SLAM recovered (or the last third of the run when it did not).
      const double from = run.kidnap_at_s + (std::isfinite(run.recovery_s) ? run.recovery_s : 0.0);
      double sum = 0;
      int n = 0;
      for (size_t i = 0; m.ran && i < m.error_m.size(); ++i) {
        if (run.time_s[i] < from) continue;
        sum += m.error_m[i] * m.error_m[i];
        ++n;
      }
      k.push_back({m.name + "_error_after_recovery_rmse_m", n > 0 ? std::sqrt(sum / n) : nan});
    }
    k.push_back({m.name + "_ms_per_update", v(m.ms_per_update)});
    k.push_back({m.name + "_ms_max_update", v(m.ms_max_update)});
    k.push_back({m.name + "_ms_per_frame", v(m.ms_per_frame)});
  }
  k.push_back({"rpe_delta_m", run.methods.empty() ? kNaN : run.methods.front().errors.rpe.delta_m});
  k.push_back({"visual_queries", static_cast<double>(run.visual_queries)});
  k.push_back({"visual_no_answer", static_cast<double>(run.visual_no_answer)});
  k.push_back({"visual_measurements_accepted", static_cast<double>(run.visual_accepted)});
  k.push_back({"visual_measurements_rejected", static_cast<double>(run.visual_rejected)});
  k.push_back({"visual_measurements_stale", static_cast<double>(run.visual_stale)});
  k.push_back({"relocalizations", static_cast<double>(run.relocalizations)});
  k.push_back({"relocalizations_refused", static_cast<double>(run.relocalizations_refused)});
  k.push_back({"unmapped_scans", static_cast<double>(run.unmapped_scans)});
  k.push_back({"fused_slam_dynamic_points", static_cast<double>(run.dynamic_points)});
  k.push_back({"fused_slam_dynamic_overflow_scans", static_cast<double>(run.dynamic_overflow_scans)});
  k.push_back({"fused_slam_nees_mean", run.fused_nees_mean});
  k.push_back({"fused_slam_nees_within_95", run.fused_nees_within_95});
  k.push_back({"fused_no_vision_nees_mean", run.no_vision_nees_mean});
  k.push_back({"fused_no_vision_nees_within_95", run.no_vision_nees_within_95});
  k.push_back({"fused_slam_degenerate_scans", static_cast<double>(run.fused_degenerate_scans)});
  k.push_back({"visual_fix_error_mean_m", run.visual_error_mean_m});
  k.push_back({"visual_fix_error_median_m", run.visual_error_median_m});
  k.push_back({"place_cells_ms_per_view", run.ms_per_view});
  k.push_back({"place_cells_ms_per_localize", run.ms_per_localize});
  k.push_back({"fused_slam_ms_per_visual_update", run.ms_per_fix_filter});
  k.push_back({"kidnapped", run.kidnapped ? 1.0 : 0.0});
  k.push_back({"kidnap_at_s", run.kidnapped ? run.kidnap_at_s : kNaN});
  k.push_back({"kidnap_recovery_s", run.kidnapped ? run.recovery_s : kNaN});
  k.push_back({"kidnap_first_under_bound_s", run.kidnapped ? run.first_under_s : kNaN});
  k.push_back({"kidnap_recovery_bound_m", run.recovery_error_m});
  k.push_back({"ratslam_loop_closures", RatSlamAvailable() ? static_cast<double>(run.ratslam_loop_closures) : kNaN});
  k.push_back({"ratslam_experiences", RatSlamAvailable() ? static_cast<double>(run.ratslam_experiences) : kNaN});
  k.push_back({"wall_s", run.seconds});
  return k;
}

namespace {

std::string Cell(double v, int digits = 3) { return std::isfinite(v) ? Fixed(v, digits) : "n/a"; }

const char* Label(const std::string& method) {
  if (method == "dead_reckoning") return "dead reckoning";
  if (method == "laser_slam") return "laser SLAM";
  if (method == "ratslam") return "RatSLAM";
  if (method == "fused_no_vision") return "fused, no visual fixes";
  return "fused SLAM";
}

// Position error over time of the methods in `only` (all when empty).
cv::Mat DrawErrors(const CompareRun& run, const std::vector<std::string>& only = {}) {
  std::vector<plot::Series> series;
  const size_t every = std::max<size_t>(1, run.time_s.size() / 500);
  for (const auto& m : run.methods) {
    if (!m.ran) continue;
    if (!only.empty() && std::find(only.begin(), only.end(), m.name) == only.end()) continue;
    plot::Series s{Label(m.name), {}, {}};
    for (size_t i = 0; i < m.error_m.size(); i += every) {
      s.x.push_back(run.time_s[i]);
      s.y.push_back(m.error_m[i]);
    }
    series.push_back(std::move(s));
  }
  plot::Axes axes;
  axes.title = run.name + ": position error against the ground truth (scene frame)" +
               (run.kidnapped ? ", kidnapped at " + Fixed(run.kidnap_at_s, 1) + " s" : "") +
               (only.empty() ? "" : ", the laser methods");
  axes.x_label = "simulated time [s]";
  axes.y_label = "error [m]";
  axes.y_from_zero = true;
  return plot::LineChart(axes, series, {1000, 520});
}

cv::Mat DrawTiming(const CompareRun& run) {
  std::vector<plot::BarGroup> groups;
  for (const auto& m : run.methods) {
    groups.push_back({Label(m.name), {m.ran ? m.ms_per_frame : kNaN}});
  }
  plot::Axes axes;
  axes.title = run.name + ": work per 10 Hz frame period (100 ms), one core";
  axes.y_label = "ms per frame";
  axes.value_labels = true;
  return plot::BarChart(axes, {"ms per frame"}, groups, {800, 450});
}

}  // namespace

void WriteCompareRun(const CompareRun& run, const std::string& dir) {
  const fs::path out(dir);
  fs::create_directories(out);
  {
    results::Json j;
    j["run"] = run.name;
    j["scene"] = run.scene;
    j["ratslam"] = run.method("ratslam").ran ? "ran" : run.method("ratslam").note;
    j["explore_pose"] = run.memory_explore_pose;
    for (const auto& [key, value] : SummaryKeys(run)) j[key] = results::Significant(value);
    results::WriteJsonFile((out / "summary.json").string(), j);
  }
  std::vector<std::vector<nav::Pose2>> tracks = {run.truth};
  std::vector<std::string> names = {"ground truth"};
  for (const auto& m : run.methods) {
    if (!m.ran) continue;
    tracks.push_back(m.poses);
    names.push_back(Label(m.name));
  }
  std::ostringstream title;
  title << run.name << ", " << Fixed(run.distance_m, 0) << " m: ATE";
  for (const auto& m : run.methods) {
    if (m.ran) title << " " << Label(m.name) << " " << Fixed(m.errors.ate_aligned.rmse_m, 3);
  }
  plot::SavePng(DrawRun(tracks, names, run.map, title.str()), (out / "trajectories.png").string());
  plot::SavePng(DrawErrors(run), (out / "errors.png").string());
  plot::SavePng(DrawErrors(run, {"laser_slam", "fused_slam", "fused_no_vision"}), (out / "errors_laser_fused.png").string());
  plot::SavePng(DrawTiming(run), (out / "timing.png").string());
  {
    std::ofstream csv(out / "trajectories.csv");
    csv << "utime,time_s,truth_x_m,truth_y_m,truth_theta_rad";
    for (const auto& m : run.methods) {
      if (m.ran) csv << "," << m.name << "_x_m," << m.name << "_y_m," << m.name << "_theta_rad";
    }
    csv << ",fused_slam_sigma_x_m,fused_slam_sigma_y_m,fused_slam_sigma_theta_rad,fused_slam_map_offset_x_m,"
           "fused_slam_map_offset_y_m,fused_slam_map_offset_theta_rad,fused_slam_map_offset_sigma_x_m,"
           "fused_slam_map_offset_sigma_y_m,fused_slam_map_offset_sigma_theta_rad,fused_slam_occluded_fraction,"
           "fused_slam_nees,fused_no_vision_nees,fused_slam_laser_sigma_x_m,fused_slam_laser_sigma_y_m,"
           "fused_slam_laser_sigma_theta_rad,fused_slam_weakest_constraint\n"
        << std::setprecision(9);
    for (size_t i = 0; i < run.truth.size(); ++i) {
      csv << run.utime[i] << "," << run.time_s[i] << "," << run.truth[i].x_m << "," << run.truth[i].y_m << ","
          << run.truth[i].theta_rad;
      for (const auto& m : run.methods) {
        if (m.ran) csv << "," << m.poses[i].x_m << "," << m.poses[i].y_m << "," << m.poses[i].theta_rad;
      }
      const Eigen::Vector3d sigma = i < run.fused_sigma.size() ? run.fused_sigma[i] : Eigen::Vector3d::Constant(kNaN);
      csv << "," << sigma.x() << "," << sigma.y() << "," << sigma.z();
      const Eigen::Vector3d nan3 = Eigen::Vector3d::Constant(kNaN);
      const Eigen::Vector3d o = i < run.fused_map_offset.size() ? run.fused_map_offset[i] : nan3;
      const Eigen::Vector3d os = i < run.fused_map_offset_sigma.size() ? run.fused_map_offset_sigma[i] : nan3;
      csv << "," << o.x() << "," << o.y() << "," << o.z() << "," << os.x() << "," << os.y() << "," << os.z() << ","
          << (i < run.fused_occluded_fraction.size() ? run.fused_occluded_fraction[i] : kNaN) << ","
          << (i < run.fused_nees.size() ? run.fused_nees[i] : kNaN) << ","
          << (i < run.no_vision_nees.size() ? run.no_vision_nees[i] : kNaN);
      const Eigen::Vector3d ls = i < run.fused_laser_sigma.size() ? run.fused_laser_sigma[i] : nan3;
      csv << "," << ls.x() << "," << ls.y() << "," << ls.z() << ","
          << (i < run.fused_weakest_constraint.size() ? run.fused_weakest_constraint[i] : kNaN) << "\n";
    }
  }
  {
    std::ofstream csv(out / "fixes.csv");
    csv << "time_s,x_m,y_m,theta_rad,outcome,truth_x_m,truth_y_m,truth_theta_rad,error_m,mahalanobis2,"
           "occluded_fraction,nearest_person_m\n"
        << std::setprecision(9);
    for (size_t i = 0; i < run.fixes.size(); ++i) {
      const nav::Pose2& z = run.fixes[i];
      const nav::Pose2& t = run.fix_truth[i];
      csv << run.fix_time_s[i] << "," << z.x_m << "," << z.y_m << "," << z.theta_rad << "," << run.fix_outcomes[i] << ","
          << t.x_m << "," << t.y_m << "," << t.theta_rad << "," << Distance(z, t) << "," << run.fix_mahalanobis2[i] << ","
          << run.fix_occluded_fraction[i] << "," << run.fix_nearest_person_m[i] << "\n";
    }
  }
}

std::string CompareTableMarkdown(const std::vector<CompareRun>& runs, const std::vector<LogComparison>& logs) {
  std::ostringstream s;
  s << "ATE RMSE after SE(2) alignment [m] (scene frame, no alignment, in brackets); RPE per metre travelled.\n\n"
    << "| run | distance | dead reckoning | laser SLAM | RatSLAM | fused SLAM | fused SLAM without its visual fixes "
       "(ablation) | visual fixes accepted / rejected | relocalisations | kidnap recovery |\n"
       "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : runs) {
    s << "| " << r.name << " | " << Fixed(r.distance_m, 0) << " m";
    for (const auto& m : r.methods) {
      if (!m.ran) {
        s << " | n/a";
        continue;
      }
      s << " | " << Fixed(m.errors.ate_aligned.rmse_m, 4) << " (" << Fixed(m.errors.ate.rmse_m, 4) << ")";
    }
    s << " | " << r.visual_accepted << " / " << r.visual_rejected << " | " << r.relocalizations << " | "
      << (r.kidnapped ? (std::isfinite(r.recovery_s) ? Fixed(r.recovery_s, 1) + " s" : std::string("not recovered"))
                      : std::string("-"))
      << " |\n";
  }
  for (const auto& l : logs) {
    s << "| log " << fs::path(l.log).filename().string() << " | " << l.scans << " scans";
    if (l.has_reference) {
      s << " | " << Fixed(l.dead_reckoning.errors.ate_aligned.rmse_m, 3) << " | "
        << Fixed(l.laser_slam.errors.ate_aligned.rmse_m, 3);
    } else {
      s << " | no reference | no reference";
    }
    s << " | n/a (no frames) | n/a (no frames) | n/a (no frames) | - | - | - |\n";
  }
  s << "\nThe ablation column is fused SLAM given no visual measurement: its laser SLAM with the people test "
       "(dynamic_* keys of [fused_slam]). What the place cells add is fused SLAM's ATE against it; what the people "
       "test adds is the ablation's against laser SLAM.\n\n| run | fused SLAM - ablation (vision's share) | "
       "ablation - laser SLAM (the people test's share) |\n|---|---|---|\n";
  for (const auto& r : runs) {
    const MethodResult& f = r.method("fused_slam");
    const MethodResult& a = r.method("fused_no_vision");
    const MethodResult& l = r.method("laser_slam");
    s << "| " << r.name << " | " << Fixed((f.errors.ate_aligned.rmse_m - a.errors.ate_aligned.rmse_m) * 1000, 2)
      << " mm | " << Fixed((a.errors.ate_aligned.rmse_m - l.errors.ate_aligned.rmse_m) * 1000, 2) << " mm |\n";
  }
  s << "\nThe place-cell memory of each run, explored beforehand along the route: where its cells are stored (laser-slam: "
       "laser-only SLAM's pose during the exploration, as a robot explores; truth: the true pose, an upper bound) and "
       "how far that is from the truth.\n\n| run | cells | stored at | off the truth, mean / max [m] |\n|---|---|---|---|\n";
  for (const auto& r : runs) {
    s << "| " << r.name << " | " << r.memory_cells << " | " << r.memory_explore_pose << " | "
      << Fixed(r.memory_cell_error_mean_m, 3) << " / " << Fixed(r.memory_cell_error_max_m, 3) << " |\n";
  }
  s << "\nPer method: RPE translation [m] / rotation [deg] per metre, ms per update, ms per 10 Hz frame period "
       "(all of the method's work per scan; fused SLAM includes its place-cell views and queries).\n\n"
       "| run | method | RPE | ms per update | slowest update | ms per frame |\n|---|---|---|---|---|---|\n";
  for (const auto& r : runs) {
    for (const auto& m : r.methods) {
      s << "| " << r.name << " | " << Label(m.name);
      if (!m.ran) {
        s << " | " << m.note << " | | | |\n";
        continue;
      }
      s << " | " << Fixed(m.errors.rpe.translation_rmse_m, 3) << " / " << Fixed(m.errors.rpe.rotation_rmse_deg, 2)
        << " | " << Fixed(m.ms_per_update, 3) << " per " << m.update_unit << " | " << Cell(m.ms_max_update, 2)
        << " | " << Fixed(m.ms_per_frame, 2) << " |\n";
    }
  }
  return s.str();
}

std::string CompareTableCsv(const std::vector<CompareRun>& runs, const std::vector<LogComparison>& logs) {
  std::ostringstream s;
  s << "run,scene,method,ran,distance_m,ate_rmse_m,ate_max_m,ate_unaligned_rmse_m,ate_unaligned_final_m,"
       "rpe_translation_rmse_m,rpe_rotation_rmse_deg,ms_per_update,ms_max_update,ms_per_frame,"
       "visual_accepted,visual_rejected,relocalizations,kidnap_recovery_s\n";
  auto row = [&](const std::string& run, const std::string& scene, const MethodResult& m, double distance,
                 const std::string& visual) {
    s << run << "," << scene << "," << m.name << "," << (m.ran ? 1 : 0) << "," << Cell(distance, 2);
    if (m.ran) {
      s << "," << Cell(m.errors.ate_aligned.rmse_m, 4) << "," << Cell(m.errors.ate_aligned.max_m, 4) << ","
        << Cell(m.errors.ate.rmse_m, 4) << "," << Cell(m.errors.ate.final_m, 4) << ","
        << Cell(m.errors.rpe.translation_rmse_m, 4) << "," << Cell(m.errors.rpe.rotation_rmse_deg, 3) << ","
        << Cell(m.ms_per_update, 4) << "," << Cell(m.ms_max_update, 3) << "," << Cell(m.ms_per_frame, 3);
    } else {
      s << ",,,,,,,,,";
    }
    s << "," << visual << "\n";
  };
  for (const auto& r : runs) {
    for (const auto& m : r.methods) {
      const std::string visual =
          m.name == "fused_slam" ? std::to_string(r.visual_accepted) + "," + std::to_string(r.visual_rejected) + "," +
                                       std::to_string(r.relocalizations) + "," +
                                       (r.kidnapped ? Cell(r.recovery_s, 2) : std::string())
                                 : std::string(",,,");
      row(r.name, r.scene, m, r.distance_m, visual);
    }
  }
  for (const auto& l : logs) {
    const std::string name = "log:" + fs::path(l.log).filename().string();
    row(name, "", l.dead_reckoning, kNaN, ",,,");
    row(name, "", l.laser_slam, kNaN, ",,,");
  }
  return s.str();
}

std::vector<std::string> MissedTargets(const CompareRun& run, double max_recovery_s) {
  std::vector<std::string> missed;
  const MethodResult& fused = run.method("fused_slam");
  for (const auto& m : run.methods) {
    // The four methods; the ablation (fused_no_vision) is reported beside them.
    if (!m.ran || m.name == "fused_slam" || m.name == "fused_no_vision") continue;
    if (!(fused.errors.ate_aligned.rmse_m < m.errors.ate_aligned.rmse_m)) {
      missed.push_back(run.name + ": fused SLAM ATE " + Fixed(fused.errors.ate_aligned.rmse_m, 4) + " m is not below " +
                       Label(m.name) + "'s " + Fixed(m.errors.ate_aligned.rmse_m, 4) + " m");
    }
  }
  if (run.kidnapped && !(run.recovery_s <= max_recovery_s)) {
    missed.push_back(run.name + ": fused SLAM recovered from the kidnapping in " +
                     (std::isfinite(run.recovery_s) ? Fixed(run.recovery_s, 1) + " s" : std::string("never")) +
                     " (target <= " + Fixed(max_recovery_s, 0) + " s)");
  }
  return missed;
}

}  // namespace snapnav::eval
