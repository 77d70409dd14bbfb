#include "snapnav/nav/slam/fused_slam.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "snapnav/nav/covariance.hpp"
#include "snapnav/nav/slam/cell_key.hpp"

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

Eigen::Matrix3d Diagonal(double sigma_xy, double sigma_theta) {
  return Eigen::Vector3d(sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_theta * sigma_theta).asDiagonal();
}

// Carries a rigid map offset (t at `from`, phi) to `to`: t + phi J (to - from), J a quarter turn.
Eigen::Matrix3d Lever(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
  a(0, 2) = -(to.y() - from.y());
  a(1, 2) = to.x() - from.x();
  return a;
}

// The rotation of a pose covariance by `r` (x, y turned, the heading kept).
Eigen::Matrix3d Rotate(const Eigen::Matrix2d& r, const Eigen::Matrix3d& c) {
  Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
  j.topLeftCorner<2, 2>() = r;
  return j * c * j.transpose();
}

Eigen::Matrix3d Symmetric(const Eigen::Matrix3d& c) { return 0.5 * (c + c.transpose()); }

// The smallest covariance at least `c` and at least `floor` along every direction where floor
// exceeds c: c plus the positive part of floor - c.
Eigen::Matrix3d AtLeast(const Eigen::Matrix3d& c, const Eigen::Matrix3d& floor) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(Symmetric(floor - c));
  const Eigen::Vector3d positive = eig.eigenvalues().cwiseMax(0.0);
  return Symmetric(c + eig.eigenvectors() * positive.asDiagonal() * eig.eigenvectors().transpose());
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
          "relocalize_sigma_xy_m and relocalize_sigma_theta_deg must be >= 0");
  Require(min_fix_sigma_xy_m > 0 && min_fix_sigma_theta_rad > 0 && std::isfinite(min_fix_sigma_xy_m) &&
              std::isfinite(min_fix_sigma_theta_rad),
          "min_fix_sigma_xy_m and min_fix_sigma_theta_deg must be positive");
  Require(max_fix_age_s > 0 && std::isfinite(max_fix_age_s), "max_fix_age_s must be positive");
  Require(relocalize_window_s > 0 && std::isfinite(relocalize_window_s), "relocalize_window_s must be positive");
  Require(relocalize_min_distance_m >= 0 && relocalize_min_heading_rad >= 0,
          "relocalize_min_distance_m and relocalize_min_heading_deg must be >= 0");
  Require(relocalize_max_fit_loss >= 0 && relocalize_max_fit_loss <= 1, "relocalize_max_fit_loss must be in [0, 1]");
  Require(suspect_after >= 0, "suspect_after must be >= 0 (0: never)");
  Require(map_min_fit >= 0 && map_min_fit <= 1, "map_min_fit must be in [0, 1]");
  Require(dynamic_explain_m >= 0 && std::isfinite(dynamic_explain_m), "dynamic_explain_m must be >= 0 (0: off)");
  Require(dynamic_max_behind_m >= 0 && std::isfinite(dynamic_max_behind_m), "dynamic_max_behind_m must be >= 0");
  Require(dynamic_map_age_s >= 0 && std::isfinite(dynamic_map_age_s), "dynamic_map_age_s must be >= 0");
  Require(dynamic_max_fraction >= 0 && dynamic_max_fraction <= 1, "dynamic_max_fraction must be in [0, 1]");
  Require(occlusion_fix_inflation >= 0 && std::isfinite(occlusion_fix_inflation),
          "occlusion_fix_inflation must be >= 0 (0: off)");
  Require(laser_min_constraint >= 0 && std::isfinite(laser_min_constraint), "laser_min_constraint must be >= 0 (0: off)");
  Require(fix_correlation_m >= 0 && std::isfinite(fix_correlation_m), "fix_correlation_m must be >= 0 (0: off)");
  Require(map_cell_m > 0 && std::isfinite(map_cell_m), "map_cell_m must be positive");
  Require(start_sigma_xy_m >= 0 && start_sigma_theta_rad >= 0 && std::isfinite(start_sigma_xy_m) &&
              std::isfinite(start_sigma_theta_rad),
          "start_sigma_xy_m and start_sigma_theta_deg must be >= 0");
  Require(map_drift_xy_m >= 0 && map_drift_theta_rad >= 0 && std::isfinite(map_drift_xy_m) &&
              std::isfinite(map_drift_theta_rad),
          "map_drift_xy_m and map_drift_theta_deg must be >= 0");
}

