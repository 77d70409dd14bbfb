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
#include "snapnav/nav/covariance.hpp"
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

namespace {

// The [fused_slam] keys, declared once: read, printed and described from here ([laser_slam] is
// glue::LaserSlamOptionTable).
const glue::OptionTable<FusedSlamConfig>& FusedSlamTable() {
  using C = FusedSlamConfig;
  static const auto table = glue::OptionTable<C>()
      .Choice("start", &C::start, {FusedStart::kOdometry, FusedStart::kVisual}, FusedStartName)
      .Number("gate_chi2", "", [](auto& o) -> auto& { return o.options.gate_chi2; })
      .Number("agree_chi2", "", [](auto& o) -> auto& { return o.options.agree_chi2; })
      .Number("relocalize_after", "", [](auto& o) -> auto& { return o.options.relocalize_after; })
      .Number("relocalize_sigma_xy_m", "m", [](auto& o) -> auto& { return o.options.relocalize_sigma_xy_m; })
      .Degrees("relocalize_sigma_theta_deg", [](auto& o) -> auto& { return o.options.relocalize_sigma_theta_rad; })
      .Number("min_fix_sigma_xy_m", "m", [](auto& o) -> auto& { return o.options.min_fix_sigma_xy_m; })
      .Degrees("min_fix_sigma_theta_deg", [](auto& o) -> auto& { return o.options.min_fix_sigma_theta_rad; })
      .Number("max_fix_age_s", "s", [](auto& o) -> auto& { return o.options.max_fix_age_s; })
      .Number("relocalize_window_s", "s", [](auto& o) -> auto& { return o.options.relocalize_window_s; })
      .Number("relocalize_max_fit_loss", "", [](auto& o) -> auto& { return o.options.relocalize_max_fit_loss; })
      .Flag("relocalize_net_of_accepted", [](auto& o) -> auto& { return o.options.relocalize_net_of_accepted; })
      .Number("relocalize_min_distance_m", "m", [](auto& o) -> auto& { return o.options.relocalize_min_distance_m; })
      .Degrees("relocalize_min_heading_deg", [](auto& o) -> auto& { return o.options.relocalize_min_heading_rad; })
      .Number("suspect_after", "", [](auto& o) -> auto& { return o.options.suspect_after; })
      .Number("start_sigma_xy_m", "m", [](auto& o) -> auto& { return o.options.start_sigma_xy_m; })
      .Degrees("start_sigma_theta_deg", [](auto& o) -> auto& { return o.options.start_sigma_theta_rad; })
      .Number("map_cell_m", "m", [](auto& o) -> auto& { return o.options.map_cell_m; })
      .Number("map_drift_xy_m", "m", [](auto& o) -> auto& { return o.options.map_drift_xy_m; })
      .Degrees("map_drift_theta_deg", [](auto& o) -> auto& { return o.options.map_drift_theta_rad; })
      .Flag("map_drift_accumulates", [](auto& o) -> auto& { return o.options.map_drift_accumulates; })
      .Number("map_min_fit", "", [](auto& o) -> auto& { return o.options.map_min_fit; })
      .Number("dynamic_explain_m", "m", [](auto& o) -> auto& { return o.options.dynamic_explain_m; })
      .Number("dynamic_max_behind_m", "m", [](auto& o) -> auto& { return o.options.dynamic_max_behind_m; })
      .Number("dynamic_max_fraction", "", [](auto& o) -> auto& { return o.options.dynamic_max_fraction; })
      .Number("dynamic_map_age_s", "s", [](auto& o) -> auto& { return o.options.dynamic_map_age_s; })
      .Number("occlusion_fix_inflation", "", [](auto& o) -> auto& { return o.options.occlusion_fix_inflation; })
      .Number("laser_min_constraint", "", [](auto& o) -> auto& { return o.options.laser_min_constraint; })
      .Flag("map_inherits_laser_drift", [](auto& o) -> auto& { return o.options.map_inherits_laser_drift; })
      .Number("fix_correlation_m", "m", [](auto& o) -> auto& { return o.options.fix_correlation_m; })
      .Number("map_every_n_scans", "", &C::map_every_n_scans)
      .Number("status_every_n_scans", "", &C::status_every_n_scans);
  return table;
}

}  // namespace

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
  FusedSlamTable().Read(ini, "fused_slam", &c);
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
  out << "[fused_slam]\n";
  FusedSlamTable().Print(out, *this);
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
    s.position_sigma_m = nav::PositionSigmaM(f.covariance());
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
