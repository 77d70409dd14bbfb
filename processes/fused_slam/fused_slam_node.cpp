#include "fused_slam_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>

#include "snapnav/glue/slam_options.hpp"
#include "snapnav/fused_slam_status_t.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/laser_scan_checks.hpp"
#include "snapnav/glue/message_clock.hpp"
#include "snapnav/point_map_t.hpp"

namespace snapnav::processes {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;
constexpr char kEstimator[] = "fused_slam";
constexpr char kFrame[] = "map";

bool Finite(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }

// Why a finite visual covariance with non-negative variances cannot be one, or "": it must be
// positive semi-definite (up to rounding), a position std. dev. within glue::kMaxPositionM and a
// heading std. dev. within glue::kMaxOdometryStepRad (larger ones overflow the filter's products).
std::string CovarianceProblem(const Eigen::Matrix3d& r) {
  const double max_xy = glue::kMaxPositionM * glue::kMaxPositionM;
  const double max_theta = glue::kMaxOdometryStepRad * glue::kMaxOdometryStepRad;
  if (r(0, 0) > max_xy || r(1, 1) > max_xy || r(2, 2) > max_theta) return "a variance beyond its bound";
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(0.5 * (r + r.transpose()), Eigen::EigenvaluesOnly);
  if (eig.eigenvalues().minCoeff() < -1e-9 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
    return "not positive semi-definite";
  }
  return "";
}

double Ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

const char* FusedStartName(FusedStart start) { return start == FusedStart::kOdometry ? "odometry" : "visual"; }

FusedSlamConfig FusedSlamConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  FusedSlamConfig c;
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.scan_channel = channel_prefix + ini.GetString("channels", "scan");
  c.visual_channel = channel_prefix + ini.GetString("channels", "visual");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");
  c.map_channel = channel_prefix + ini.GetString("channels", "map");
  c.status_channel = channel_prefix + ini.GetString("channels", "status");
  nav::FusedSlamOptions& o = c.options;
  o.laser = glue::ReadLaserSlamOptions(ini, "laser_slam");
  const char* s = "fused_slam";
  c.start = glue::ReadChoice<FusedStart>(ini, s, "start", {{"odometry", FusedStart::kOdometry}, {"visual", FusedStart::kVisual}});
  o.gate_chi2 = ini.GetDouble(s, "gate_chi2");
  o.agree_chi2 = ini.GetDouble(s, "agree_chi2");
  o.relocalize_after = ini.GetInt(s, "relocalize_after");
  o.relocalize_sigma_xy_m = ini.GetDouble(s, "relocalize_sigma_xy_m");
  o.relocalize_sigma_theta_rad = ini.GetDouble(s, "relocalize_sigma_theta_deg") / kDegPerRad;
  o.min_fix_sigma_xy_m = ini.GetDouble(s, "min_fix_sigma_xy_m");
  o.min_fix_sigma_theta_rad = ini.GetDouble(s, "min_fix_sigma_theta_deg") / kDegPerRad;
  o.max_fix_age_s = ini.GetDouble(s, "max_fix_age_s");
  o.relocalize_window_s = ini.GetDouble(s, "relocalize_window_s");
  o.relocalize_max_fit_loss = ini.GetDouble(s, "relocalize_max_fit_loss");
  o.relocalize_min_distance_m = ini.GetDouble(s, "relocalize_min_distance_m");
  o.relocalize_min_heading_rad = ini.GetDouble(s, "relocalize_min_heading_deg") / kDegPerRad;
  o.suspect_after = ini.GetInt(s, "suspect_after");
  o.start_sigma_xy_m = ini.GetDouble(s, "start_sigma_xy_m");
  o.start_sigma_theta_rad = ini.GetDouble(s, "start_sigma_theta_deg") / kDegPerRad;
  o.map_cell_m = ini.GetDouble(s, "map_cell_m");
  o.map_drift_xy_m = ini.GetDouble(s, "map_drift_xy_m");
  o.map_drift_theta_rad = ini.GetDouble(s, "map_drift_theta_deg") / kDegPerRad;
  o.map_drift_accumulates = ini.GetBool(s, "map_drift_accumulates");
  o.map_min_fit = ini.GetDouble(s, "map_min_fit");
  o.dynamic_explain_m = ini.GetDouble(s, "dynamic_explain_m");
  o.dynamic_max_behind_m = ini.GetDouble(s, "dynamic_max_behind_m");
  o.dynamic_max_fraction = ini.GetDouble(s, "dynamic_max_fraction");
  o.dynamic_map_age_s = ini.GetDouble(s, "dynamic_map_age_s");
  o.occlusion_fix_inflation = ini.GetDouble(s, "occlusion_fix_inflation");
  o.laser_min_constraint = ini.GetDouble(s, "laser_min_constraint");
  o.map_inherits_laser_drift = ini.GetBool(s, "map_inherits_laser_drift");
  o.fix_correlation_m = ini.GetDouble(s, "fix_correlation_m");
  c.map_every_n_scans = ini.GetInt(s, "map_every_n_scans");
  c.status_every_n_scans = ini.GetInt(s, "status_every_n_scans");
  ini.CheckAllUsed();
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  if (c.map_every_n_scans < 0) ini.FailKey("fused_slam", "map_every_n_scans", "must be >= 0");
  if (c.status_every_n_scans < 0) ini.FailKey("fused_slam", "status_every_n_scans", "must be >= 0");
  return c;
}