FusedSlam::FusedSlam(const FusedSlamOptions& options, const Pose2& start)
    : FusedSlam(options, start, Diagonal(options.start_sigma_xy_m, options.start_sigma_theta_rad)) {}

FusedSlam::FusedSlam(const FusedSlamOptions& options, const Pose2& start, const Eigen::Matrix3d& covariance)
    : options_(options),
      start_(start),
      laser_((options.Validate(), options.laser), Pose2{}),
      old_map_(options.laser.map_resolution_m, std::max(0.25, options.dynamic_explain_m)) {
  Require(Finite(start) && covariance.allFinite(), "start pose or covariance is not finite");
  start_.theta_rad = WrapAngle(start_.theta_rad);
  const double c = std::cos(start_.theta_rad), s = std::sin(start_.theta_rad);
  start_rotation_ << c, -s, s, c;
  laser_.SetMapping(true, options_.map_min_fit);
  // The map frame is the start's: its uncertainty in the world is the offset of everything seen first.
  u_cov_ = Rotate(start_rotation_.transpose(), Symmetric(covariance));
  laser_cov_ = laser_.covariance();
  Refresh();
}

void FusedSlam::Refresh() {
  const Pose2& m = laser_.pose();
  const Eigen::Vector2d p(m.x_m, m.y_m);
  const Eigen::Matrix3d a = Lever(u_at_, p);
  const Eigen::Vector3d u = a * u_ + drift_;
  const Pose2 corrected{m.x_m - u.x(), m.y_m - u.y(), WrapAngle(m.theta_rad - u.z())};
  pose_ = start_.Compose(corrected);
  pose_.theta_rad = WrapAngle(pose_.theta_rad);
  covariance_ = Rotate(start_rotation_, Symmetric(laser_covariance() + a * u_cov_ * a.transpose()));
}

void FusedSlam::Predict(int64_t utime, const Pose2& delta) {
  const Pose2 before = laser_.pose();
  laser_.Predict(delta);  // throws on a non-finite increment before anything changes
  travelled_since_scan_m_ += std::hypot(delta.x_m, delta.y_m);
  travelled_since_fix_m_ += std::hypot(delta.x_m, delta.y_m);
  travelled_since_new_cells_m_ += std::hypot(delta.x_m, delta.y_m);
  if (options_.laser_min_constraint > 0) {
    // P_l grows with the laser's motion model; the drift d is carried with the motion (the corrected
    // pose m - d moves by the same increment as m).
    const Pose2 corrected{before.x_m - drift_.x(), before.y_m - drift_.y(), WrapAngle(before.theta_rad - drift_.z())};
    Pose2 moved = before;
    PredictWithOdometry(options_.laser.motion, delta, &moved, &laser_cov_);
    drift_ = Difference(moved, corrected.Compose(delta));
    laser_cov_ = Symmetric(laser_cov_);
  }
  if (hypothesis_) PredictWithOdometry(options_.laser.motion, delta, &hypothesis_->pose, &hypothesis_->covariance);
  for (auto& e : rejected_window_) PredictWithOdometry(options_.laser.motion, delta, &e.pose, &e.covariance);
  if (!have_time_ || utime > utime_) utime_ = utime;
  have_time_ = true;
  history_.emplace_back(utime, delta);
  const int64_t keep_from = utime_ - static_cast<int64_t>(std::llround(options_.max_fix_age_s * 1e6));
  while (!history_.empty() && history_.front().first < keep_from) history_.pop_front();
  const int64_t window_from = utime_ - static_cast<int64_t>(std::llround(options_.relocalize_window_s * 1e6));
  while (!rejected_window_.empty() && rejected_window_.front().utime < window_from) rejected_window_.pop_front();
  while (!accepted_window_.empty() && accepted_window_.front() < window_from) accepted_window_.pop_front();
  Refresh();
}

