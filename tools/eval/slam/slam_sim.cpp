#include "slam_sim.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "scene_file.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/log_writer.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

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

void SimSlamOptions::Validate() const {
  if (laps < 0 || !(duration_s >= 0) || !std::isfinite(duration_s)) {
    throw std::invalid_argument("slam sim: laps and duration_s must be >= 0");
  }
  if (laps == 0 && duration_s == 0) throw std::invalid_argument("slam sim: give a number of laps or a duration");
  if (!(physics_rate_hz > 0) || std::abs(1e6 / physics_rate_hz - std::round(1e6 / physics_rate_hz)) > 1e-9) {
    throw std::invalid_argument("slam sim: physics_rate_hz must give a whole number of microseconds per step");
  }
  EveryNSteps(physics_rate_hz, odometry_rate_hz, "odometry");
  EveryNSteps(physics_rate_hz, laser_rate_hz, "laser");
  if (!(route_speed_mps > 0) || !(route_tolerance_m > 0)) {
    throw std::invalid_argument("slam sim: route speed and tolerance must be positive");
  }
  drive.Validate();
  laser.Validate();
}

SimSlamOptions SimSlamOptions::FromSimConfig(const processes::SimConfig& sim) {
  SimSlamOptions o;
  o.scene = sim.scene;
  o.seed = sim.seed;
  o.start_utime = sim.start_utime;
  o.physics_rate_hz = sim.physics_rate_hz;
  o.odometry_rate_hz = sim.odometry_rate_hz;
  o.laser_rate_hz = sim.laser_rate_hz;
  o.route_speed_mps = sim.route_speed_mps;
  o.route_tolerance_m = sim.route_tolerance_m;
  o.drive = sim.drive_options;
  o.laser = sim.laser;
  o.kidnap = sim.kidnap;
  o.scan_channel = sim.scan_channel;
  o.odometry_channel = sim.odometry_channel;
  o.ground_truth_channel = sim.ground_truth_channel;
  return o;
}

