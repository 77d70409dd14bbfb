#include "snapnav/nav/fused_slam.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

namespace snapnav::nav {
namespace {

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("fused slam: " + what);
}

bool Finite(const Pose2& p) { return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad); }

Eigen::Vector3d Difference(const Pose2& a, const Pose2& b) {  // a - b, angle wrapped
  return {a.x_m - b.x_m, a.y_m - b.y_m, WrapAngle(a.theta_rad - b.theta_rad)};
}

// y^T (p + r)^-1 y.
double Mahalanobis2(const Eigen::Vector3d& y, const Eigen::Matrix3d& p, const Eigen::Matrix3d& r) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(p + r);
  return y.dot(ldlt.solve(y));
}

Eigen::Matrix3d InitialCovariance(const LaserSlamOptions& o) {
  const double sxy = o.initial_sigma_xy_m * o.initial_sigma_xy_m, st = o.initial_sigma_theta_rad * o.initial_sigma_theta_rad;
  return Eigen::Vector3d(sxy, sxy, st).asDiagonal();
}

}  // namespace

const char* VisualOutcomeName(VisualOutcome outcome) {
  switch (outcome) {
    case VisualOutcome::kAccepted: return "accepted";
    case VisualOutcome::kRejected: return "rejected";
    case VisualOutcome::kRelocalized: return "relocalized";
    case VisualOutcome::kStale: return "stale";
  }
  return "?";
}

void FusedSlamOptions::Validate() const {
  laser.Validate();
  Require(gate_chi2 > 0 && std::isfinite(gate_chi2), "gate_chi2 must be positive");
  Require(agree_chi2 > 0 && std::isfinite(agree_chi2), "agree_chi2 must be positive");
  Require(relocalize_after >= 0, "relocalize_after must be >= 0 (0: never)");
  Require(relocalize_sigma_xy_m >= 0 && relocalize_sigma_theta_rad >= 0 && std::isfinite(relocalize_sigma_xy_m) &&
              std::isfinite(relocalize_sigma_theta_rad),
          "relocalize sigmas must be >= 0");
  Require(min_fix_sigma_xy_m > 0 && min_fix_sigma_theta_rad > 0 && std::isfinite(min_fix_sigma_xy_m) &&
              std::isfinite(min_fix_sigma_theta_rad),
          "min_fix sigmas must be positive");
  Require(max_fix_age_s > 0 && std::isfinite(max_fix_age_s), "max_fix_age_s must be positive");
  Require(relocalize_window_s > 0 && std::isfinite(relocalize_window_s), "relocalize_window_s must be positive");
  Require(relocalize_min_distance_m >= 0 && relocalize_min_heading_rad >= 0, "relocalize minimum jumps must be >= 0");
  Require(relocalize_max_fit_loss >= 0 && relocalize_max_fit_loss <= 1, "relocalize_max_fit_loss must be in [0, 1]");
  Require(suspect_after >= 0, "suspect_after must be >= 0 (0: never)");
  Require(map_min_fit >= 0 && map_min_fit <= 1, "map_min_fit must be in [0, 1]");
  Require(map_cell_m >= 0 && std::isfinite(map_cell_m), "map_cell_m must be >= 0 (0: off)");
  Require(map_drift_xy_m >= 0 && map_drift_theta_rad >= 0 && std::isfinite(map_drift_xy_m) &&
              std::isfinite(map_drift_theta_rad),
          "map drift must be >= 0");
  Require(laser_sigma_xy_m >= 0 && laser_sigma_theta_rad >= 0 && std::isfinite(laser_sigma_xy_m) &&
              std::isfinite(laser_sigma_theta_rad),
          "laser sigmas must be >= 0");
}

FusedSlam::FusedSlam(const FusedSlamOptions& options, const Pose2& start)
    : FusedSlam(options, start, InitialCovariance(options.laser)) {}

FusedSlam::FusedSlam(const FusedSlamOptions& options, const Pose2& start, const Eigen::Matrix3d& covariance)
    : options_(options), laser_((options.Validate(), options.laser), start) {
  Require(Finite(start) && covariance.allFinite(), "start pose or covariance is not finite");
  laser_.ResetPose(start, covariance);
  laser_.SetMapping(true, options_.map_min_fit);
}