size_t FusedSlam::EvidenceCap() const { return static_cast<size_t>(std::max(8, 2 * options_.relocalize_after)); }

bool FusedSlam::suspect() const {
  return options_.suspect_after > 0 && consecutive_rejections_ >= options_.suspect_after;
}

uint64_t FusedSlam::CellKey(const Eigen::Vector2d& p) const { return nav::CellKey(p, options_.map_cell_m); }

Eigen::Vector2d FusedSlam::CellCenter(const Eigen::Vector2d& p) const {
  const double c = options_.map_cell_m;
  return {(std::floor(p.x() / c) + 0.5) * c, (std::floor(p.y() / c) + 0.5) * c};
}

namespace {

constexpr size_t kMapSamples = 64;  // scan points looked at for the map offset and the relocalisation fit
constexpr double kCoverageM = 1.0;  // a scan point is judged by the map if a map point is this close [m]
constexpr double kMinJudged = 0.3;  // the fits are compared when this share of the points is judged at both poses

}  // namespace

bool FusedSlam::SeenOffset(const Pose2& m, Eigen::Vector3d* u, Eigen::Matrix3d* cov,
                           std::vector<std::pair<uint64_t, double>>* cells) const {
  std::vector<std::pair<uint64_t, double>> seen;
  int n = 0;
  for (const auto& point : last_points_) {
    const uint64_t key = CellKey(m.Transform(point));
    if (!cells_.count(key)) continue;
    ++n;
    auto it = std::find_if(seen.begin(), seen.end(), [key](const auto& e) { return e.first == key; });
    if (it == seen.end()) {
      seen.emplace_back(key, 1.0);
    } else {
      it->second += 1.0;
    }
  }
  if (cells) cells->clear();
  if (n == 0) return false;
  const Eigen::Vector2d p(m.x_m, m.y_m);
  u->setZero();
  cov->setZero();
  for (auto& [key, w] : seen) {
    w /= n;
    const MapOffset& c = cells_.at(key);
    const Eigen::Matrix3d a = Lever(c.center, p);
    *u += w * (a * c.offset);
    *cov += w * (a * c.covariance * a.transpose());
  }
  *cov = Symmetric(*cov);
  if (cells) *cells = std::move(seen);
  return true;
}

std::optional<MapOffset> FusedSlam::MapOffsetAt(const Eigen::Vector2d& p) const {
  const auto it = cells_.find(CellKey(start_.Inverse().Transform(p)));
  if (it == cells_.end()) return std::nullopt;
  return it->second;
}

std::vector<Eigen::Vector2d> FusedSlam::WorldMapPoints() const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(laser_.map().size());
  for (const auto& q : laser_.map().points()) {
    Eigen::Vector2d corrected = q;
    const auto it = cells_.find(CellKey(q));
    if (it != cells_.end()) {
      const Eigen::Vector3d& o = it->second.offset;
      const Eigen::Vector2d r = q - it->second.center;
      corrected = q - o.head<2>() - o.z() * Eigen::Vector2d(-r.y(), r.x());
    }
    out.push_back(start_.Transform(corrected));
  }
  return out;
}

