#include "snapnav/nav/laser_slam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

namespace snapnav::nav {

Pose2 EkfPoseUpdate(const Pose2& pose, Eigen::Matrix3d* covariance, const Pose2& z, const Eigen::Matrix3d& r) {
  const Eigen::Matrix3d& p = *covariance;
  const Eigen::Matrix3d k = p * (p + r).inverse();
  const Eigen::Vector3d innovation(z.x_m - pose.x_m, z.y_m - pose.y_m, WrapAngle(z.theta_rad - pose.theta_rad));
  const Eigen::Vector3d dx = k * innovation;
  // Joseph form keeps the covariance symmetric and positive.
  const Eigen::Matrix3d i_k = Eigen::Matrix3d::Identity() - k;
  *covariance = i_k * p * i_k.transpose() + k * r * k.transpose();
  return {pose.x_m + dx.x(), pose.y_m + dx.y(), WrapAngle(pose.theta_rad + dx.z())};
}

std::optional<Pose2> AlignPoints(const std::vector<Eigen::Vector2d>& src, const std::vector<Eigen::Vector2d>& dst) {
  if (src.size() != dst.size() || src.size() < 2) return std::nullopt;
  Eigen::Vector2d ms = Eigen::Vector2d::Zero(), md = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    ms += src[i];
    md += dst[i];
  }
  ms /= static_cast<double>(src.size());
  md /= static_cast<double>(dst.size());
  double sxx = 0, sxy = 0, spread = 0;  // cross terms of the centred pairs
  for (size_t i = 0; i < src.size(); ++i) {
    const Eigen::Vector2d a = src[i] - ms, b = dst[i] - md;
    sxx += a.x() * b.x() + a.y() * b.y();
    sxy += a.x() * b.y() - a.y() * b.x();
    spread += a.squaredNorm();
  }
  if (spread < 1e-12) return std::nullopt;
  const double theta = std::atan2(sxy, sxx);
  const double c = std::cos(theta), s = std::sin(theta);
  const Eigen::Vector2d t = md - Eigen::Vector2d(c * ms.x() - s * ms.y(), s * ms.x() + c * ms.y());
  return Pose2{t.x(), t.y(), WrapAngle(theta)};
}

std::vector<Eigen::Vector2d> ScanToPoints(const std::vector<float>& ranges_m, double angle_min_rad,
                                          double angle_increment_rad, double range_min_m, double range_max_m,
                                          const Pose2& sensor) {
  std::vector<Eigen::Vector2d> points;
  points.reserve(ranges_m.size());
  // Ranges travel as floats: a max-range reading may arrive a few ULPs below range_max.
  const double no_return = range_max_m - 1e-5 * std::max(1.0, range_max_m);
  for (size_t i = 0; i < ranges_m.size(); ++i) {
    const double r = ranges_m[i];
    if (!std::isfinite(r) || r < range_min_m || r >= no_return) continue;
    const double a = angle_min_rad + angle_increment_rad * static_cast<double>(i);
    points.push_back(sensor.Transform({r * std::cos(a), r * std::sin(a)}));
  }
  return points;
}

PointGridMap::PointGridMap(double resolution_m, double bucket_m) : resolution_(resolution_m), bucket_(bucket_m) {
  if (!(resolution_m > 0) || !(bucket_m > 0)) throw std::invalid_argument("point map: cell sizes must be > 0");
}

bool PointGridMap::Add(const Eigen::Vector2d& p) {
  const uint64_t fine = Key(static_cast<int64_t>(std::floor(p.x() / resolution_)),
                            static_cast<int64_t>(std::floor(p.y() / resolution_)));
  if (!cells_.emplace(fine, static_cast<uint32_t>(points_.size())).second) return false;
  buckets_[Key(static_cast<int64_t>(std::floor(p.x() / bucket_)), static_cast<int64_t>(std::floor(p.y() / bucket_)))]
      .push_back(static_cast<uint32_t>(points_.size()));
  points_.push_back(p);
  return true;
}

std::optional<Eigen::Vector2d> PointGridMap::Nearest(const Eigen::Vector2d& p, double max_distance_m) const {
  const int64_t bx = static_cast<int64_t>(std::floor(p.x() / bucket_));
  const int64_t by = static_cast<int64_t>(std::floor(p.y() / bucket_));
  const int64_t reach = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(max_distance_m / bucket_)));
  double best = max_distance_m * max_distance_m;
  const Eigen::Vector2d* found = nullptr;
  for (int64_t dx = -reach; dx <= reach; ++dx) {
    for (int64_t dy = -reach; dy <= reach; ++dy) {
      const auto it = buckets_.find(Key(bx + dx, by + dy));
      if (it == buckets_.end()) continue;
      for (const uint32_t i : it->second) {
        const double d = (points_[i] - p).squaredNorm();
        if (d < best) {
          best = d;
          found = &points_[i];
        }
      }
    }
  }
  if (!found) return std::nullopt;
  return *found;
}

