#include "laser_slam_node.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <optional>
#include <vector>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/laser_scan_checks.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/glue/slam_options.hpp"
#include "snapnav/laser_slam_status_t.hpp"
#include "snapnav/nav/covariance.hpp"
#include "snapnav/point_map_t.hpp"

namespace snapnav::processes {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;

bool Finite(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }

}  // namespace

LaserSlamConfig LaserSlamConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  LaserSlamConfig c;
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.scan_channel = channel_prefix + ini.GetString("channels", "scan");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");
  c.map_channel = channel_prefix + ini.GetString("channels", "map");
  c.status_channel = channel_prefix + ini.GetString("channels", "status");
  c.correction_channel = channel_prefix + ini.GetString("channels", "correction");
  c.options = glue::ReadLaserSlamOptions(ini, "laser_slam");
  c.map_every_n_scans = ini.GetInt("laser_slam", "map_every_n_scans");
  const std::string backend = ini.GetString("laser_slam", "backend");
  const auto parsed_backend = ParseSlamBackend(backend);
  if (!parsed_backend) {
    ini.FailKey("laser_slam", "backend", "expected ekf or graph");
  }
  c.backend = *parsed_backend;
  c.graph = glue::ReadGraphSlamOptions(ini, "laser_slam");
  c.grid = GridConfig::FromIni(ini, channel_prefix);
  c.localize = LocalizeConfig::FromIni(ini, channel_prefix);
  c.localize.options.tracking = c.options;
  ini.CheckAllUsed();
  if (c.map_every_n_scans < 0)
    ini.FailKey("laser_slam", "map_every_n_scans", "must be >= 0 (0: never publish the map)");
  return c;
}

void LaserSlamConfig::Print(std::ostream& out) const {
  out << "[channels]\nodometry = " << odometry_channel << "\nscan = " << scan_channel << "\npose = " << pose_channel
      << "\nmap = " << map_channel << "\nstatus = " << status_channel
      << "\ncorrection = " << correction_channel << "\ngrid = " << grid.channel
      << "\ngrid_request = " << grid.request_channel << "\nlocalization_status = " << localize.status_channel
      << "\n[laser_slam]\n";
  glue::PrintLaserSlamOptions(out, options);
  out << "map_every_n_scans = " << map_every_n_scans << "\nbackend = " << SlamBackendName(backend) << "\n";
  glue::PrintGraphSlamOptions(out, graph);
  grid.Print(out);
  out << "[localize]\n";
  localize.Print(out);
}

