#include "sim_harness.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "calibrated_mask.hpp"
#include "scene_file.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/nav/homing/unwrap.hpp"

namespace snapnav::eval {

int EveryNSteps(double physics_hz, double rate_hz, const char* what) {
  const double n = physics_hz / rate_hz;
  if (!std::isfinite(n) || n < 1 || std::abs(n - std::round(n)) > 1e-6) {
    throw std::invalid_argument(std::string("simulator: ") + what + " rate must divide the physics rate");
  }
  return static_cast<int>(std::round(n));
}

double RouteLength(const std::vector<Eigen::Vector2d>& route) {
  double length = 0;
  for (size_t i = 0; i < route.size(); ++i) length += (route[(i + 1) % route.size()] - route[i]).norm();
  return length;
}

SimDriveResult DriveSimulation(const SimDriveOptions& options, const SimFrameOptions* frames, SimDriveSink& sink,
                               const std::string& what, const std::function<void(double, int)>& progress) {
  using Clock = std::chrono::steady_clock;
  const nav::sim::Scene scene = processes::LoadSceneFile(processes::SceneFilePath(options.scene));
  SimDriveResult out;
  out.scene_name = scene.name;
  out.route = options.route.empty() ? scene.route : options.route;
  if (out.route.empty()) throw std::runtime_error("scene '" + scene.name + "' has no route and none was given");

  nav::sim::World world(scene, options.drive, options.laser, options.seed);
  world.SetKidnap(options.kidnap);
  nav::sim::RouteDriver driver(out.route, options.route_speed_mps, options.route_tolerance_m, /*loop=*/true);
  bool restarted = false;  // the driver went on after the kidnapping
  out.start = world.true_pose();

  // The camera only for a sink that wants frames; its effects draw from their own generator (as
  // the sim process), so the world's draws are the same with or without it.
  const bool with_frames = frames && sink.WantsFrames();
  std::optional<nav::sim::OmniRenderer> renderer;
  std::optional<nav::Unwrapper> unwrapper;
  std::mt19937_64 effects_rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  const std::vector<nav::sim::Cylinder> nobody;
  int camera_every = 0;
  if (with_frames) {
    renderer.emplace(scene, frames->camera);
    if (frames->raw_frames) {
      unwrapper.emplace(frames->camera.ReportedMirror(), frames->camera.panorama,
                        cv::Size(frames->camera.omni_width_px, frames->camera.omni_height_px));
      const cv::Mat raw_mask = frames->truth_mask ? TruthMask(renderer->PartsMask()) : frames->raw_mask;
      if (!raw_mask.empty()) unwrapper->SetMask(raw_mask);
      // (Without a raw mask the panorama's may still mask a rim that runs past the image.)
      if (!unwrapper->panorama_mask().empty()) sink.OnPanoramaMask(unwrapper->panorama_mask());
    } else if (frames->truth_mask || !frames->raw_mask.empty()) {
      throw std::invalid_argument("a mask is of raw images: it needs raw frames");
    }
    camera_every = EveryNSteps(options.physics_rate_hz, frames->rate_hz, "camera");
  }
  sink.OnStart(scene, out.start);

  const int64_t dt_us = static_cast<int64_t>(std::llround(1e6 / options.physics_rate_hz));
  const int odometry_every = EveryNSteps(options.physics_rate_hz, options.odometry_rate_hz, "odometry");
  const int laser_every = EveryNSteps(options.physics_rate_hz, options.laser_rate_hz, "laser");
  // A robot that cannot finish its laps (blocked, unreachable waypoint) must not run forever.
  const Eigen::Vector2d start_xy(out.start.x_m, out.start.y_m);
  const double expected_s =
      ((out.route.front() - start_xy).norm() + options.laps * RouteLength(out.route)) / options.route_speed_mps;
  const int64_t limit_us = options.duration_s > 0 ? static_cast<int64_t>(std::llround(options.duration_s * 1e6))
                                                  : static_cast<int64_t>(std::llround((3 * expected_s + 60) * 1e6));
  const int64_t progress_every = std::max<int64_t>(1, static_cast<int64_t>(10.0 * options.physics_rate_hz));
  const nav::sim::LaserOptions& laser = options.laser;
  cv::Mat image, panorama, gray;
  int64_t step = 0;
  for (;; ++step) {
    const int64_t t_us = step * dt_us;
    if (t_us >= limit_us) {
      if (options.duration_s > 0) break;
      throw std::runtime_error(what + ": the robot completed " + std::to_string(driver.laps()) + " of " +
                               std::to_string(options.laps) + " laps of the route in " +
                               std::to_string(limit_us / 1000000) + " s (blocked?)");
    }
    const int64_t utime = options.start_utime + t_us;
    // Sensors first: what the robot sees at time t, then it moves to t + dt (as the sim process).
    if (step % odometry_every == 0) {
      const nav::sim::OdometryReading r = world.TakeOdometry();
      sink.OnOdometry(glue::ToOdometryMsg(utime, "sim_wheels", r.cumulative, r.delta, r.dt_s), world.true_pose());
      ++out.odometry;
    }
    if (step % laser_every == 0) {
      laser_scan_t m{};
      m.utime = utime;
      m.sensor_name = "sim_hokuyo";
      m.sensor_x_m = static_cast<float>(laser.mount_x_m);
      m.angle_min_rad = static_cast<float>(laser.angle_min_rad);
      m.angle_increment_rad = static_cast<float>(laser.AngleIncrement());
      m.range_min_m = static_cast<float>(laser.range_min_m);
      m.range_max_m = static_cast<float>(laser.range_max_m);
      m.ranges_m = world.Scan();
      m.nranges = static_cast<int32_t>(m.ranges_m.size());
      m.nintensities = 0;
      sink.OnScan(m);
      ++out.scans;
    }
    if (with_frames && step % camera_every == 0) {
      const auto t0 = Clock::now();
      const auto& people = frames->people ? world.people() : nobody;
      if (frames->raw_frames) {
        renderer->RenderOmni(world.true_pose(), people, &image);
      } else {
        renderer->RenderPanorama(world.true_pose(), people, &image);
      }
      nav::sim::ApplyImageEffects(frames->effects, effects_rng, &image);
      if (unwrapper) {
        unwrapper->Unwrap(image, &panorama);
      } else {
        panorama = image;
      }
      if (panorama.channels() == 1) {
        gray = panorama;
      } else {
        cv::cvtColor(panorama, gray, cv::COLOR_BGR2GRAY);
      }
      out.render_s += std::chrono::duration<double>(Clock::now() - t0).count();
      sink.OnFrame(utime, gray, world.true_pose());
      ++out.frames;
    }
    sink.OnStep(utime, world);
    const Eigen::Vector2d cmd = driver.Command(world.true_pose());
    if (options.laps > 0 && driver.laps() >= options.laps) break;
    world.Step(cmd.x(), cmd.y(), dt_us * 1e-6);
    if (world.kidnapped() && !restarted) {
      restarted = true;
      driver.Restart(world.true_pose());
    }
    if (progress && step % progress_every == 0 && step > 0) progress(t_us * 1e-6, driver.laps());
  }
  out.laps = driver.laps();
  out.duration_s = step * dt_us * 1e-6;
  out.distance_m = world.distance_m();
  out.collisions = world.collisions();
  return out;
}

}  // namespace snapnav::eval