double FusedSlam::ScanFit(const Pose2& m, double* judged) const {
  *judged = 0;
  if (last_points_.empty()) return 0;
  const double near = 2 * options_.laser.point_sigma_m;
  int covered = 0, close = 0;
  for (const auto& p : last_points_) {
    const Eigen::Vector2d w = m.Transform(p);
    const int i = laser_.map().NearestIndex(w, kCoverageM);
    if (i < 0) continue;  // the map has nothing there: no evidence either way
    ++covered;
    if ((laser_.map().points()[static_cast<size_t>(i)] - w).norm() <= near) ++close;
  }
  *judged = static_cast<double>(covered) / static_cast<double>(last_points_.size());
  return covered > 0 ? static_cast<double>(close) / covered : 0.0;
}

void FusedSlam::AgeMap() {
  // The map only grows: its first `old` points are those of the scans at least dynamic_map_age_s ago.
  const int64_t age_us = static_cast<int64_t>(std::llround(options_.dynamic_map_age_s * 1e6));
  size_t old = 0;
  for (const auto& [utime, size] : map_sizes_) {
    if (utime > utime_ - age_us) break;
    old = size;
  }
  const auto& points = laser_.map().points();
  for (; old_added_ < old && old_added_ < points.size(); ++old_added_) old_map_.Add(points[old_added_]);
}

std::vector<bool> FusedSlam::DynamicPoints(const Pose2& m, const std::vector<Eigen::Vector2d>& points) const {
  std::vector<bool> dynamic(points.size(), false);
  const double d = options_.dynamic_explain_m;
  if (d <= 0 || old_map_.size() == 0) return dynamic;
  // Only from a prediction certain to d (one std. dev. of its position): just relocalised (a wide
  // covariance) the walls themselves would stand "in front of" the map.
  {
    if (PositionSigmaM(laser_.covariance()) > d) return dynamic;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const double range = points[i].norm();
    if (!(range > 0)) continue;
    const Eigen::Vector2d w = m.Transform(points[i]);
    if (old_map_.HasPointWithin(w, d)) continue;  // the map explains it
    // Along the beam beyond the point (steps of d, each looking d around): a mapped surface the
    // point stands in front of.
    const Eigen::Vector2d dir = (w - Eigen::Vector2d(m.x_m, m.y_m)) / range;
    for (double s = 2 * d; s <= options_.dynamic_max_behind_m; s += d) {
      if (old_map_.HasPointWithin(w + s * dir, d)) {
        dynamic[i] = true;
        break;
      }
    }
  }
  return dynamic;
}

