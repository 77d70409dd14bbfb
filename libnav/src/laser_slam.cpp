#include "snapnav/nav/laser_slam.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <Eigen/Dense>

namespace snapnav::nav {
namespace {

Eigen::Vector2d Rotate(double c, double s, const Eigen::Vector2d& v) { return {c * v.x() - s * v.y(), s * v.x() + c * v.y()}; }

}  // namespace

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

void LaserSlamOptions::Validate() const {
  motion.Validate();
  if (!(initial_sigma_xy_m >= 0) || !(initial_sigma_theta_rad >= 0)) throw std::invalid_argument("laser slam: initial sigmas must be >= 0");
  if (!(match_distance_m > 0)) throw std::invalid_argument("laser slam: match_distance_m must be > 0");
  if (!(match_distance_start_m >= match_distance_m)) {
    throw std::invalid_argument("laser slam: match_distance_start_m must be >= match_distance_m");
  }
  if (!(robust_scale_m > 0)) throw std::invalid_argument("laser slam: robust_scale_m must be > 0");
  if (!(max_range_m >= 0)) throw std::invalid_argument("laser slam: max_range_m must be >= 0 (0: no limit)");
  if (!(recovery_fit >= 0 && recovery_fit <= 1)) throw std::invalid_argument("laser slam: recovery_fit must be in [0, 1]");
  if (!(search_sigmas >= 0) || !(search_window_max_rad >= 0) || !(search_step_rad > 0)) {
    throw std::invalid_argument("laser slam: search_sigmas and search_window_max must be >= 0, search_step > 0");
  }
  if (icp_iterations < 1) throw std::invalid_argument("laser slam: icp_iterations must be >= 1");
  if (!(point_sigma_m > 0)) throw std::invalid_argument("laser slam: point_sigma_m must be > 0");
  if (min_matches < 3) throw std::invalid_argument("laser slam: min_matches must be >= 3");
  if (!(map_resolution_m > 0) || !(add_distance_m > 0)) throw std::invalid_argument("laser slam: map sizes must be > 0");
  if (scan_step < 1) throw std::invalid_argument("laser slam: scan_step must be >= 1");
  if (!(update_score_margin >= 0 && update_score_margin < 1)) {
    throw std::invalid_argument("laser slam: update_score_margin must be in [0, 1)");
  }
  if (!(turn_noise_rad_per_rad >= 0)) throw std::invalid_argument("laser slam: turn_noise_rad_per_rad must be >= 0");
  if (!(lookup_cell_m >= 0)) throw std::invalid_argument("laser slam: lookup_cell_m must be >= 0 (0: exact search)");
  if (!(search_window_xy_m >= 0)) throw std::invalid_argument("laser slam: search_window_xy_m must be >= 0");
  if (!(search_sigma_m > 0) || !(3 * search_sigma_m <= std::max(match_distance_start_m, add_distance_m))) {
    throw std::invalid_argument("laser slam: search_sigma_m must be > 0 and at most match_distance_start_m / 3");
  }
  if (!(scan_latency_s >= 0 && scan_latency_s <= 10))
    throw std::invalid_argument("laser slam: scan_latency_s must be in [0, 10]");
  if (!(stale_fraction >= 0 && stale_fraction <= 1))
    throw std::invalid_argument("laser slam: stale_fraction must be in [0, 1]");
  if (refine_starts < 1) throw std::invalid_argument("laser slam: refine_starts must be >= 1");
  if (refine_prune_iterations < 0) throw std::invalid_argument("laser slam: refine_prune_iterations must be >= 0");
  if (!(refine_prune_fraction > 0 && refine_prune_fraction <= 1)) {
    throw std::invalid_argument("laser slam: refine_prune_fraction must be in (0, 1]");
  }
  if (!(search_prior_weight >= 0)) throw std::invalid_argument("laser slam: search_prior_weight must be >= 0");
}

LaserSlam::LaserSlam(const LaserSlamOptions& options, const Pose2& start)
    : options_(options),
      pose_(start),
      map_(options.map_resolution_m, std::max(0.25, options.match_distance_m),
           options.lookup_cell_m > 0 ? std::max(options.match_distance_start_m, options.add_distance_m) : 0,
           options.lookup_cell_m > 0 ? options.lookup_cell_m : 1.0,
           options.matcher == ScanMatcher::kCorrelative && options.lookup_cell_m > 0 ? options.search_sigma_m : 0) {
  options_.Validate();
  covariance_ = Eigen::Vector3d(options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_theta_rad * options.initial_sigma_theta_rad)
                    .asDiagonal();
}

void LaserSlam::Predict(const Pose2& odometry_delta) {
  PredictWithOdometry(options_.motion, odometry_delta, &pose_, &covariance_);
  odometry_since_scan_ = odometry_since_scan_.Compose(odometry_delta);
}

void LaserSlam::Predict(const Pose2& odometry_delta, int64_t end_utime) {
  Predict(odometry_delta);
  const int64_t start = last_odometry_utime_ ? std::min(*last_odometry_utime_, end_utime) : end_utime;
  recent_odometry_.push_back({start, end_utime, odometry_delta});
  last_odometry_utime_ = end_utime;
}

LaserSlamUpdate LaserSlam::Update(const std::vector<Eigen::Vector2d>& points_robot) {
  // Untimed: matched at the latest odometry; the timed increments so far are past.
  recent_odometry_.clear();
  odometry_since_scan_ = tail_.Compose(odometry_since_scan_);
  tail_ = {};
  const LaserSlamUpdate u = UpdateAtScan(points_robot);
  scan_pose_ = pose_;
  return u;
}

LaserSlamUpdate LaserSlam::Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime) {
  // The odometry after the match time: the later part of each increment that ends after it.
  const int64_t at = utime - static_cast<int64_t>(std::llround(options_.scan_latency_s * 1e6));
  Pose2 tail;
  for (const TimedIncrement& inc : recent_odometry_) {
    if (inc.end_utime <= at) continue;
    if (inc.start_utime >= at || inc.end_utime <= inc.start_utime) {
      tail = tail.Compose(inc.delta);
      continue;
    }
    const double before =
        static_cast<double>(at - inc.start_utime) / static_cast<double>(inc.end_utime - inc.start_utime);
    const Pose2 first{before * inc.delta.x_m, before * inc.delta.y_m, before * inc.delta.theta_rad};
    tail = tail.Compose(first.Inverse().Compose(inc.delta));
  }
  recent_odometry_.clear();
  // The motion between the two match times, and the pose at this one.
  odometry_since_scan_ = tail_.Compose(odometry_since_scan_).Compose(tail.Inverse());
  pose_ = pose_.Compose(tail.Inverse());
  tail_ = tail;
  const LaserSlamUpdate u = UpdateAtScan(points_robot);
  scan_pose_ = pose_;
  pose_ = pose_.Compose(tail_);
  return u;
}