void FusedSlamConfig::Print(std::ostream& out) const {
  const nav::FusedSlamOptions& o = options;
  out << "[channels]\nodometry = " << odometry_channel << "\nscan = " << scan_channel << "\nvisual = " << visual_channel
      << "\npose = " << pose_channel << "\nmap = " << map_channel << "\nstatus = " << status_channel << "\n[laser_slam]\n";
  glue::PrintLaserSlamOptions(out, o.laser);
  out << "[fused_slam]\nstart = " << FusedStartName(start) << "\ngate_chi2 = " << o.gate_chi2
      << "\nagree_chi2 = " << o.agree_chi2 << "\nrelocalize_after = " << o.relocalize_after
      << "\nrelocalize_sigma_xy_m = " << o.relocalize_sigma_xy_m
      << "\nrelocalize_sigma_theta_deg = " << o.relocalize_sigma_theta_rad * kDegPerRad
      << "\nmin_fix_sigma_xy_m = " << o.min_fix_sigma_xy_m
      << "\nmin_fix_sigma_theta_deg = " << o.min_fix_sigma_theta_rad * kDegPerRad << "\nmax_fix_age_s = " << o.max_fix_age_s
      << "\nrelocalize_window_s = " << o.relocalize_window_s
      << "\nrelocalize_max_fit_loss = " << o.relocalize_max_fit_loss
      << "\nrelocalize_min_distance_m = " << o.relocalize_min_distance_m
      << "\nrelocalize_min_heading_deg = " << o.relocalize_min_heading_rad * kDegPerRad
      << "\nsuspect_after = " << o.suspect_after << "\nstart_sigma_xy_m = " << o.start_sigma_xy_m
      << "\nstart_sigma_theta_deg = " << o.start_sigma_theta_rad * kDegPerRad << "\nmap_cell_m = " << o.map_cell_m
      << "\nmap_drift_xy_m = " << o.map_drift_xy_m << "\nmap_drift_theta_deg = " << o.map_drift_theta_rad * kDegPerRad
      << "\nmap_drift_accumulates = " << (o.map_drift_accumulates ? "true" : "false")
      << "\nmap_min_fit = " << o.map_min_fit << "\ndynamic_explain_m = " << o.dynamic_explain_m
      << "\ndynamic_max_behind_m = " << o.dynamic_max_behind_m << "\ndynamic_max_fraction = " << o.dynamic_max_fraction
      << "\ndynamic_map_age_s = " << o.dynamic_map_age_s
      << "\nocclusion_fix_inflation = " << o.occlusion_fix_inflation
      << "\nlaser_min_constraint = " << o.laser_min_constraint
      << "\nmap_inherits_laser_drift = " << (o.map_inherits_laser_drift ? "true" : "false")
      << "\nfix_correlation_m = " << o.fix_correlation_m
      << "\nmap_every_n_scans = " << map_every_n_scans << "\nstatus_every_n_scans = " << status_every_n_scans << "\n";
}