LaserSlamUpdate FusedSlam::Update(const std::vector<Eigen::Vector2d>& points_robot) {
  // Dynamic obstacles at the predicted pose, left out of the laser's update and map.
  std::vector<Eigen::Vector2d> kept;
  const std::vector<Eigen::Vector2d>* points = &points_robot;
  occluded_fraction_ = 0;
  if (options_.dynamic_explain_m > 0 && !points_robot.empty()) {
    AgeMap();
    const std::vector<bool> dynamic = DynamicPoints(laser_.pose(), points_robot);
    const int64_t n = std::count(dynamic.begin(), dynamic.end(), true);
    occluded_fraction_ = static_cast<double>(n) / static_cast<double>(points_robot.size());
    if (occluded_fraction_ > options_.dynamic_max_fraction) {
      ++dynamic_overflow_scans_;  // the prediction is off, not people: the whole scan
    } else if (n > 0) {
      kept.reserve(points_robot.size() - static_cast<size_t>(n));
      for (size_t i = 0; i < points_robot.size(); ++i) {
        if (!dynamic[i]) kept.push_back(points_robot[i]);
      }
      dynamic_points_ += n;
      points = &kept;
    }
  }
  {
    // A sample of the scan, for the map offset and for judging a relocalisation.
    last_points_.clear();
    const size_t stride = std::max<size_t>(1, points->size() / kMapSamples);
    for (size_t i = 0; i < points->size(); i += stride) last_points_.push_back((*points)[i]);
  }
  laser_.SetMapping(!suspect(), options_.map_min_fit);
  const bool map_empty = laser_.map().size() == 0;
  const LaserSlamUpdate u = laser_.Update(*points);  // the laser SLAM, as it runs alone, on the static points
  UpdateLaserCovariance(u);
  if (map_empty && options_.laser_min_constraint > 0) {
    // The first scan defines the map: the laser sits on it exactly (its uncertainty in the world is
    // the start's, the cells' offset).
    laser_cov_.setZero();
    drift_.setZero();
  }
  const Pose2& m = laser_.pose();
  const Eigen::Vector2d p(m.x_m, m.y_m);
  // The robot's offset: the seen cells' (or, where none has one yet, carried with the robot).
  Eigen::Vector3d seen_u;
  Eigen::Matrix3d seen_cov;
  if (SeenOffset(m, &seen_u, &seen_cov, &seen_)) {
    u_ = seen_u;
    u_cov_ = seen_cov;
  } else {
    const Eigen::Matrix3d a = Lever(u_at_, p);
    u_ = a * u_;
    u_cov_ = Symmetric(a * u_cov_ * a.transpose());
  }
  u_at_ = p;
  // A scan kept out of the map (as LaserSlam::SetMapping decides).
  const bool unmapped = !map_empty && (suspect() || u.fit < options_.map_min_fit);
  if (unmapped) ++unmapped_scans_;
  if (!unmapped) {
    // Cells this scan reaches first are mapped from the robot's pose: its offset, carried to them,
    // and one more scan's drift.
    const double d = options_.map_drift_accumulates ? travelled_since_new_cells_m_ : travelled_since_scan_m_;
    const Eigen::Matrix3d drift = Diagonal(options_.map_drift_xy_m * std::sqrt(d), options_.map_drift_theta_rad * std::sqrt(d));
    bool added = false;
    for (const auto& point : last_points_) {
      const Eigen::Vector2d q = m.Transform(point);
      const uint64_t key = CellKey(q);
      if (cells_.count(key)) continue;
      MapOffset c;
      c.center = CellCenter(q);
      const Eigen::Matrix3d a = Lever(p, c.center);
      if (options_.map_inherits_laser_drift && options_.laser_min_constraint > 0) {
        c.offset = a * (u_ + drift_);
        c.covariance = Symmetric(a * (u_cov_ + laser_cov_) * a.transpose() + drift);
      } else {
        c.offset = a * u_;
        c.covariance = Symmetric(a * u_cov_ * a.transpose() + drift);
      }
      cells_.emplace(key, c);
      added = true;
    }
    if (added) travelled_since_new_cells_m_ = 0;
    if (added && SeenOffset(m, &seen_u, &seen_cov, &seen_)) {
      u_ = seen_u;
      u_cov_ = seen_cov;
    }
  }
  travelled_since_scan_m_ = 0;
  // The map's size after this scan, for the age of its points (DynamicPoints).
  map_sizes_.emplace_back(utime_, laser_.map().size());
  const int64_t keep_us = static_cast<int64_t>(std::llround(options_.dynamic_map_age_s * 1e6));
  while (map_sizes_.size() > 1 && map_sizes_[1].first <= utime_ - keep_us) map_sizes_.pop_front();
  Refresh();
  return u;
}