void FusedSlam::Predict(int64_t utime, const Pose2& delta) {
  laser_.Predict(delta);  // throws on a non-finite increment before anything changes
  travelled_since_scan_m_ += std::hypot(delta.x_m, delta.y_m);
  if (hypothesis_) PredictWithOdometry(options_.laser.motion, delta, &hypothesis_->pose, &hypothesis_->covariance);
  for (auto& e : rejected_window_) PredictWithOdometry(options_.laser.motion, delta, &e.pose, &e.covariance);
  if (!have_time_ || utime > utime_) utime_ = utime;
  have_time_ = true;
  history_.emplace_back(utime, delta);
  const int64_t keep_from = utime_ - static_cast<int64_t>(std::llround(options_.max_fix_age_s * 1e6));
  while (!history_.empty() && history_.front().first < keep_from) history_.pop_front();
  const int64_t window_from = utime_ - static_cast<int64_t>(std::llround(options_.relocalize_window_s * 1e6));
  while (!rejected_window_.empty() && rejected_window_.front().utime < window_from) rejected_window_.pop_front();
}

bool FusedSlam::suspect() const {
  return options_.suspect_after > 0 && consecutive_rejections_ >= options_.suspect_after;
}

uint64_t FusedSlam::CellKey(const Eigen::Vector2d& p) const {
  const int64_t ix = static_cast<int64_t>(std::floor(p.x() / options_.map_cell_m));
  const int64_t iy = static_cast<int64_t>(std::floor(p.y() / options_.map_cell_m));
  return (static_cast<uint64_t>(ix) << 32) ^ (static_cast<uint64_t>(iy) & 0xffffffffULL);
}

namespace {

constexpr size_t kMapSamples = 64;  // scan points looked at for the map uncertainty and the relocalisation fit
constexpr double kCoverageM = 1.0;  // a scan point is judged by the map if a map point is this close [m]
constexpr double kMinJudged = 0.3;  // the fits are compared when this share of the points is judged at both poses

}  // namespace

bool FusedSlam::MapCovariance(const Pose2& pose, const std::vector<Eigen::Vector2d>& points,
                              Eigen::Matrix3d* out) const {
  const size_t stride = std::max<size_t>(1, points.size() / kMapSamples);
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  int n = 0;
  for (size_t i = 0; i < points.size(); i += stride) {
    const auto it = map_covariance_.find(CellKey(pose.Transform(points[i])));
    if (it == map_covariance_.end()) continue;
    sum += it->second;
    ++n;
  }
  if (n == 0) return false;
  *out = sum / n;
  return true;
}

void FusedSlam::RecordMapCovariance(const Pose2& pose, const std::vector<Eigen::Vector2d>& points,
                                    const Eigen::Matrix3d& covariance) {
  const size_t stride = std::max<size_t>(1, points.size() / kMapSamples);
  for (size_t i = 0; i < points.size(); i += stride) map_covariance_.emplace(CellKey(pose.Transform(points[i])), covariance);
}

std::optional<Eigen::Matrix3d> FusedSlam::MapCovarianceAt(const Eigen::Vector2d& p) const {
  if (options_.map_cell_m <= 0) return std::nullopt;
  const auto it = map_covariance_.find(CellKey(p));
  if (it == map_covariance_.end()) return std::nullopt;
  return it->second;
}

double FusedSlam::ScanFit(const Pose2& pose, double* judged) const {
  *judged = 0;
  if (last_points_.empty()) return 0;
  const double near = 2 * options_.laser.point_sigma_m;
  int covered = 0, close = 0;
  for (const auto& p : last_points_) {
    const Eigen::Vector2d w = pose.Transform(p);
    const int i = laser_.map().NearestIndex(w, kCoverageM);
    if (i < 0) continue;  // the map has nothing there: no evidence either way
    ++covered;
    if ((laser_.map().points()[static_cast<size_t>(i)] - w).norm() <= near) ++close;
  }
  *judged = static_cast<double>(covered) / static_cast<double>(last_points_.size());
  return covered > 0 ? static_cast<double>(close) / covered : 0.0;
}