FusedSlamNode::FusedSlamNode(glue::Bus& bus, const FusedSlamConfig& config)
    : bus_(bus), config_(config), problems_(bus, "fused-slam") {
  config_.options.Validate();  // throws std::invalid_argument before anything is subscribed
  bus_.Subscribe(config_.odometry_channel, &FusedSlamNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
  bus_.Subscribe(config_.scan_channel, &FusedSlamNode::OnScan, this);
  bus_.Subscribe(config_.visual_channel, &FusedSlamNode::OnVisual, this);
}

// Nothing leaves a handler: inputs are checked before libnav sees them, and anything else
// (a failed publish) is counted as an internal error and reported at exit.
void FusedSlamNode::OnOdometry(const odometry_t& msg) {
  problems_.Guard("odometry", [&] { HandleOdometry(msg); });
}

void FusedSlamNode::OnScan(const laser_scan_t& msg) {
  problems_.Guard("scan", [&] { HandleScan(msg); });
}

void FusedSlamNode::OnVisual(const pose_t& msg) {
  problems_.Guard("visual", [&] { HandleVisual(msg); });
}

void FusedSlamNode::HandleOdometry(const odometry_t& msg) {
  ++odometry_;
  // The first message fixes the start (its cumulative pose); its increment is relative to a
  // message never seen. Later ones: the increment, within glue's bounds.
  const std::string problem = odometry_seen_ ? glue::OdometryProblem(msg, false) : glue::OdometryStartProblem(msg);
  if (!problem.empty()) {
    const bool finite = odometry_seen_ ? Finite(msg.delta_x_m, msg.delta_y_m, msg.delta_theta_rad)
                                       : Finite(msg.x_m, msg.y_m, msg.theta_rad);
    Skip(finite ? "absurd odometry" : "non-finite odometry", problem, true);
    return;
  }
  // The filter keeps odometry by time for late visual measurements: times in order, and one
  // absurd stamp cannot block it (glue::MessageClock).
  switch (odometry_clock_.Check(msg.utime)) {
    case glue::MessageClock::Verdict::kImplausible:
      Skip("implausible utime", "odometry at utime " + std::to_string(msg.utime), true);
      return;
    case glue::MessageClock::Verdict::kBackInTime:
      Skip("odometry back in time", "utime " + std::to_string(msg.utime) + " after " +
                                        std::to_string(*odometry_clock_.last()), true);
      return;
    case glue::MessageClock::Verdict::kRestarted:
      // The filter's odometry history is in the old time: start it again at its pose and
      // covariance (its map starts afresh).
      std::cerr << "fused-slam: odometry time restarted at utime " << msg.utime
                << (slam_ ? "; the filter restarts at its pose, with a new map" : "") << "\n";
      if (slam_) {
        const nav::Pose2 pose = slam_->pose();
        const Eigen::Matrix3d covariance = slam_->covariance();
        slam_.emplace(config_.options, pose, covariance);
      }
      ++time_restarts_;
      break;
    case glue::MessageClock::Verdict::kAccepted:
      break;
  }
  if (!odometry_seen_) {
    odometry_seen_ = true;
    if (!slam_ && config_.start == FusedStart::kOdometry) slam_.emplace(config_.options, glue::OdometryPose(msg));
    return;
  }
  if (!slam_) {
    Skip("waiting for a visual fix", "", false);
    return;
  }
  slam_->Predict(msg.utime, glue::OdometryDelta(msg));
}

void FusedSlamNode::HandleScan(const laser_scan_t& msg) {
  ++scans_;
  if (const auto problem = glue::CheckLaserScan(msg)) {
    Skip(problem->reason, problem->detail, true);
    return;
  }
  if (!slam_) {
    if (config_.start == FusedStart::kVisual) {
      Skip("waiting for a visual fix", "", false);
      return;
    }
    slam_.emplace(config_.options, nav::Pose2{});  // no odometry yet: start at the origin
  }
  const auto points = glue::LaserScanPoints(msg);
  if (points.empty()) {
    // Saw nothing: no update, the prediction stands and its pose is still published.
    Skip("no valid points", "", false);
  } else {
    const auto t0 = std::chrono::steady_clock::now();
    const nav::LaserSlamUpdate u = slam_->Update(points);
    scan_ms_total_ += Ms(t0);
    last_fit_ = u.fit;
    ++updates_;
  }
  PublishPose(msg.utime, slam_->pose());
  if (!points.empty() && config_.map_every_n_scans > 0 && updates_ % config_.map_every_n_scans == 0) {
    PublishMap(msg.utime);
  }
  if (config_.status_every_n_scans > 0 && scans_ % config_.status_every_n_scans == 0) PublishStatus(msg.utime);
}

void FusedSlamNode::HandleVisual(const pose_t& msg) {
  ++visual_;
  if (!glue::PlausibleUtime(msg.utime)) {  // the filter takes time differences with it
    Skip("implausible utime", "visual pose at utime " + std::to_string(msg.utime), true);
    return;
  }
  if (!Finite(msg.x_m, msg.y_m, msg.theta_rad)) {
    Skip("non-finite visual pose", "x_m, y_m or theta_rad is not finite", true);
    return;
  }
  if (std::abs(msg.x_m) > glue::kMaxPositionM || std::abs(msg.y_m) > glue::kMaxPositionM) {
    // A relocalisation there would build the map beyond its integer cells.
    Skip("absurd visual pose", "(" + std::to_string(msg.x_m) + ", " + std::to_string(msg.y_m) + ") m", true);
    return;
  }
  const Eigen::Matrix3d r = glue::CovarianceOf(msg);
  if (!r.allFinite() || r(0, 0) < 0 || r(1, 1) < 0 || r(2, 2) < 0) {
    Skip("bad visual covariance", "not finite or a negative variance", true);
    return;
  }
  if (r.isZero()) {
    Skip("visual pose without covariance", "", false);  // pose_t: all zero = unknown
    return;
  }
  if (const std::string problem = CovarianceProblem(r); !problem.empty()) {
    Skip("bad visual covariance", problem, true);
    return;
  }
  const nav::Pose2 z = glue::FromPoseMsg(msg);
  const auto t0 = std::chrono::steady_clock::now();
  if (!slam_) {
    if (config_.start == FusedStart::kOdometry) {
      Skip("visual before odometry", "", false);
      return;
    }
    // start = visual: the filter starts at the first fix, its covariance floored.
    Eigen::Matrix3d p = 0.5 * (r + r.transpose());
    const double fp = config_.options.min_fix_sigma_xy_m, fh = config_.options.min_fix_sigma_theta_rad;
    p(0, 0) = std::max(p(0, 0), fp * fp);
    p(1, 1) = std::max(p(1, 1), fp * fp);
    p(2, 2) = std::max(p(2, 2), fh * fh);
    slam_.emplace(config_.options, z, p);
    visual_ms_total_ += Ms(t0);
    ++visual_used_;
    last_outcome_ = fused_slam_status_t::ACCEPTED;
    last_mahalanobis2_ = 0;
    PublishPose(msg.utime, slam_->pose());
    PublishStatus(msg.utime);
    return;
  }
  const nav::VisualUpdate v = slam_->AddVisual(msg.utime, z, r);
  visual_ms_total_ += Ms(t0);
  ++visual_used_;
  last_mahalanobis2_ = v.mahalanobis2;
  switch (v.outcome) {
    case nav::VisualOutcome::kAccepted: last_outcome_ = fused_slam_status_t::ACCEPTED; break;
    case nav::VisualOutcome::kRejected: last_outcome_ = fused_slam_status_t::REJECTED; break;
    case nav::VisualOutcome::kRelocalized: last_outcome_ = fused_slam_status_t::RELOCALIZED; break;
    case nav::VisualOutcome::kStale: last_outcome_ = fused_slam_status_t::STALE; break;
  }
  if (v.outcome == nav::VisualOutcome::kRelocalized) {
    std::cerr << "fused-slam: relocalised to (" << slam_->pose().x_m << ", " << slam_->pose().y_m << ", "
              << slam_->pose().theta_rad * kDegPerRad << " deg) after " << config_.options.relocalize_after
              << " agreeing visual measurements beyond the gate\n";
  }
  // The pose at the measurement's time (unknown for a stale one).
  if (const auto at = slam_->PoseAt(msg.utime)) PublishPose(msg.utime, *at);
  PublishStatus(msg.utime);
}

void FusedSlamNode::PublishPose(int64_t utime, const nav::Pose2& pose) {
  bus_.Publish(config_.pose_channel, glue::ToPoseMsg(utime, kEstimator, kFrame, pose, slam_->covariance()));
  ++poses_published_;
}

void FusedSlamNode::PublishMap(int64_t utime) {
  bus_.Publish(config_.map_channel,
               glue::ToPointMapMsg(utime, kEstimator, slam_->map().resolution_m(), slam_->WorldMapPoints()));
  ++maps_published_;
}

void FusedSlamNode::PublishStatus(int64_t utime) {
  fused_slam_status_t s{};
  s.utime = utime;
  s.last_outcome = last_outcome_;
  s.last_mahalanobis2 = last_mahalanobis2_;
  s.last_fit = last_fit_;
  s.scans = updates_;
  if (!slam_) {
    s.state = fused_slam_status_t::WAITING;
  } else {
    const nav::FusedSlam& f = *slam_;
    s.state = f.suspect() ? fused_slam_status_t::SUSPECT : fused_slam_status_t::TRACKING;
    s.consecutive_rejections = f.consecutive_rejections();
    s.agreeing_rejections = f.agreeing_rejections();
    s.visual_accepted = f.accepted();
    s.visual_rejected = f.rejected();
    s.relocalizations = f.relocalizations();
    s.relocalizations_refused = f.refused_relocalizations();
    s.visual_stale = f.stale();
    s.unmapped_scans = f.unmapped_scans();
    s.map_points = static_cast<int32_t>(f.map().size());
    s.x_m = f.pose().x_m;
    s.y_m = f.pose().y_m;
    s.theta_rad = f.pose().theta_rad;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(f.covariance().topLeftCorner<2, 2>());
    s.position_sigma_m = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
  }
  bus_.Publish(config_.status_channel, s);
  ++statuses_published_;
}

void FusedSlamNode::Report(std::ostream& out) const {
  out << "fused-slam: scans " << scans_ << ", updates " << updates_ << ", odometry " << odometry_ << ", visual "
      << visual_ << " (used " << visual_used_ << "), poses published " << poses_published_ << ", maps published "
      << maps_published_ << ", statuses published " << statuses_published_ << ", skipped " << problems_.skipped_total()
      << ", internal errors " << problems_.internal_errors();
  if (time_restarts_ > 0) out << ", odometry time restarts " << time_restarts_;
  out << "\n";
  if (slam_) {
    const nav::FusedSlam& f = *slam_;
    out << "fused-slam: visual measurements accepted " << f.accepted() << ", rejected " << f.rejected()
        << ", relocalisations " << f.relocalizations() << " (refused " << f.refused_relocalizations() << "), stale "
        << f.stale() << "; unmapped scans "
        << f.unmapped_scans() << ", map " << f.map().size() << " points\n";
  }
  out << "fused-slam: mean " << mean_scan_ms() << " ms per scan, " << mean_visual_ms() << " ms per visual measurement\n";
  problems_.Report(out);
}

}  // namespace snapnav::processes