LaserSlamNode::LaserSlamNode(glue::Bus& bus, const LaserSlamConfig& config)
    : bus_(bus), config_(config), problems_(bus, "laser-slam") {
  config_.options.Validate();  // throws std::invalid_argument before anything is subscribed
  config_.graph.Validate();
  bus_.Subscribe(config_.odometry_channel, &LaserSlamNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
  bus_.Subscribe(config_.scan_channel, &LaserSlamNode::OnScan, this);
  if (!config_.grid.channel.empty()) {
    grid_.emplace(bus_, config_.grid, "laser_slam", problems_);
    if (config_.backend == SlamBackend::kGraph) {
      grid_->SetKeyframePoses([this] { return graph_ ? graph_->graph().poses() : std::vector<nav::Pose2>{}; });
    }
  }
}

// Nothing leaves a handler: inputs are checked before libnav sees them, and anything else
// (a failed publish) is counted as an internal error and reported at exit.
void LaserSlamNode::OnOdometry(const odometry_t& msg) {
  problems_.Guard("odometry", [&] { HandleOdometry(msg); });
}

void LaserSlamNode::OnScan(const laser_scan_t& msg) {
  problems_.Guard("scan", [&] { HandleScan(msg); });
}

void LaserSlamNode::HandleOdometry(const odometry_t& msg) {
  ++odometry_;
  if (!odometry_seen_) {
    // The first message fixes the start; its increment is relative to a message never seen.
    if (const std::string problem = glue::OdometryStartProblem(msg); !problem.empty()) {
      Skip(Finite(msg.x_m, msg.y_m, msg.theta_rad) ? "absurd odometry" : "non-finite odometry", problem, true);
      return;
    }
    odometry_seen_ = true;
    if (!started()) Start(glue::OdometryPose(msg));
    return;
  }
  if (const std::string problem = glue::OdometryProblem(msg, false); !problem.empty()) {
    Skip(std::isfinite(msg.delta_x_m) && std::isfinite(msg.delta_y_m) && std::isfinite(msg.delta_theta_rad)
             ? "absurd odometry"
             : "non-finite odometry",
         problem, true);
    return;
  }
  if (scans_ > 0 && msg.utime < last_scan_utime_) ++late_odometry_;  // applied anyway: arrival order
  if (graph_) {
    graph_->Predict(glue::OdometryDelta(msg), msg.utime);
  } else {
    slam_->Predict(glue::OdometryDelta(msg), msg.utime);
  }
}

void LaserSlamNode::Start(const nav::Pose2& pose) {
  if (config_.backend == SlamBackend::kGraph) {
    graph_.emplace(config_.options, config_.graph, pose);
  } else {
    slam_.emplace(config_.options, pose);
  }
}

void LaserSlamNode::HandleScan(const laser_scan_t& msg) {
  ++scans_;
  // Malformed scans: counted, no update, no pose.
  if (const auto problem = glue::CheckLaserScan(msg)) {
    Skip(problem->reason, problem->detail, true);
    return;
  }
  last_scan_utime_ = msg.utime;
  if (!started()) Start(nav::Pose2{});  // no odometry yet: start at the origin

  const auto points = glue::LaserScanPoints(msg);
  std::optional<nav::LaserSlamUpdate> update;
  if (points.empty()) {
    // A well-formed scan that saw nothing (every beam NaN or no return, e.g. open space): no update,
    // the prediction stands and its pose is still published, so every well-formed scan has a pose.
    Skip("no valid points", "", false);
  } else {
    const auto t0 = std::chrono::steady_clock::now();
    if (graph_) {
      const nav::GraphSlamUpdate g = graph_->Update(points, msg.utime);
      update = g.front_end;
      if (g.corrected) last_correction_utime_ = msg.utime;
      if (grid_) {
        // The live grid follows the graph: the keyframes' scans kept, the grid rebuilt from them at
        // the optimized poses after a correction (GridPublisher).
        if (g.keyframe) grid_->AddKeyframeScan(g.anchor_keyframe, msg);
        if (g.corrected) grid_->Corrected();
      }
    } else {
      update = slam_->Update(points, msg.utime);
    }
    update_ms_total_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++updates_;
    measured_ += update->outcome == nav::MatchOutcome::kAccepted;
    gated_ += update->outcome == nav::MatchOutcome::kGated;
    wall_measured_ += update->wall_measured;
    ambiguous_ += update->outcome == nav::MatchOutcome::kAmbiguous;
    no_match_ += update->outcome == nav::MatchOutcome::kNoMatch;
  }
  bus_.Publish(config_.pose_channel, glue::ToPoseMsg(msg.utime, "laser_slam", "map", graph_ ? graph_->pose() : slam_->pose(),
                                                     graph_ ? graph_->covariance() : slam_->covariance()));
  ++poses_published_;
  if (graph_) {
    // What the published pose is relative to (its keyframe, and that keyframe's pose now), for the
    // correction tables: the graph never changes a scan's pose relative to its keyframe.
    const int k = graph_->anchor_keyframe();
    published_.Note(msg.utime, k, k >= 0 ? graph_->graph().pose(k) : nav::Pose2{});
    if (last_correction_utime_ == msg.utime && graph_->corrections() > 0) PublishCorrection(msg.utime);
  }
  PublishStatus(msg.utime, update ? &*update : nullptr);  // only what the inputs decide: a replay repeats it
  if (!points.empty() && config_.map_every_n_scans > 0 && updates_ % config_.map_every_n_scans == 0) {
    PublishMap(msg.utime);
  }
  if (grid_) {
    // The scans the point map takes (not a gated or ambiguous match), at the pose they were matched at.
    if (update && update->outcome != nav::MatchOutcome::kGated && update->outcome != nav::MatchOutcome::kAmbiguous) {
      grid_->AddScan(msg, graph_ ? graph_->scan_pose() : slam_->scan_pose());
    }
    grid_->AfterScan(msg.utime);
  }
}

void LaserSlamNode::PublishStatus(int64_t utime, const nav::LaserSlamUpdate* u) {
  laser_slam_status_t s{};
  s.utime = utime;
  s.gate_mahalanobis2 = config_.options.gate_mahalanobis2;
  if (!u) {
    s.outcome = laser_slam_status_t::NO_POINTS;
    s.prediction = laser_slam_status_t::ODOMETRY;
  } else {
    switch (u->outcome) {
      case nav::MatchOutcome::kMapStart: s.outcome = laser_slam_status_t::MAP_START; break;
      case nav::MatchOutcome::kAccepted: s.outcome = laser_slam_status_t::ACCEPTED; break;
      case nav::MatchOutcome::kGated: s.outcome = laser_slam_status_t::GATED; break;
      case nav::MatchOutcome::kAmbiguous: s.outcome = laser_slam_status_t::AMBIGUOUS; break;
      case nav::MatchOutcome::kNoMatch: s.outcome = laser_slam_status_t::NO_MATCH; break;
    }
    switch (u->prediction) {
      case nav::PredictionSource::kOdometry: s.prediction = laser_slam_status_t::ODOMETRY; break;
      case nav::PredictionSource::kStale: s.prediction = laser_slam_status_t::STALE; break;
      case nav::PredictionSource::kCatchUp: s.prediction = laser_slam_status_t::CATCH_UP; break;
    }
    s.predictions = static_cast<int8_t>(u->predictions);
    s.widened = u->widened;
    s.mahalanobis2 = u->mahalanobis2;
    s.ambiguity = u->ambiguity;
    s.fit = u->fit;
    s.kernel = u->kernel;
    s.points = u->points;
    s.matches = u->matches;
    s.coasting_scans = u->coasting;
    s.wall_measured = u->wall_measured;
    s.wall_gated = u->wall_gated;
    s.wall_offset_deg = u->wall_offset_rad * kDegPerRad;
    s.wall_contrast = u->wall_contrast;
  }
  s.wall_measurements = wall_measured_;
  if (const nav::LaserSlam* f = slam()) {
    const nav::OdometryCalibration& c = f->odometry_calibration();
    s.odometry_drift_deg_per_m = c.drift_rad_per_m() * kDegPerRad;
    s.odometry_turn_scale = c.turn_scale();
    s.odometry_distance_scale = c.distance_scale();
    s.odometry_stretches = c.observations();
    s.odometry_calibration_applied = config_.options.odometry_calibration.apply && !graph_;
  }
  if (graph_) {
    s.backend = laser_slam_status_t::BACKEND_GRAPH;
    s.keyframes = graph_->keyframes();
    s.loop_candidates = graph_->loop_candidates();
    s.loop_accepted = graph_->loop_accepted();
    s.loop_rejected = graph_->loop_rejected();
    s.corrections = graph_->corrections();
    s.corrected = graph_->corrections() > 0 && last_correction_utime_ == utime;
    s.correction_m = graph_->last_correction_m();
    s.correction_deg = graph_->last_correction_rad() * kDegPerRad;
    s.correction_utime = last_correction_utime_;
  } else {
    s.backend = laser_slam_status_t::BACKEND_EKF;
  }
  const Eigen::Matrix3d& p = slam()->covariance();
  s.position_sigma_m = nav::PositionSigmaM(p);
  s.heading_sigma_deg = std::sqrt(std::max(0.0, p(2, 2))) * kDegPerRad;
  s.scans = scans_;
  s.accepted = measured_;
  s.gated = gated_;
  s.ambiguous = ambiguous_;
  s.no_match = no_match_;
  s.map_points = static_cast<int32_t>(graph_ ? graph_->Map().size() : slam_->map().size());
  bus_.Publish(config_.status_channel, s);
}

void LaserSlamNode::PublishCorrection(int64_t utime) {
  const nav::PoseCorrectionTable table =
      published_.Table([this](int k) { return graph_->graph().pose(k); });
  bus_.Publish(config_.correction_channel,
               glue::ToPoseCorrectionMsg(utime, config_.pose_channel, graph_->corrections(), table));
  ++corrections_published_;
}

void LaserSlamNode::PublishMap(int64_t utime) {
  // The graph back end's map: the optimized keyframes' points (GraphSlam::Map).
  const std::vector<Eigen::Vector2d>& points = graph_ ? graph_->Map() : slam_->map().points();
  bus_.Publish(config_.map_channel, glue::ToPointMapMsg(utime, "laser_slam", slam()->map().resolution_m(), points));
  ++maps_published_;
}

void LaserSlamNode::Report(std::ostream& out) const {
  out << "laser-slam: scans " << scans_ << ", updates " << updates_ << ", accepted " << measured_ << ", gated "
      << gated_ << ", ambiguous " << ambiguous_ << ", no match " << no_match_ << ", odometry "
      << odometry_ << " (late " << late_odometry_ << "), poses published " << poses_published_ << ", maps published "
      << maps_published_ << ", skipped " << problems_.skipped_total() << ", internal errors " << problems_.internal_errors() << "\n";
  out << "laser-slam: mean update " << mean_update_ms() << " ms per scan";
  if (slam_) out << ", map " << slam_->map().size() << " points";
  if (!graph_ && config_.options.wall_orientation) out << ", heading measured by the walls on " << wall_measured_ << " scans";
  if (graph_) {
    out << ", graph back end: " << graph_->keyframes() << " keyframes (" << graph_->keyframe_reuses()
        << " due but reused), loop closures " << graph_->loop_accepted()
        << " accepted / " << graph_->loop_rejected() << " rejected of " << graph_->loop_candidates()
        << " candidates, " << graph_->corrections() << " corrections (" << corrections_published_
        << " tables of published poses, " << published_.ranges() << " ranges), map " << graph_->Map().size() << " points";
  }
  out << "\n";
  if (const nav::LaserSlam* s = slam(); s && s->odometry_calibration().observations() > 0) {
    // Odometry's systematic errors as the matches calibrate them (odometry_calibration applies them).
    const nav::OdometryCalibration& c = s->odometry_calibration();
    char line[200];
    std::snprintf(line, sizeof line,
                  "laser-slam: odometry as the scans calibrate it: heading drift %+.2f deg/m, turn scale %+.1f %%, "
                  "distance scale %+.1f %% (%d stretches; %s)\n",
                  c.drift_rad_per_m() / nav::kRadPerDeg, 100 * c.turn_scale(), 100 * c.distance_scale(), c.observations(),
                  config_.options.odometry_calibration.apply && !graph_ ? "applied" : "not applied");
    out << line;
  }
  if (grid_) {
    out << "laser-slam: ";
    grid_->Report(out);
  }
  problems_.Report(out);
}

}  // namespace snapnav::processes