LaserSlamUpdate FusedSlam::Update(const std::vector<Eigen::Vector2d>& points_robot) {
  {
    // A sample of the scan, for judging a relocalisation.
    last_points_.clear();
    const size_t stride = std::max<size_t>(1, points_robot.size() / kMapSamples);
    for (size_t i = 0; i < points_robot.size(); i += stride) last_points_.push_back(points_robot[i]);
  }
  laser_.SetMapping(!suspect(), options_.map_min_fit);
  const bool map_empty = laser_.map().size() == 0;
  const bool map_uncertainty = options_.map_cell_m > 0;
  // The scan's own error: ICP's covariance is far too certain (one scan against the map).
  const double sxy = options_.laser_sigma_xy_m, st = options_.laser_sigma_theta_rad;
  const Eigen::Matrix3d own = Eigen::Vector3d(sxy * sxy, sxy * sxy, st * st).asDiagonal();
  Eigen::Matrix3d map_p = Eigen::Matrix3d::Zero();
  const bool anchored = map_uncertainty && MapCovariance(pose(), points_robot, &map_p);
  const Eigen::Matrix3d prior = covariance();
  laser_.SetMeasurementInflation(own + map_p);
  const LaserSlamUpdate u = laser_.Update(points_robot);
  if (anchored && u.measured) {
    // Matched to the map, the pose is not more certain than the map plus the scan's own error
    // (nor than it was before).
    Eigen::Matrix3d p = covariance();
    bool raised = false;
    for (int i = 0; i < 3; ++i) {
      const double floor = std::min(prior(i, i), map_p(i, i) + own(i, i));
      if (p(i, i) < floor) {
        p(i, i) = floor;
        raised = true;
      }
    }
    if (raised) laser_.ResetPose(pose(), p);
  }
  // A scan kept out of the map (as LaserSlam::SetMapping decides).
  const bool unmapped = !map_empty && (suspect() || u.fit < options_.map_min_fit);
  if (unmapped) ++unmapped_scans_;
  if (map_uncertainty && !unmapped) {
    // The parts this scan maps first are as certain as the pose now, less the drift of the map
    // over the distance explored since the last scan.
    const double d = travelled_since_scan_m_;
    const double gxy = options_.map_drift_xy_m * options_.map_drift_xy_m * d;
    const double gt = options_.map_drift_theta_rad * options_.map_drift_theta_rad * d;
    RecordMapCovariance(pose(), points_robot, covariance() + Eigen::Matrix3d(Eigen::Vector3d(gxy, gxy, gt).asDiagonal()));
  }
  travelled_since_scan_m_ = 0;
  return u;
}

bool FusedSlam::CarryForward(int64_t utime, Pose2* z, Eigen::Matrix3d* r) const {
  if (have_time_ && utime < utime_ - static_cast<int64_t>(std::llround(options_.max_fix_age_s * 1e6))) return false;
  for (const auto& [t, delta] : history_) {
    if (t > utime) PredictWithOdometry(options_.laser.motion, delta, z, r);
  }
  return true;
}

std::optional<Pose2> FusedSlam::PoseAt(int64_t utime) const {
  if (have_time_ && utime < utime_ - static_cast<int64_t>(std::llround(options_.max_fix_age_s * 1e6))) {
    return std::nullopt;
  }
  Pose2 motion;  // odometry from utime to now
  for (const auto& [t, delta] : history_) {
    if (t > utime) motion = motion.Compose(delta);
  }
  return pose().Compose(motion.Inverse());
}

std::optional<std::pair<Pose2, Eigen::Matrix3d>> FusedSlam::hypothesis() const {
  if (!hypothesis_) return std::nullopt;
  return std::make_pair(hypothesis_->pose, hypothesis_->covariance);
}