SimulatedSlamLog SimulateSlamLog(const SimSlamOptions& options) {
  options.Validate();
  const nav::sim::Scene scene = processes::LoadSceneFile(processes::SceneFilePath(options.scene));
  SimulatedSlamLog out;
  out.scene_name = scene.name;
  out.route = options.route.empty() ? scene.route : options.route;
  if (out.route.empty()) throw std::runtime_error("scene '" + scene.name + "' has no route and none was given");

  nav::sim::World world(scene, options.drive, options.laser, options.seed);
  world.SetKidnap(options.kidnap);
  nav::sim::RouteDriver driver(out.route, options.route_speed_mps, options.route_tolerance_m, /*loop=*/true);
  bool restarted = false;  // the driver went on after the kidnapping
  out.start = world.true_pose();
  const nav::Pose2 to_start_frame = out.start.Inverse();

  const int64_t dt_us = static_cast<int64_t>(std::llround(1e6 / options.physics_rate_hz));
  const int odometry_every = EveryNSteps(options.physics_rate_hz, options.odometry_rate_hz, "odometry");
  const int laser_every = EveryNSteps(options.physics_rate_hz, options.laser_rate_hz, "laser");
  // A robot that cannot finish its laps (blocked, unreachable waypoint) must not run forever.
  const Eigen::Vector2d start_xy(out.start.x_m, out.start.y_m);
  const double expected_s =
      ((out.route.front() - start_xy).norm() + options.laps * RouteLength(out.route)) / options.route_speed_mps;
  const int64_t limit_us = options.duration_s > 0 ? static_cast<int64_t>(std::llround(options.duration_s * 1e6))
                                                  : static_cast<int64_t>(std::llround((3 * expected_s + 60) * 1e6));

  std::unique_ptr<glue::LogWriter> writer;
  if (!options.log_path.empty()) writer = std::make_unique<glue::LogWriter>(options.log_path);

  SlamLog& log = out.log;
  log.path = options.log_path.empty() ? "sim:" + scene.name : options.log_path;
  const nav::sim::LaserOptions& laser = options.laser;
  int64_t step = 0;
  for (;; ++step) {
    const int64_t t_us = step * dt_us;
    if (t_us >= limit_us) {
      if (options.duration_s > 0) break;
      throw std::runtime_error("slam sim: the robot completed " + std::to_string(driver.laps()) + " of " +
                               std::to_string(options.laps) + " laps of the route in " +
                               std::to_string(limit_us / 1000000) + " s (blocked?)");
    }
    const int64_t utime = options.start_utime + t_us;
    // Sensors first: what the robot sees at time t, then it moves to t + dt (as the sim process).
    if (step % odometry_every == 0) {
      const nav::sim::OdometryReading r = world.TakeOdometry();
      const odometry_t o = glue::ToOdometryMsg(utime, "sim_wheels", r.cumulative, r.delta, r.dt_s);
      SlamStep s;
      s.utime = utime;
      s.odometry_delta = glue::OdometryDelta(o);
      log.steps.push_back(std::move(s));
      ++log.odometry;
      if (options.on_sensor) options.on_sensor(log.steps.back());
      out.reference.by_time.push_back({utime, to_start_frame.Compose(world.true_pose())});
      if (writer) {
        writer->Write(options.odometry_channel, o);
        writer->Write(options.ground_truth_channel,
                      glue::ToPoseMsg(utime, "ground_truth", "map", world.true_pose(), Eigen::Matrix3d::Zero()));
      }
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
      // As eval::LoadSlamLog reads a scan message.
      SlamStep s;
      s.is_scan = true;
      s.utime = utime;
      s.points = nav::ScanToPoints(m.ranges_m, m.angle_min_rad, m.angle_increment_rad, m.range_min_m, m.range_max_m,
                                   nav::Pose2{m.sensor_x_m, m.sensor_y_m, m.sensor_theta_rad});
      s.ranges_key.assign(reinterpret_cast<const char*>(m.ranges_m.data()), m.ranges_m.size() * sizeof(float));
      if (log.beams == 0) log.beams = m.nranges;
      log.steps.push_back(std::move(s));
      ++log.scans;
      if (writer) writer->Write(options.scan_channel, m);
      if (options.on_sensor) options.on_sensor(log.steps.back());
    }
    if (options.on_step) options.on_step(utime, world);
    const Eigen::Vector2d cmd = driver.Command(world.true_pose());
    if (options.laps > 0 && driver.laps() >= options.laps) break;
    world.Step(cmd.x(), cmd.y(), dt_us * 1e-6);
    if (world.kidnapped() && !restarted) {
      restarted = true;
      driver.Restart(world.true_pose());
    }
  }
  log.events = 2 * log.odometry + log.scans;  // as many as the written log holds (ground truth included)
  out.laps = driver.laps();
  out.duration_s = step * dt_us * 1e-6;
  out.distance_m = world.distance_m();
  out.collisions = world.collisions();
  if (writer) {
    out.log_events = writer->events();
    writer->Close();
  }
  return out;
}

SimSlamEvaluation EvaluateSimulatedSlam(const SimulatedSlamLog& sim, const nav::LaserSlamOptions& options,
                                        double rpe_delta_m) {
  SimSlamEvaluation e;
  e.run = RunSlam(sim.log, options);
  const auto slam_pairs = PairWithReference(e.run.slam, e.run, sim.reference);
  const auto dr_pairs = PairWithReference(e.run.dead_reckoning, e.run, sim.reference);
  if (slam_pairs.size() < 2 || slam_pairs.size() != e.run.slam.size()) {
    throw std::runtime_error("slam sim: " + std::to_string(slam_pairs.size()) + " of " +
                             std::to_string(e.run.slam.size()) + " scans have a true pose");
  }
  for (const auto& pair : slam_pairs) e.truth.push_back(pair.second);
  auto errors = [rpe_delta_m](const std::vector<std::pair<nav::Pose2, nav::Pose2>>& pairs) {
    TrajectoryErrors t;
    t.ate = nav::ComputeAte(pairs);
    t.ate_aligned = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
    t.rpe = nav::ComputeRpe(pairs, rpe_delta_m);
    return t;
  };
  e.laser_slam = errors(slam_pairs);
  e.dead_reckoning = errors(dr_pairs);
  return e;
}

}  // namespace snapnav::eval