void LaserSlamOptions::Validate() const {
  motion.Validate();
  if (!(initial_sigma_xy_m >= 0) || !(initial_sigma_theta_rad >= 0)) throw std::invalid_argument("laser slam: initial sigmas must be >= 0");
  if (!(match_distance_m > 0)) throw std::invalid_argument("laser slam: match_distance_m must be > 0");
  if (icp_iterations < 1) throw std::invalid_argument("laser slam: icp_iterations must be >= 1");
  if (!(point_sigma_m > 0)) throw std::invalid_argument("laser slam: point_sigma_m must be > 0");
  if (min_matches < 3) throw std::invalid_argument("laser slam: min_matches must be >= 3");
  if (!(map_resolution_m > 0) || !(add_distance_m > 0)) throw std::invalid_argument("laser slam: map sizes must be > 0");
  if (scan_step < 1) throw std::invalid_argument("laser slam: scan_step must be >= 1");
}

LaserSlam::LaserSlam(const LaserSlamOptions& options, const Pose2& start)
    : options_(options), pose_(start), map_(options.map_resolution_m, options.match_distance_m) {
  options_.Validate();
  covariance_ = Eigen::Vector3d(options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_theta_rad * options.initial_sigma_theta_rad)
                    .asDiagonal();
}

void LaserSlam::Predict(const Pose2& odometry_delta) {
  PredictWithOdometry(options_.motion, odometry_delta, &pose_, &covariance_);
}

LaserSlamUpdate LaserSlam::Update(const std::vector<Eigen::Vector2d>& all_points) {
  LaserSlamUpdate u;
  std::vector<Eigen::Vector2d> decimated;
  if (options_.scan_step > 1) {
    for (size_t i = 0; i < all_points.size(); i += options_.scan_step) decimated.push_back(all_points[i]);
  }
  const std::vector<Eigen::Vector2d>& points = options_.scan_step > 1 ? decimated : all_points;
  u.points = static_cast<int>(points.size());
  ++scans_;
  if (map_.size() > 0 && !points.empty()) {
    // ICP: nearest map point of every scan point, closed-form alignment, repeated.
    Pose2 estimate = pose_;
    std::vector<Eigen::Vector2d> src, dst;
    std::vector<size_t> index;
    for (int it = 0; it < options_.icp_iterations; ++it) {
      src.clear();
      dst.clear();
      index.clear();
      for (size_t i = 0; i < points.size(); ++i) {
        const auto q = map_.Nearest(estimate.Transform(points[i]), options_.match_distance_m);
        if (!q) continue;
        src.push_back(points[i]);
        dst.push_back(*q);
        index.push_back(i);
      }
      ++u.iterations;
      if (static_cast<int>(src.size()) < options_.min_matches) break;
      const auto next = AlignPoints(src, dst);
      if (!next) break;
      // Convergence: translation plus rotation (radians count as metres at 1 m range).
      const double step = std::hypot(next->x_m - estimate.x_m, next->y_m - estimate.y_m) +
                          std::abs(WrapAngle(next->theta_rad - estimate.theta_rad));
      estimate = *next;
      if (step < options_.icp_convergence_m) break;
    }
    u.matches = static_cast<int>(src.size());
    if (u.matches >= options_.min_matches) {
      // Measurement covariance from the point-to-line information of the matches: the normal of
      // the scan's surface at each match (from its scan neighbours) constrains the pose along it
      // only, so a corridor leaves its axis to the prediction.
      const double c = std::cos(estimate.theta_rad), s = std::sin(estimate.theta_rad);
      double residual2 = 0;
      Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
      for (size_t k = 0; k < src.size(); ++k) {
        const Eigen::Vector2d w = estimate.Transform(src[k]);
        residual2 += (w - dst[k]).squaredNorm();
        const size_t i = index[k];
        const Eigen::Vector2d a = points[i > 0 ? i - 1 : i], b = points[i + 1 < points.size() ? i + 1 : i];
        Eigen::Vector2d tangent = b - a;
        if (tangent.norm() < 1e-9 || tangent.norm() > 0.5) continue;  // isolated point: no surface
        tangent = Eigen::Vector2d(c * tangent.x() - s * tangent.y(), s * tangent.x() + c * tangent.y()).normalized();
        const Eigen::Vector2d n(-tangent.y(), tangent.x());
        const Eigen::Vector2d d_theta(-s * src[k].x() - c * src[k].y(), c * src[k].x() - s * src[k].y());
        const Eigen::RowVector3d j(n.x(), n.y(), n.dot(d_theta));
        info += j.transpose() * j;
      }
      const double sigma2 = std::max(options_.point_sigma_m * options_.point_sigma_m, residual2 / (2.0 * u.matches));
      info /= sigma2;
      info += Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();  // unobservable directions: huge R, not singular
      u.measured = true;
      u.measurement = estimate;
      u.measurement_covariance = info.inverse();
      pose_ = EkfPoseUpdate(pose_, &covariance_, estimate, u.measurement_covariance);
    }
  }
  // Unmatched points join the map at the updated pose.
  for (const auto& p : points) {
    const Eigen::Vector2d w = pose_.Transform(p);
    if (map_.size() > 0 && map_.HasPointWithin(w, options_.add_distance_m)) continue;
    if (map_.Add(w)) ++u.added;
  }
  return u;
}

}  // namespace snapnav::nav