LaserSlamUpdate LaserSlam::UpdateAtScan(const std::vector<Eigen::Vector2d>& all_points) {
  LaserSlamUpdate u;
  std::vector<Eigen::Vector2d> points;
  points.reserve(all_points.size() / static_cast<size_t>(options_.scan_step) + 1);
  const double max_range2 = options_.max_range_m > 0 ? options_.max_range_m * options_.max_range_m
                                                     : std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < all_points.size(); i += static_cast<size_t>(options_.scan_step)) {
    if (all_points[i].squaredNorm() <= max_range2) points.push_back(all_points[i]);
  }
  const std::vector<Eigen::Vector2d> normals = ScanNormals(points);
  u.points = static_cast<int>(points.size());
  ++scans_;
  if (options_.stale_odometry && last_scan_pose_) {
    // (Increments between two equal odometry poses are zero up to rounding.)
    const double moved = std::hypot(odometry_since_scan_.x_m, odometry_since_scan_.y_m);
    const double last_moved = std::hypot(last_motion_.x_m, last_motion_.y_m);
    const bool frozen = moved <= 1e-6 && std::abs(odometry_since_scan_.theta_rad) <= 1e-6;
    // A robot moving at last_moved per scan cannot stop within one scan interval: odometry whose
    // translation falls below stale_fraction of it lags (CSAIL: 0.21 m, then 0.004, 0, 0, then 0.83).
    const bool lagging =
        options_.stale_fraction > 0 && last_moved >= kStaleMinMotionM && moved < options_.stale_fraction * last_moved;
    if (frozen || lagging) {
      // Stale (or the robot stopped: then the last motion is small, or the scan corrects it).
      if (!stale_since_) {
        stale_since_ = *last_scan_pose_;
        odometry_since_stale_ = {};
      }
      odometry_since_stale_ = odometry_since_stale_.Compose(odometry_since_scan_);
      // The prediction is the last motion instead of odometry's (from the pose after the last
      // scan, as a filter built on this one may have moved it since); its covariance also covers
      // what odometry said (the robot may have stopped).
      pose_ = pose_.Compose(odometry_since_scan_.Inverse());
      const double c = std::cos(pose_.theta_rad), sn = std::sin(pose_.theta_rad);
      PredictWithOdometry(options_.motion, last_motion_, &pose_, &covariance_);
      const Eigen::Vector2d off =
          Rotate(c, sn, {last_motion_.x_m - odometry_since_scan_.x_m, last_motion_.y_m - odometry_since_scan_.y_m});
      const double off_theta = WrapAngle(last_motion_.theta_rad - odometry_since_scan_.theta_rad);
      covariance_.topLeftCorner<2, 2>() += off * off.transpose();
      covariance_(2, 2) += off_theta * off_theta;
      u.stale_odometry = true;
    } else if (stale_since_) {
      // Odometry's increments over the stale interval and this one hold the whole motion since.
      // Take out what the scans tracked meanwhile.
      odometry_since_stale_ = odometry_since_stale_.Compose(odometry_since_scan_);
      const Pose2 tracked = stale_since_->Between(*last_scan_pose_);
      pose_ = pose_.Compose(odometry_since_scan_.Inverse()).Compose(tracked.Inverse().Compose(odometry_since_stale_));
      stale_since_.reset();
    }
  }
  if (map_.size() > 0 && !points.empty()) {
    const MapMatcher match = matcher();
    // Heading search: the prediction's heading may be off by more than ICP can pull in (a fast
    // turn, odometry late against the laser). Headings within search_sigmas standard deviations
    // of the prediction are scored on a subset of the points, and ICP starts from the best.
    const size_t stride = std::max<size_t>(1, points.size() / 90);
    const double step = options_.search_step_rad;
    Pose2 start = pose_;
    const double turn = std::max(std::abs(odometry_since_scan_.theta_rad), std::abs(previous_odometry_turn_rad_));
    covariance_(2, 2) += std::pow(options_.turn_noise_rad_per_rad * turn, 2);
    u.predicted = pose_;
    u.predicted_covariance = covariance_;
    const double window = std::min(options_.search_window_max_rad, options_.search_sigmas * std::sqrt(covariance_(2, 2)));
    const bool correlative = options_.matcher == ScanMatcher::kCorrelative;
    const double sigma_xy = std::sqrt(std::max(covariance_(0, 0), covariance_(1, 1)));
    std::vector<MapMatcher::Candidate> candidates;
    if (correlative && options_.search_window_max_rad >= step) {
      const double window_xy = std::min(options_.search_window_xy_m, options_.search_sigmas * sigma_xy);
      candidates = match.SearchPoses(pose_, covariance_, window, window_xy, true, points, stride);
      ++u.searches;
    } else if (window >= step) {
      candidates = match.SearchHeading(pose_, window, 0.0, points, stride);
      ++u.searches;
    }
    if (candidates.empty()) candidates.push_back({pose_, 0});
    MapMatcher::RefineCounts counts;
    MapMatcher::Icp icp = match.RefineBest(candidates, points, normals, &start, &counts);
    u.start = start;
    u.fit = !icp.ok ? 0.0 : icp.scored ? icp.fit : match.Fit(icp.estimate, points, 1);
    if (u.fit < options_.recovery_fit && options_.search_window_max_rad >= step) {
      // Poor fit: search the whole window, and positions around the prediction, then align again.
      const std::vector<MapMatcher::Candidate> again_candidates =
          correlative ? match.SearchPoses(pose_, covariance_, options_.search_window_max_rad, options_.search_window_xy_m,
                                    false, points, stride)
                      : match.SearchHeading(pose_, options_.search_window_max_rad, options_.match_distance_start_m / 2,
                                      points, stride);
      Pose2 again_start = pose_;
      const MapMatcher::Icp again = match.RefineBest(again_candidates, points, normals, &again_start, &counts);
      const double again_fit = !again.ok ? 0.0 : again.scored ? again.fit : match.Fit(again.estimate, points, 1);
      ++u.recoveries;
      if (again_fit > u.fit) {
        icp = again;
        u.start = again_start;
        u.fit = again_fit;
        // The prediction was off by this much, whatever its covariance said: widen it so the
        // update does not pull the pose back towards it.
        const Eigen::Vector3d off(icp.estimate.x_m - pose_.x_m, icp.estimate.y_m - pose_.y_m,
                                  WrapAngle(icp.estimate.theta_rad - pose_.theta_rad));
        covariance_ += off.cwiseProduct(off).asDiagonal();
      }
    }
    u.starts = counts.starts;
    u.pruned = counts.pruned;
    u.iterations = icp.iterations;
    u.matches = icp.matches;
    if (icp.ok) {
      const double sigma2 = std::max(options_.point_sigma_m * options_.point_sigma_m, icp.residual2 / icp.weight_sum);
      Eigen::Matrix3d info = icp.info / sigma2;
      info += Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();  // unobservable directions: huge R, not singular
      u.measured = true;
      u.measurement = icp.estimate;
      u.measurement_covariance = info.inverse();
      const Pose2 predicted = pose_;
      const Eigen::Matrix3d predicted_covariance = covariance_;
      pose_ = EkfPoseUpdate(pose_, &covariance_, icp.estimate, u.measurement_covariance);
      if (options_.update_score_margin > 0) {
        // The update should sit where the scan fits: if it scores clearly below the ICP pose
        // against the map, the prediction was off by more than its covariance allowed (odometry
        // jitter along a corridor, a late turn); widen it by the innovation and update again.
        const double at_icp = icp.scored ? icp.score : match.Score(icp.estimate, points, 1);
        const double at_update = match.Score(pose_, points, 1);
        if (at_update < (1 - options_.update_score_margin) * at_icp) {
          const Eigen::Vector3d off(icp.estimate.x_m - predicted.x_m, icp.estimate.y_m - predicted.y_m,
                                    WrapAngle(icp.estimate.theta_rad - predicted.theta_rad));
          covariance_ = predicted_covariance;
          covariance_ += off.cwiseProduct(off).asDiagonal();
          pose_ = EkfPoseUpdate(predicted, &covariance_, icp.estimate, u.measurement_covariance);
          u.widened = true;
        }
      }
    }
  }
  previous_odometry_turn_rad_ = odometry_since_scan_.theta_rad;
  odometry_since_scan_ = {};
  if (last_scan_pose_) last_motion_ = last_scan_pose_->Between(pose_);
  last_scan_pose_ = pose_;
  if (!MayAddPoints(u)) return u;
  // Points with no map point near them join the map at the updated pose, with their normals.
  const double c = std::cos(pose_.theta_rad), s = std::sin(pose_.theta_rad);
  const Eigen::Vector2d t(pose_.x_m, pose_.y_m);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d w = Rotate(c, s, points[i]) + t;
    if (map_.size() > 0 && map_.HasPointWithin(w, options_.add_distance_m)) continue;
    if (map_.Add(w, Rotate(c, s, normals[i]))) ++u.added;
  }
  return u;
}

