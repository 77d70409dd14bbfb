#include "snapnav/nav/fused_slam.hpp"

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
  Require(suspect_after >= 0, "suspect_after must be >= 0 (0: never)");
  Require(map_min_fit >= 0 && map_min_fit <= 1, "map_min_fit must be in [0, 1]");
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
  if (hypothesis_) PredictWithOdometry(options_.laser.motion, delta, &hypothesis_->pose, &hypothesis_->covariance);
  if (!have_time_ || utime > utime_) utime_ = utime;
  have_time_ = true;
  history_.emplace_back(utime, delta);
  const int64_t keep_from = utime_ - static_cast<int64_t>(std::llround(options_.max_fix_age_s * 1e6));
  while (!history_.empty() && history_.front().first < keep_from) history_.pop_front();
}

bool FusedSlam::suspect() const {
  return options_.suspect_after > 0 && consecutive_rejections_ >= options_.suspect_after;
}

LaserSlamUpdate FusedSlam::Update(const std::vector<Eigen::Vector2d>& points_robot) {
  laser_.SetMapping(!suspect(), options_.map_min_fit);
  const bool map_empty = laser_.map().size() == 0;
  const LaserSlamUpdate u = laser_.Update(points_robot);
  // A scan kept out of the map (as LaserSlam::SetMapping decides).
  if (!map_empty && (suspect() || u.fit < options_.map_min_fit)) ++unmapped_scans_;
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
  // Evidence for a relocalisation: does it agree with the rejected ones before it?
  if (hypothesis_ && Mahalanobis2(Difference(z, hypothesis_->pose), hypothesis_->covariance, r) <= options_.agree_chi2) {
    hypothesis_->pose = EkfPoseUpdate(hypothesis_->pose, &hypothesis_->covariance, z, r);
    ++hypothesis_count_;
  } else {
    hypothesis_ = Hypothesis{z, r};
    hypothesis_count_ = 1;
  }
  v.agreeing_rejections = hypothesis_count_;
  v.outcome = VisualOutcome::kRejected;
  if (options_.relocalize_after > 0 && hypothesis_count_ >= options_.relocalize_after) {
    Eigen::Matrix3d p = hypothesis_->covariance;
    const double sxy = options_.relocalize_sigma_xy_m, st = options_.relocalize_sigma_theta_rad;
    const Eigen::Vector3d wide(sxy * sxy, sxy * sxy, st * st);
    for (int i = 0; i < 3; ++i) p(i, i) = std::max(p(i, i), wide(i));
    laser_.ResetPose(hypothesis_->pose, p);
    ++relocalizations_;
    consecutive_rejections_ = 0;
    hypothesis_.reset();
    hypothesis_count_ = 0;
    v.outcome = VisualOutcome::kRelocalized;
  }
  return v;
}

}  // namespace snapnav::nav
