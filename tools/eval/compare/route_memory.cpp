// The place-cell memory of the comparison, explored along a scene's route before the evaluated run
// (slam_compare.hpp: RouteMemory, ExploreRouteMemory): its cells stored at the SLAM's pose of the
// exploration, as a robot explores, or at the true pose, the upper bound.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "exploration.hpp"
#include "homing_eval.hpp"
#include "slam_compare.hpp"
#include "timing.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/slam/fused_slam.hpp"

namespace snapnav::eval {

const char* ExplorePoseName(CompareOptions::ExplorePose p) {
  switch (p) {
    case CompareOptions::ExplorePose::kLaserSlam: return "laser-slam";
    case CompareOptions::ExplorePose::kFusedSlam: return "fused-slam";
    case CompareOptions::ExplorePose::kTruth: return "truth";
  }
  return "?";
}

namespace {

// The exploration with a SLAM: the route driven once with the simulator's noise (as the evaluated
// run, its own seed), laser-only SLAM (or fused SLAM, no visual fixes) over that run's odometry and
// scans, and a sample every `spacing_m` of the SLAM's own travel, at the scan: the true pose (where
// the camera is), the SLAM's pose (where the robot believes it is, scene frame) and the people then.
struct SlamExploreSample {
  ExploreSample sample;
  nav::Pose2 estimate;
};
std::vector<SlamExploreSample> ExploreWithSlam(const nav::sim::Scene& scene, const CompareOptions& options,
                                               const SimSlamOptions& sim) {
  SimSlamOptions explore = sim;
  explore.seed = options.explore_seed;
  // The route once and back to its first waypoint (a lap ends at the last waypoint): every part the
  // run drives, as the exploration at the true pose.
  explore.route = sim.route.empty() ? scene.route : sim.route;
  if (!explore.route.empty()) explore.route.push_back(explore.route.front());
  explore.laps = 1;
  explore.duration_s = 0;
  explore.kidnap = {};
  explore.log_path.clear();
  explore.drive.people_block_robot = false;  // as the evaluated run (RunComparison)
  // The true pose and the people at every scan (the scan's step, then the physics step's observer).
  std::map<int64_t, ExploreSample> at_scan;
  int64_t pending_scan = -1;
  explore.on_sensor = [&](const SlamStep& s) {
    if (s.is_scan) pending_scan = s.utime;
  };
  explore.on_step = [&](int64_t utime, const nav::sim::World& world) {
    if (utime != pending_scan) return;
    ExploreSample& e = at_scan[utime];
    e.truth = world.true_pose();
    e.utime = utime;
    e.people = world.people();
  };
  const SimulatedSlamLog log = SimulateSlamLog(explore);
  // The SLAM's pose at every scan (scene frame) and the scan's time.
  std::vector<nav::Pose2> poses;
  std::vector<int64_t> utimes;
  if (options.explore_pose == CompareOptions::ExplorePose::kFusedSlam) {
    nav::FusedSlam fused(options.fused, log.start);
    for (const SlamStep& s : log.log.steps) {
      if (!s.is_scan) {
        fused.Predict(s.utime, s.odometry_delta);
        continue;
      }
      fused.Update(s.points);
      poses.push_back(fused.pose());
      utimes.push_back(s.utime);
    }
  } else {
    const SlamRun run = RunSlam(log.log, options.laser);
    for (const nav::Pose2& p : run.slam) poses.push_back(log.start.Compose(p));
    utimes = run.utime;
  }
  std::vector<SlamExploreSample> out;
  double travelled = 0, last = -1;
  for (size_t i = 0; i < poses.size(); ++i) {
    const nav::Pose2& estimate = poses[i];
    if (i > 0) travelled += std::hypot(poses[i].x_m - poses[i - 1].x_m, poses[i].y_m - poses[i - 1].y_m);
    if (last >= 0 && travelled - last < options.cell_spacing_m) continue;
    const auto it = at_scan.find(utimes[i]);
    if (it == at_scan.end()) throw std::logic_error("compare: no true pose at an exploration scan");
    last = travelled;
    out.push_back({it->second, estimate});
  }
  return out;
}

}  // namespace

RouteMemory ExploreRouteMemory(const nav::sim::Scene& scene, const CompareOptions& options, const SimSlamOptions& sim) {
  if (scene.route.empty()) throw std::runtime_error("scene '" + scene.name + "' has no route to explore");
  const auto t0 = Clock::now();
  std::vector<SlamExploreSample> samples;
  if (options.explore_pose == CompareOptions::ExplorePose::kTruth) {
    // From the start, along the route, back to its first waypoint: every part the run drives.
    std::vector<Eigen::Vector2d> waypoints = {scene.start_pose.head<2>()};
    for (const auto& w : scene.route) waypoints.push_back(w);
    waypoints.push_back(scene.route.front());
    for (const ExploreSample& s : DriveRoute(scene, waypoints, sim.drive, options.cell_spacing_m, options.explore_seed)) {
      samples.push_back({s, s.truth});
    }
  } else {
    samples = ExploreWithSlam(scene, options, sim);
  }
  RouteMemory out;
  out.memory = std::make_unique<nav::PlaceCellMemory>(options.view, options.camera.panorama, options.vocabulary);
  ViewRenderer renderer(scene, options.camera, options.explore_seed);
  out.raw_mask = RawMask(options.mask, renderer, cv::Size(options.camera.omni_width_px, options.camera.omni_height_px),
                         sim.seed);
  const cv::Mat mask = UseRawMask(out.raw_mask, renderer), clearance = nav::MaskClearance(mask);
  CameraPipeline pipeline;
  pipeline.input = CameraPipeline::Input::kRaw;
  pipeline.effects = options.effects;
  const auto t_views = Clock::now();
  for (const auto& [s, estimate] : samples) {
    const cv::Mat panorama = renderer.ToPanorama(renderer.Sensor(s.truth, pipeline.input, s.people), pipeline);
    out.memory->Add(estimate, s.utime, nav::MakePlaceView(panorama, options.view, mask, clearance));
    out.cell_poses.push_back(s.truth);
    out.cell_estimates.push_back(estimate);
    const double e = std::hypot(estimate.x_m - s.truth.x_m, estimate.y_m - s.truth.y_m);
    out.cell_error_mean_m += e / static_cast<double>(samples.size());
    out.cell_error_max_m = std::max(out.cell_error_max_m, e);
  }
  out.ms_per_view = samples.empty() ? 0 : MsSince(t_views) / static_cast<double>(samples.size());
  out.memory->BuildIndex();
  out.seconds = MsSince(t0) / 1000;
  return out;
}

}  // namespace snapnav::eval