VisualUpdate FusedSlam::AddVisual(int64_t utime, const Pose2& z_in, const Eigen::Matrix3d& r_in) {
  Require(Finite(z_in), "visual pose is not finite");
  Require(r_in.allFinite(), "visual covariance is not finite");
  Require(r_in(0, 0) >= 0 && r_in(1, 1) >= 0 && r_in(2, 2) >= 0,
          "visual covariance has a negative variance");
  VisualUpdate v;
  // The measurement's covariance, symmetric, its variances floored.
  Eigen::Matrix3d r = 0.5 * (r_in + r_in.transpose());
  const double fp = options_.min_fix_sigma_xy_m, fh = options_.min_fix_sigma_theta_rad;
  const Eigen::Vector3d floor(fp * fp, fp * fp, fh * fh);
  for (int i = 0; i < 3; ++i) r(i, i) += std::max(0.0, floor(i) - r(i, i));
  Pose2 z{z_in.x_m, z_in.y_m, WrapAngle(z_in.theta_rad)};
  if (!CarryForward(utime, &z, &r)) {
    ++stale_;
    v.outcome = VisualOutcome::kStale;
    return v;
  }
  v.measurement = z;
  v.measurement_covariance = r;
  v.mahalanobis2 = Mahalanobis2(Difference(z, pose()), covariance(), r);
  if (v.mahalanobis2 <= options_.gate_chi2) {
    laser_.UpdatePose(z, r);
    ++accepted_;
    consecutive_rejections_ = 0;
    hypothesis_.reset();
    hypothesis_count_ = 0;
    v.outcome = VisualOutcome::kAccepted;
    return v;
  }
  ++rejected_;
  ++consecutive_rejections_;
  // Evidence for a relocalisation: the recent rejected measurements (carried here by odometry)
  // that agree with this one, fused with it.
  Hypothesis h{z, r};
  int count = 1;
  for (auto it = rejected_window_.rbegin(); it != rejected_window_.rend(); ++it) {
    if (Mahalanobis2(Difference(it->pose, z), it->covariance, r) > options_.agree_chi2) continue;
    h.pose = EkfPoseUpdate(h.pose, &h.covariance, it->pose, it->covariance);
    ++count;
  }
  rejected_window_.push_back({utime, z, r});
  const size_t cap = static_cast<size_t>(std::max(8, 2 * options_.relocalize_after));
  while (rejected_window_.size() > cap) rejected_window_.pop_front();
  hypothesis_ = h;
  hypothesis_count_ = count;
  v.agreeing_rejections = count;
  v.outcome = VisualOutcome::kRejected;
  // Relocalise when enough agree, their fused pose still disagrees with the filter, and the last
  // scan does not fit the map clearly worse there than at the filter's pose (aliasing that moves
  // with the robot: views a metre behind along a straight wall look alike).
  const Eigen::Vector3d jump = Difference(h.pose, pose());
  bool relocalize = options_.relocalize_after > 0 && count >= options_.relocalize_after &&
                    Mahalanobis2(jump, covariance(), h.covariance) > options_.gate_chi2;
  if (relocalize && jump.head<2>().norm() < options_.relocalize_min_distance_m &&
      std::abs(jump.z()) < options_.relocalize_min_heading_rad) {
    relocalize = false;  // a small disagreement (a drifted map), not a kidnapping: the laser keeps the pose
    ++small_disagreements_;
  }
  if (relocalize && options_.relocalize_max_fit_loss < 1) {
    double judged_here = 0, judged_there = 0;
    const double here = ScanFit(pose(), &judged_here), there = ScanFit(h.pose, &judged_there);
    if (judged_here >= kMinJudged && judged_there >= kMinJudged && there < here - options_.relocalize_max_fit_loss) {
      relocalize = false;
      ++refused_relocalizations_;
    }
  }
  if (relocalize) {
    Eigen::Matrix3d p = h.covariance;
    const double sxy = options_.relocalize_sigma_xy_m, st = options_.relocalize_sigma_theta_rad;
    const Eigen::Vector3d wide(sxy * sxy, sxy * sxy, st * st);
    for (int i = 0; i < 3; ++i) p(i, i) = std::max(p(i, i), wide(i));
    laser_.ResetPose(h.pose, p);
    ++relocalizations_;
    consecutive_rejections_ = 0;
    rejected_window_.clear();
    hypothesis_.reset();
    hypothesis_count_ = 0;
    v.outcome = VisualOutcome::kRelocalized;
  }
  return v;
}

}  // namespace snapnav::nav