void FusedSlam::UpdateLaserCovariance(const LaserSlamUpdate& u) {
  if (options_.laser_min_constraint <= 0) return;
  if (u.measured && u.matches > 0) {
    // The scan's information, without its weak position directions.
    const Eigen::Matrix3d info = Symmetric(u.measurement_covariance.inverse());
    const SymmetricEigen2 eig = EigenOfSymmetric(info.topLeftCorner<2, 2>());
    const double per_point = options_.laser.point_sigma_m * options_.laser.point_sigma_m / u.matches;
    Eigen::Matrix<double, 3, Eigen::Dynamic> kept(3, 1);
    kept.col(0) = Eigen::Vector3d::UnitZ();
    weakest_constraint_ = std::max(0.0, eig.values(0)) * per_point;  // ascending: (0) is the weakest
    for (int i = 0; i < 2; ++i) {
      if (eig.values(i) * per_point < options_.laser_min_constraint) continue;
      kept.conservativeResize(3, kept.cols() + 1);
      kept.col(kept.cols() - 1) << eig.vectors(0, i), eig.vectors(1, i), 0.0;
    }
    degenerate_ = kept.cols() < 3;
    if (degenerate_) ++degenerate_scans_;
    const Eigen::Matrix3d used = kept * (kept.transpose() * info * kept) * kept.transpose();
    // Information form: P = (P^-1 + I')^-1 = (1 + P I')^-1 P; d = (1 + P I')^-1 d (the scan says the
    // laser sits on its map along the directions it constrains).
    const Eigen::Matrix3d g = (Eigen::Matrix3d::Identity() + laser_cov_ * used).inverse();
    laser_cov_ = Symmetric(g * laser_cov_);
    drift_ = g * drift_;
  }
  // The laser widened its own covariance (a poor fit's recovery, an update off the fit): never below it.
  if (u.widened || u.recoveries > 0 || !u.measured) laser_cov_ = AtLeast(laser_cov_, laser_.covariance());
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
  Eigen::Matrix3d r = Symmetric(r_in);
  const double fp = options_.min_fix_sigma_xy_m, fh = options_.min_fix_sigma_theta_rad;
  const Eigen::Vector3d floor(fp * fp, fp * fp, fh * fh);
  for (int i = 0; i < 3; ++i) r(i, i) += std::max(0.0, floor(i) - r(i, i));
  // People in the view (the laser's occluded fraction) move the place cells' match.
  const double inflate = 1 + options_.occlusion_fix_inflation * occluded_fraction_;
  r *= inflate * inflate;
  Pose2 z{z_in.x_m, z_in.y_m, WrapAngle(z_in.theta_rad)};
  if (!CarryForward(utime, &z, &r)) {
    ++stale_;
    v.outcome = VisualOutcome::kStale;
    return v;
  }
  v.measurement = z;
  v.measurement_covariance = r;
  // In the map frame the fix measures the map's offset at the robot: m - z.
  const Pose2& m = laser_.pose();
  const Eigen::Vector2d p(m.x_m, m.y_m);
  const Pose2 zm = start_.Inverse().Compose(z);
  const Eigen::Matrix3d rm = Rotate(start_rotation_.transpose(), r) + laser_covariance();
  const Eigen::Matrix3d a = Lever(u_at_, p);
  const Eigen::Vector3d u = a * u_ + drift_;
  const Eigen::Matrix3d uc = Symmetric(a * u_cov_ * a.transpose());
  const Eigen::Vector3d measured(m.x_m - zm.x_m, m.y_m - zm.y_m, WrapAngle(m.theta_rad - zm.theta_rad));
  Eigen::Vector3d y = measured - u;
  y.z() = WrapAngle(y.z());
  const Eigen::LDLT<Eigen::Matrix3d> s(Symmetric(uc + rm));
  v.mahalanobis2 = y.dot(s.solve(y));
  if (v.mahalanobis2 <= options_.gate_chi2) {
    // Correlated fixes (fix_correlation_m): the update takes the fix's covariance times the
    // effective number of fixes its error is shared with.
    double factor = 1;
    if (options_.fix_correlation_m > 0 && have_fix_) {
      const double rho = std::exp(-travelled_since_fix_m_ / options_.fix_correlation_m);
      factor = std::min(1e4, (1 + rho) / std::max(1e-12, 1 - rho));
    }
    const Eigen::Matrix3d ru = Rotate(start_rotation_.transpose(), r) * factor + laser_covariance();
    const Eigen::LDLT<Eigen::Matrix3d> su(Symmetric(uc + ru));
    const Eigen::Vector3d y_offset = y;  // the innovation of the robot's offset (cells and drift)
    const Eigen::Vector3d drift_before = drift_;
    const Eigen::Matrix3d ru_before = ru;  // the cells' updates see the drift's state before this fix
    if (options_.laser_min_constraint > 0) {
      // The laser's drift from its map takes its share (P_l S^-1) of the innovation.
      const Eigen::Matrix3d kd = su.solve(laser_cov_).transpose();  // P_l S^-1
      drift_ += kd * y_offset;
      drift_.z() = WrapAngle(drift_.z());
      laser_cov_ = Symmetric(laser_cov_ - kd * laser_cov_);
    }
    u_at_ = p;
    have_fix_ = true;
    travelled_since_fix_m_ = 0;
    if (seen_.empty()) {
      // No map cell under the robot (just relocalised, no scan yet): the robot's offset alone.
      const Eigen::Matrix3d k = su.solve(uc).transpose();  // uc S^-1 (both symmetric)
      u_ = a * u_ + k * y_offset;
      u_.z() = WrapAngle(u_.z());
      u_cov_ = Symmetric(uc - k * uc);
    } else {
      // Every cell the last scan saw measures the map's offset at the robot as well: each gets
      // its own Kalman update (its offset carried to the robot, innovation and gain its own), and
      // the robot's offset is their mean again, as after a scan.
      u_.setZero();
      u_cov_.setZero();
      for (const auto& [key, w] : seen_) {
        MapOffset& c = cells_.at(key);
        const Eigen::Matrix3d ac = Lever(c.center, p);
        Eigen::Vector3d yc = measured - drift_before - ac * c.offset;
        yc.z() = WrapAngle(yc.z());
        const Eigen::Matrix3d oa = c.covariance * ac.transpose();
        const Eigen::LDLT<Eigen::Matrix3d> sc(Symmetric(ac * oa + ru_before));
        const Eigen::Matrix3d kc = sc.solve(oa.transpose()).transpose();  // O A^T S_c^-1
        c.offset += kc * yc;
        c.offset.z() = WrapAngle(c.offset.z());
        c.covariance = Symmetric(c.covariance - kc * oa.transpose());
        u_ += w * (ac * c.offset);
        u_cov_ += w * (ac * c.covariance * ac.transpose());
      }
      u_.z() = WrapAngle(u_.z());
      u_cov_ = Symmetric(u_cov_);
    }
    ++accepted_;
    // Only the most recent can count against the agreeing rejected ones (at most EvidenceCap() + 1
    // of those): bounded without odometry to prune by time too.
    accepted_window_.push_back(utime);
    while (accepted_window_.size() > EvidenceCap() + 1) accepted_window_.pop_front();
    consecutive_rejections_ = 0;
    hypothesis_.reset();
    hypothesis_count_ = 0;
    v.outcome = VisualOutcome::kAccepted;
    Refresh();
    return v;
  }
  ++rejected_;
  ++consecutive_rejections_;
  // Evidence for a relocalisation: the recent rejected measurements (carried here by odometry)
  // that agree with this one, fused with it.
  Hypothesis h{z, r};
  int count = 1;
  int64_t oldest = utime;
  for (auto it = rejected_window_.rbegin(); it != rejected_window_.rend(); ++it) {
    if (Mahalanobis2(Difference(it->pose, z), it->covariance, r) > options_.agree_chi2) continue;
    h.pose = EkfPoseUpdate(h.pose, &h.covariance, it->pose, it->covariance);
    ++count;
    oldest = std::min(oldest, it->utime);
  }
  // The measurements the filter accepted meanwhile: evidence that it is where it thinks.
  int against = 0;
  if (options_.relocalize_net_of_accepted) {
    for (const int64_t t : accepted_window_) against += t >= oldest ? 1 : 0;
  }
  rejected_window_.push_back({utime, z, r});
  while (rejected_window_.size() > EvidenceCap()) rejected_window_.pop_front();
  hypothesis_ = h;
  hypothesis_count_ = count;
  v.agreeing_rejections = count;
  v.outcome = VisualOutcome::kRejected;
  // Relocalise when enough agree, their fused pose still disagrees with the filter, and the last
  // scan does not fit the map clearly worse there than at the filter's pose (aliasing that moves
  // with the robot: views a metre behind along a straight wall look alike).
  const Eigen::Vector3d jump = Difference(h.pose, pose());
  bool relocalize = options_.relocalize_after > 0 && count - against >= options_.relocalize_after &&
                    Mahalanobis2(jump, covariance(), h.covariance) > options_.gate_chi2;
  if (relocalize && jump.head<2>().norm() < options_.relocalize_min_distance_m &&
      std::abs(jump.z()) < options_.relocalize_min_heading_rad) {
    relocalize = false;  // a small disagreement (a drifted map), not a kidnapping: the laser keeps the pose
    ++small_disagreements_;
  }
  // The laser's pose there: the world pose in the map frame plus the map's offset there (the
  // cells the last scan would see from it; none: an unmapped part, no offset).
  const Pose2 hm = start_.Inverse().Compose(h.pose);
  Pose2 target{hm.x_m + u.x(), hm.y_m + u.y(), WrapAngle(hm.theta_rad + u.z())};
  Eigen::Vector3d there_u = Eigen::Vector3d::Zero();
  Eigen::Matrix3d there_cov = Eigen::Matrix3d::Zero();
  std::vector<std::pair<uint64_t, double>> there_cells;
  const bool mapped_there = SeenOffset(target, &there_u, &there_cov, &there_cells);
  target = {hm.x_m + there_u.x(), hm.y_m + there_u.y(), WrapAngle(hm.theta_rad + there_u.z())};
  if (relocalize && options_.relocalize_max_fit_loss < 1) {
    double judged_here = 0, judged_there = 0;
    const double here = ScanFit(m, &judged_here), there = ScanFit(target, &judged_there);
    if (judged_here >= kMinJudged && judged_there >= kMinJudged && there < here - options_.relocalize_max_fit_loss) {
      relocalize = false;
      ++refused_relocalizations_;
    }
  }
  if (relocalize) {
    Eigen::Matrix3d pw = h.covariance;
    const double sxy = options_.relocalize_sigma_xy_m, st = options_.relocalize_sigma_theta_rad;
    const Eigen::Vector3d wide(sxy * sxy, sxy * sxy, st * st);
    for (int i = 0; i < 3; ++i) pw(i, i) = std::max(pw(i, i), wide(i));
    const Eigen::Matrix3d pm = Rotate(start_rotation_.transpose(), Symmetric(pw));
    if (mapped_there) {
      // The laser searches its map there with the wide covariance; the map's offset there is known.
      laser_.ResetPose(target, pm);
      u_cov_ = there_cov;
    } else {
      // No map there: the laser starts a new part of its map as it starts the first (its own
      // initial uncertainty), and that part is off the world by the relocalised pose's error.
      const double ixy = options_.laser.initial_sigma_xy_m, ith = options_.laser.initial_sigma_theta_rad;
      laser_.ResetPose(target, Diagonal(ixy, ith));
      u_cov_ = pm;
    }
    laser_cov_ = laser_.covariance();  // the relocalised pose's: no drift from the map known
    drift_.setZero();
    u_ = there_u;
    u_at_ = {target.x_m, target.y_m};
    seen_ = std::move(there_cells);
    ++relocalizations_;
    consecutive_rejections_ = 0;
    rejected_window_.clear();
    accepted_window_.clear();
    hypothesis_.reset();
    hypothesis_count_ = 0;
    v.outcome = VisualOutcome::kRelocalized;
    Refresh();
  }
  return v;
}

}  // namespace snapnav::nav
