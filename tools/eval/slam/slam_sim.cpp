#include "slam_sim.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/log_writer.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::eval {

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

namespace {

// The harness's readings as laser SLAM inputs (the steps eval::LoadSlamLog makes from a log), the
// truth at every odometry reading in the start frame, and the written log.
class SlamLogSink : public SimDriveSink {
 public:
  SlamLogSink(const SimSlamOptions& options, SimulatedSlamLog* out) : options_(options), out_(out) {}

  void OnStart(const nav::sim::Scene& scene, const nav::Pose2& start) override {
    to_start_frame_ = start.Inverse();
    if (!options_.log_path.empty()) writer_ = std::make_unique<glue::LogWriter>(options_.log_path);
    out_->log.path = options_.log_path.empty() ? "sim:" + scene.name : options_.log_path;
  }

  void OnOdometry(const odometry_t& o, const nav::Pose2& truth) override {
    SlamLog& log = out_->log;
    SlamStep s;
    s.utime = o.utime;
    s.odometry_delta = glue::OdometryDelta(o);
    log.steps.push_back(std::move(s));
    ++log.odometry;
    if (options_.on_sensor) options_.on_sensor(log.steps.back());
    out_->reference.by_time.push_back({o.utime, to_start_frame_.Compose(truth)});
    if (writer_) {
      writer_->Write(options_.odometry_channel, o);
      writer_->Write(options_.ground_truth_channel,
                     glue::ToPoseMsg(o.utime, "ground_truth", "map", truth, Eigen::Matrix3d::Zero()));
    }
  }

  void OnScan(const laser_scan_t& m) override {
    SlamLog& log = out_->log;
    // As eval::LoadSlamLog reads a scan message.
    SlamStep s;
    s.is_scan = true;
    s.utime = m.utime;
    s.points = nav::ScanToPoints(m.ranges_m, m.angle_min_rad, m.angle_increment_rad, m.range_min_m, m.range_max_m,
                                 nav::Pose2{m.sensor_x_m, m.sensor_y_m, m.sensor_theta_rad});
    s.ranges_key.assign(reinterpret_cast<const char*>(m.ranges_m.data()), m.ranges_m.size() * sizeof(float));
    if (log.beams == 0) log.beams = m.nranges;
    log.steps.push_back(std::move(s));
    ++log.scans;
    if (writer_) writer_->Write(options_.scan_channel, m);
    if (options_.on_sensor) options_.on_sensor(log.steps.back());
  }

  void OnStep(int64_t utime, const nav::sim::World& world) override {
    if (options_.on_step) options_.on_step(utime, world);
  }

  glue::LogWriter* writer() { return writer_.get(); }

 private:
  const SimSlamOptions& options_;
  SimulatedSlamLog* out_;
  nav::Pose2 to_start_frame_;
  std::unique_ptr<glue::LogWriter> writer_;
};

}  // namespace

SimulatedSlamLog SimulateSlamLog(const SimSlamOptions& options) {
  options.Validate();
  SimulatedSlamLog out;
  SlamLogSink sink(options, &out);
  const SimDriveResult drive = DriveSimulation(options, /*frames=*/nullptr, sink, "slam sim");
  out.scene_name = drive.scene_name;
  out.route = drive.route;
  out.start = drive.start;
  out.log.events = 2 * out.log.odometry + out.log.scans;  // as many as the written log holds (ground truth included)
  out.laps = drive.laps;
  out.duration_s = drive.duration_s;
  out.distance_m = drive.distance_m;
  out.collisions = drive.collisions;
  if (sink.writer()) {
    out.log_events = sink.writer()->events();
    sink.writer()->Close();
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