// ---- For filters built on this one (nav::FusedSlam).

void LaserSlam::UpdatePose(const Pose2& z, const Eigen::Matrix3d& r) {
  if (!std::isfinite(z.x_m) || !std::isfinite(z.y_m) || !std::isfinite(z.theta_rad) || !r.allFinite()) {
    throw std::invalid_argument("laser slam: pose measurement or its covariance is not finite");
  }
  pose_ = EkfPoseUpdate(pose_, &covariance_, z, r);
}

void LaserSlam::ResetPose(const Pose2& pose, const Eigen::Matrix3d& covariance) {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad) ||
      !covariance.allFinite()) {
    throw std::invalid_argument("laser slam: reset pose or covariance is not finite");
  }
  const Pose2 old = pose_;
  pose_ = {pose.x_m, pose.y_m, WrapAngle(pose.theta_rad)};
  covariance_ = 0.5 * (covariance + covariance.transpose());
  // The jump is no motion: the poses the odometry models keep move with it (else the next scan
  // takes the jump for the last scan-to-scan motion, and odometry below stale_fraction of it for
  // stale, and predicts the jump again at every scan).
  const auto carry = [&](const Pose2& p) { return pose_.Compose(old.Between(p)); };
  if (last_scan_pose_) last_scan_pose_ = carry(*last_scan_pose_);
  if (stale_since_) stale_since_ = carry(*stale_since_);
  scan_pose_ = carry(scan_pose_);
}

void LaserSlam::SetMapping(bool add_points, double min_fit) {
  if (!(min_fit >= 0 && min_fit <= 1)) throw std::invalid_argument("laser slam: mapping min_fit must be in [0, 1]");
  add_points_ = add_points;
  min_add_fit_ = min_fit;
}

bool LaserSlam::MayAddPoints(const LaserSlamUpdate& u) const {
  if (!add_points_) return false;
  return map_.size() == 0 || u.fit >= min_add_fit_;
}

}  // namespace snapnav::nav
