#include "snapnav/nav/slam/laser_slam.hpp"

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

// Points on each side of a scan point whose line gives the walls' directions (wall_orientation).
constexpr int kWallNeighbours = 7;
// The matcher's normals: ScanNormals' defaults.
constexpr int kNormalNeighbours = 2;
constexpr double kNormalMaxGapM = 0.3;

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
  odometry_calibration.Validate();
  if (!(initial_sigma_xy_m >= 0) || !(initial_sigma_theta_rad >= 0))
    throw std::invalid_argument("laser slam: initial_sigma_xy_m and initial_sigma_theta_deg must be >= 0");
  if (!(match_distance_m > 0)) throw std::invalid_argument("laser slam: match_distance_m must be > 0");
  if (!(match_distance_start_m >= match_distance_m)) {
    throw std::invalid_argument("laser slam: match_distance_start_m must be >= match_distance_m");
  }
  if (!(robust_scale_m > 0)) throw std::invalid_argument("laser slam: robust_scale_m must be > 0");
  if (!(max_range_m >= 0)) throw std::invalid_argument("laser slam: max_range_m must be >= 0 (0: no limit)");
  if (!(recovery_fit >= 0 && recovery_fit <= 1)) throw std::invalid_argument("laser slam: recovery_fit must be in [0, 1]");
  if (!(search_sigmas >= 0) || !(search_window_max_rad >= 0) || !(search_step_rad > 0)) {
    throw std::invalid_argument(
        "laser slam: search_sigmas and search_window_max_deg must be >= 0, search_step_deg > 0");
  }
  if (icp_iterations < 1) throw std::invalid_argument("laser slam: icp_iterations must be >= 1");
  if (!(point_sigma_rad >= 0)) throw std::invalid_argument("laser slam: point_sigma_deg must be >= 0");
  if (!(point_sigma_m > 0)) throw std::invalid_argument("laser slam: point_sigma_m must be > 0");
  if (min_matches < 3) throw std::invalid_argument("laser slam: min_matches must be >= 3");
  if (!(map_resolution_m > 0) || !(add_distance_m > 0))
    throw std::invalid_argument("laser slam: map_resolution_m and add_distance_m must be > 0");
  if (scan_step < 1) throw std::invalid_argument("laser slam: scan_step must be >= 1");
  if (!(update_score_margin >= 0 && update_score_margin < 1)) {
    throw std::invalid_argument("laser slam: update_score_margin must be in [0, 1)");
  }
  if (!(hypothesis_odds >= 1)) throw std::invalid_argument("laser slam: hypothesis_odds must be >= 1");
  if (!(interval_sigma_xy_m >= 0) || !(interval_sigma_theta_rad >= 0))
    throw std::invalid_argument("laser slam: interval_sigma_xy_m and interval_sigma_theta_deg must be >= 0");
  if (!(interval_full_m >= 0) || !(interval_full_rad >= 0))
    throw std::invalid_argument("laser slam: interval_full_m and interval_full_deg must be >= 0");
  if (!(match_sigma_xy_m >= 0) || !(match_sigma_theta_rad >= 0))
    throw std::invalid_argument("laser slam: match_sigma_xy_m and match_sigma_theta_deg must be >= 0");
  if (!(gate_mahalanobis2 >= 0)) throw std::invalid_argument("laser slam: gate_mahalanobis2 must be >= 0 (0: no gate)");
  if (!(gate_full_fit >= 0 && gate_full_fit <= 1)) throw std::invalid_argument("laser slam: gate_full_fit must be in [0, 1]");
  if (!(outlier_scale >= 1)) throw std::invalid_argument("laser slam: outlier_scale must be >= 1 (1: off)");
  if (!(outlier_min_fit >= 0 && outlier_min_fit <= 1))
    throw std::invalid_argument("laser slam: outlier_min_fit must be in [0, 1]");
  if (!(min_fit >= 0 && min_fit <= 1)) throw std::invalid_argument("laser slam: min_fit must be in [0, 1]");
  if (!(wall_window_rad > 0 && wall_window_rad <= 0.5)) throw std::invalid_argument("laser slam: wall_window_deg must be in (0, 28.6]");
  if (!(wall_kernel_rad > 0 && wall_kernel_rad <= 0.2)) throw std::invalid_argument("laser slam: wall_kernel_deg must be in (0, 11.5]");
  if (!(wall_sigma_rad > 0)) throw std::invalid_argument("laser slam: wall_sigma_deg must be > 0");
  if (!(wall_min_contrast >= 1)) throw std::invalid_argument("laser slam: wall_min_contrast must be >= 1");
  if (!(wall_min_map_points >= 0)) throw std::invalid_argument("laser slam: wall_min_map_points must be >= 0");
  if (!(wall_gate_mahalanobis2 > 0)) throw std::invalid_argument("laser slam: wall_gate_mahalanobis2 must be > 0");
  if (!(adaptive_window_scans >= 1)) throw std::invalid_argument("laser slam: adaptive_window_scans must be >= 1");
  if (!(adaptive_scale_min > 0 && adaptive_scale_min <= 1 && adaptive_scale_max >= 1))
    throw std::invalid_argument("laser slam: adaptive_scale_min must be in (0, 1] and adaptive_scale_max >= 1");
  if (!(max_ambiguity > 0 && max_ambiguity <= 1)) throw std::invalid_argument("laser slam: max_ambiguity must be in (0, 1]");
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
      map_(MakeMap(options)),
      calibration_(options.odometry_calibration) {
  options_.Validate();
  walls_ = WallOrientations(options_.wall_kernel_rad);
  covariance_ = Eigen::Vector3d(options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_theta_rad * options.initial_sigma_theta_rad)
                    .asDiagonal();
  anchor_covariance_ = covariance_;
}

PointGridMap LaserSlam::MakeMap(const LaserSlamOptions& options) {
  return PointGridMap(options.map_resolution_m, std::max(0.25, options.match_distance_m),
                      options.lookup_cell_m > 0 ? std::max(options.match_distance_start_m, options.add_distance_m) : 0,
                      options.lookup_cell_m > 0 ? options.lookup_cell_m : 1.0,
                      options.matcher == ScanMatcher::kCorrelative && options.lookup_cell_m > 0 ? options.search_sigma_m
                                                                                                : 0);
}

void LaserSlam::ResetMap(const std::vector<Eigen::Vector2d>& points, const std::vector<Eigen::Vector2d>& normals) {
  if (normals.size() != points.size()) throw std::invalid_argument("laser slam: ResetMap needs a normal per point");
  map_ = MakeMap(options_);
  // The walls' directions stay: a correction turns the map's parts by little, and these points'
  // normals (not in scan order) are not the walls' own.
  for (size_t i = 0; i < points.size(); ++i) AddMapPoint(options_, points[i], normals[i], &map_);
}

void LaserSlam::AddMapPoint(const LaserSlamOptions& options, const Eigen::Vector2d& p, const Eigen::Vector2d& normal,
                            PointGridMap* map) {
  if (!p.allFinite()) return;
  if (map->size() > 0 && map->HasPointWithin(p, options.add_distance_m)) return;
  map->Add(p, normal);
}

LaserSlamOptions ThesisLaserSlamOptions(const LaserSlamOptions& base) {
  LaserSlamOptions thesis = base;
  thesis.metric = IcpMetric::kPointToPoint;
  thesis.match_distance_m = thesis.match_distance_start_m = 0.25;
  thesis.search_window_max_rad = 0;
  thesis.motion = DeadReckoningOptions{};
  thesis.motion_noise_per_scan = false;
  thesis.turn_noise_rad_per_rad = 0;
  thesis.stale_odometry = false;
  thesis.gate_mahalanobis2 = 0;
  thesis.match_sigma_xy_m = thesis.match_sigma_theta_rad = 0;
  thesis.interval_sigma_xy_m = thesis.interval_sigma_theta_rad = 0;
  thesis.interval_full_m = thesis.interval_full_rad = 0;
  thesis.point_sigma_m = 0.03;
  thesis.point_sigma_rad = 0;
  thesis.max_ambiguity = 1;
  thesis.ambiguous_update = false;
  thesis.wall_orientation = false;
  thesis.min_fit = 0;
  thesis.gate_full_fit = 0;
  thesis.outlier_scale = 1;
  thesis.adaptive_motion_noise = false;
  thesis.odometry_calibration.apply = false;
  thesis.update_score_margin = 0;
  thesis.lookup_cell_m = 0;  // the exact nearest map point
  return thesis;
}

const char* MatchOutcomeName(MatchOutcome o) {
  switch (o) {
    case MatchOutcome::kMapStart: return "map_start";
    case MatchOutcome::kAccepted: return "accepted";
    case MatchOutcome::kGated: return "gated";
    case MatchOutcome::kAmbiguous: return "ambiguous";
    case MatchOutcome::kNoMatch: return "no_match";
  }
  return "?";
}

const char* PredictionSourceName(PredictionSource p) {
  switch (p) {
    case PredictionSource::kOdometry: return "odometry";
    case PredictionSource::kStale: return "stale";
    case PredictionSource::kCatchUp: return "catch_up";
  }
  return "?";
}

Pose2 LaserSlam::TakeOdometry(const Pose2& raw) {
  // Odometry's raw motion for the calibration's stretch; the prediction from it corrected.
  stretch_raw_ = stretch_raw_.Compose(raw);
  stretch_path_m_ += std::copysign(std::hypot(raw.x_m, raw.y_m), raw.x_m);
  stretch_turn_rad_ += raw.theta_rad;
  return calibration_.Correct(raw);
}

void LaserSlam::Predict(const Pose2& odometry_delta) { PredictCorrected(TakeOdometry(odometry_delta)); }

void LaserSlam::PredictCorrected(const Pose2& odometry_delta) {
  if (!options_.motion_noise_per_scan) {
    PredictWithOdometry(options_.motion, odometry_delta, &pose_, &covariance_);
  } else {
    if (!std::isfinite(odometry_delta.x_m) || !std::isfinite(odometry_delta.y_m) ||
        !std::isfinite(odometry_delta.theta_rad)) {
      throw std::invalid_argument("odometry increment is not finite");
    }
    // The covariance from the anchor's over the whole motion since (one error, however many
    // increments it came in).
    anchor_motion_ = anchor_motion_.Compose(odometry_delta);
    anchor_path_m_ += std::hypot(odometry_delta.x_m, odometry_delta.y_m);
    anchor_turn_rad_ += std::abs(odometry_delta.theta_rad);
    pose_ = pose_.Compose(odometry_delta);
    covariance_ = IntervalCovariance(pose_.Compose(anchor_motion_.Inverse()), anchor_covariance_, anchor_motion_,
                                     anchor_path_m_, anchor_turn_rad_);
  }
  odometry_since_scan_ = odometry_since_scan_.Compose(odometry_delta);
}

Eigen::Matrix3d LaserSlam::IntervalCovariance(const Pose2& from, const Eigen::Matrix3d& covariance,
                                              const Pose2& motion, double path_m, double turn_rad) const {
  // The motion noise and the interval's own, scaled by the odometry noise scale (adaptive_motion_noise).
  const double k = std::sqrt(motion_scale2_ * calibration_.NoiseScale2());
  DeadReckoningOptions noise = options_.motion;
  noise.translation_noise_m_per_m *= k;
  noise.rotation_noise_rad_per_rad *= k;
  noise.rotation_noise_rad_per_m *= k;
  Eigen::Matrix3d p = MotionCovariance(noise, from, covariance, motion, path_m, turn_rad);
  if (path_m > 0 || turn_rad > 0) {
    // In proportion to the interval's motion up to interval_full_*: odometry read a moment off
    // the scan is off by what the robot moved in that moment, which a dense log's short
    // intervals make small (a per-scan constant would be a random walk growing with the scan rate).
    const double share = IntervalShare(path_m, turn_rad);
    const double sxy = share * options_.interval_sigma_xy_m, sth = share * options_.interval_sigma_theta_rad;
    p.diagonal() += motion_scale2_ * Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth);
  }
  return p;
}

double LaserSlam::IntervalShare(double path_m, double turn_rad) const {
  if (options_.interval_full_m <= 0 && options_.interval_full_rad <= 0) return 1;
  double share = 0;
  if (options_.interval_full_m > 0) share = std::max(share, path_m / options_.interval_full_m);
  if (options_.interval_full_rad > 0) share = std::max(share, turn_rad / options_.interval_full_rad);
  return std::min(1.0, share);
}

void LaserSlam::Reanchor() {
  anchor_covariance_ = covariance_;
  anchor_motion_ = {};
  anchor_path_m_ = anchor_turn_rad_ = 0;
}

void LaserSlam::Predict(const Pose2& odometry_delta, int64_t end_utime) {
  const Pose2 corrected = TakeOdometry(odometry_delta);
  PredictCorrected(corrected);
  const int64_t start = last_odometry_utime_ ? std::min(*last_odometry_utime_, end_utime) : end_utime;
  recent_odometry_.push_back({start, end_utime, corrected});
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
  if (tail_.x_m != 0 || tail_.y_m != 0 || tail_.theta_rad != 0) {
    // The odometry after the match time, from the updated pose: the anchor's motion so far.
    pose_ = scan_pose_;
    const Pose2 tail = tail_;
    odometry_since_scan_ = {};
    PredictCorrected(tail);
    odometry_since_scan_ = {};
  }
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
  // The walls' directions from longer runs of points (a straight wall's, to a degree or better).
  std::vector<Eigen::Vector2d> normals, wall_normals;
  ScanNormals(points, kNormalNeighbours, kWallNeighbours, kNormalMaxGapM, &normals,
              options_.wall_orientation ? &wall_normals : nullptr);
  std::vector<double> wall_directions;  // in the robot frame, NaN where no wall
  wall_directions.reserve(wall_normals.size());
  for (const Eigen::Vector2d& n : wall_normals) wall_directions.push_back(WallOrientations::Direction(n));
  u.points = static_cast<int>(points.size());
  ++scans_;

  // The predictions to match from: odometry's, and where odometry looks stale, the last
  // scan-to-scan motion; after stale scans, odometry's catch-up less what the scans tracked.
  struct Prediction {
    PredictionSource source;
    Pose2 pose;
    Eigen::Matrix3d covariance;
  };
  std::vector<Prediction> predictions;
  {
    // Odometry read late against the laser errs where the turn rate changes (a turn reported a scan
    // late: CSAIL 21, 0.2, 20 deg where the laser saw 15 each): heading noise from the change of
    // odometry's turn between this interval and the one before.
    Eigen::Matrix3d cov = covariance_;
    const double turn_change = std::abs(WrapAngle(odometry_since_scan_.theta_rad - previous_odometry_turn_rad_));
    cov(2, 2) += std::pow(options_.turn_noise_rad_per_rad * turn_change, 2);
    predictions.push_back({PredictionSource::kOdometry, pose_, cov});
  }
  if (options_.stale_odometry && last_scan_pose_ && map_.size() > 0 && !points.empty()) {
    // The pose at the last scan (a filter built on this one may have moved it since).
    const Pose2 anchor = pose_.Compose(odometry_since_scan_.Inverse());
    const auto from_anchor = [&](PredictionSource source, const Pose2& motion) {
      predictions.push_back({source, anchor.Compose(motion),
                             IntervalCovariance(anchor, anchor_covariance_, motion, std::hypot(motion.x_m, motion.y_m),
                                                std::abs(motion.theta_rad))});
    };
    // (Increments between two equal odometry poses are zero up to rounding.)
    const double moved = std::hypot(odometry_since_scan_.x_m, odometry_since_scan_.y_m);
    const double last_moved = std::hypot(last_motion_.x_m, last_motion_.y_m);
    const bool frozen = moved <= 1e-6 && std::abs(odometry_since_scan_.theta_rad) <= 1e-6;
    // A robot moving at last_moved per scan seldom stops within one scan interval: odometry whose
    // translation falls below stale_fraction of it may lag (CSAIL: 0.21 m, then 0.004, 0, 0, then 0.83).
    const double turned = std::abs(odometry_since_scan_.theta_rad), last_turned = std::abs(last_motion_.theta_rad);
    const bool lagging = options_.stale_fraction > 0 &&
                         ((last_moved >= kStaleMinMotionM && moved < options_.stale_fraction * last_moved) ||
                          (last_turned >= kStaleMinTurnRad && turned < options_.stale_fraction * last_turned));
    const bool last_moved_at_all = last_moved > 1e-3 || std::abs(last_motion_.theta_rad) > 1e-3;
    if ((frozen || lagging) && last_moved_at_all) from_anchor(PredictionSource::kStale, last_motion_);
    if (stale_since_ && !frozen) {
      // Odometry's increments since it went stale hold the whole motion since; take out what the
      // scans tracked meanwhile.
      const Pose2 since_stale = odometry_since_stale_.Compose(odometry_since_scan_);
      const Pose2 tracked = stale_since_->Between(*last_scan_pose_);
      from_anchor(PredictionSource::kCatchUp, tracked.Inverse().Compose(since_stale));
    }
  }

  const bool use_walls = options_.wall_orientation && walls_.total() >= options_.wall_min_map_points;
  size_t chosen = 0;
  if (map_.size() == 0 || points.empty()) {
    u.outcome = map_.size() == 0 ? MatchOutcome::kMapStart : MatchOutcome::kNoMatch;
  } else {
    const MapMatcher match = matcher();
    // The search runs on a subset of the points.
    const size_t stride = std::max<size_t>(1, points.size() / 90);
    const size_t searched = (points.size() + stride - 1) / stride;
    const double step = options_.search_step_rad;
    const bool correlative = options_.matcher == ScanMatcher::kCorrelative;
    // Kernel points per nat of the prior (MatcherOptions::search_prior_weight).
    const double weight = std::max(1e-9, options_.search_prior_weight);
    const auto prior_of = [&](const Prediction& p) {
      return MapMatcher::Prior{p.pose, (p.covariance + Eigen::Vector3d(1e-12, 1e-12, 1e-12).asDiagonal().toDenseMatrix()).inverse(), weight};
    };
    // Each prediction's search: headings (and positions) within search_sigmas of its covariance.
    const auto search = [&](const Prediction& p, bool widest) {
      const double window = widest ? options_.search_window_max_rad
                                   : std::min(options_.search_window_max_rad,
                                              options_.search_sigmas * std::sqrt(p.covariance(2, 2)));
      const double sigma_xy = std::sqrt(std::max(p.covariance(0, 0), p.covariance(1, 1)));
      const double window_xy =
          widest ? options_.search_window_xy_m : std::min(options_.search_window_xy_m, options_.search_sigmas * sigma_xy);
      std::vector<MapMatcher::Candidate> candidates;
      if (correlative && options_.search_window_max_rad >= step) {
        // (The prior's weight against the kernel of the searched subset of the points.)
        candidates = match.SearchPoses(p.pose, p.covariance, window, window_xy,
                                       weight * static_cast<double>(searched) / static_cast<double>(points.size()),
                                       points, stride);
      } else if (window >= step) {
        candidates = match.SearchHeading(p.pose, window, widest ? options_.match_distance_start_m / 2 : 0.0, points,
                                         stride);
      }
      if (candidates.empty()) candidates.push_back({p.pose, match.KernelScore(p.pose, points, stride)});
      return candidates;
    };
    std::vector<std::vector<MapMatcher::Candidate>> searches;
    for (const Prediction& p : predictions) searches.push_back(search(p, false));
    u.searches = options_.search_window_max_rad >= step ? 1 : 0;
    u.predictions = static_cast<int>(predictions.size());
    // A prediction's match: ICP from its search's maxima, then the gate and the ambiguity test.
    struct Match {
      MapMatcher::Icp icp;
      MatchOutcome outcome = MatchOutcome::kNoMatch;
      Pose2 start;
      double fit = 0, ambiguity = 0, mahalanobis2 = 0;
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // the measurement's
      int recoveries = 0;
      bool odometry_outlier = false;  // accepted against the widened prediction (outlier_scale)
      // The distinct alternatives inside the gate and their probabilities relative to the best.
      std::vector<std::pair<Pose2, double>> alternatives;
    };
    MapMatcher::RefineCounts counts;
    const auto match_from = [&](const Prediction& prediction, const std::vector<MapMatcher::Candidate>& candidates) {
      Match m;
      std::vector<MapMatcher::Icp> others;
      m.start = prediction.pose;
      const MapMatcher::Prior prior = prior_of(prediction);
      m.icp = match.RefineBest(candidates, points, normals, &m.start, &counts, &others, &prior);
      m.fit = !m.icp.ok ? 0.0 : m.icp.scored ? m.icp.fit : match.Fit(m.icp.estimate, points, 1);
      if (m.fit < options_.recovery_fit && options_.search_window_max_rad >= step) {
        // Poor fit: the largest window around the prediction, its prior kept (a far match has to
        // fit much better to win, and then pass the gate).
        std::vector<MapMatcher::Icp> again_others;
        Pose2 again_start = prediction.pose;
        const MapMatcher::Icp again =
            match.RefineBest(search(prediction, true), points, normals, &again_start, &counts, &again_others, &prior);
        const double again_fit = !again.ok ? 0.0 : again.scored ? again.fit : match.Fit(again.estimate, points, 1);
        ++m.recoveries;
        if (again_fit > m.fit) {
          m.icp = again;
          others = std::move(again_others);
          m.start = again_start;
          m.fit = again_fit;
        }
      }
      if (!m.icp.ok) return m;
      if (!m.icp.scored) match.ScoreEstimate(points, &m.icp);
      // ICP's covariance: its information, less where the residuals are larger than the points' noise.
      Eigen::Matrix3d info = m.icp.info / std::max(1.0, m.icp.residual2 / m.icp.weight_sum);
      info += Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();  // unobservable directions: huge R, not singular
      m.covariance = info.inverse();
      // The innovation's squared Mahalanobis distance (innovation covariance P + R).
      const Eigen::Matrix3d s_inv = (prediction.covariance + m.covariance).inverse();
      const auto mahalanobis2 = [&](const Pose2& z) {
        const Eigen::Vector3d v(z.x_m - prediction.pose.x_m, z.y_m - prediction.pose.y_m,
                                WrapAngle(z.theta_rad - prediction.pose.theta_rad));
        return v.dot(s_inv * v);
      };
      m.mahalanobis2 = mahalanobis2(m.icp.estimate);
      // Ambiguity: of the other results that lie apart from this one and inside the gate, the
      // best's probability relative to this one's (their posteriors' difference in nats).
      for (const MapMatcher::Icp& o : others) {
        const bool apart = std::hypot(o.estimate.x_m - m.icp.estimate.x_m, o.estimate.y_m - m.icp.estimate.y_m) >
                               2 * options_.search_sigma_m ||
                           std::abs(WrapAngle(o.estimate.theta_rad - m.icp.estimate.theta_rad)) > 5 * step;
        if (!apart) continue;
        if (options_.gate_mahalanobis2 > 0 && mahalanobis2(o.estimate) > options_.gate_mahalanobis2) continue;
        const double relative = std::exp(std::min(0.0, (o.posterior - m.icp.posterior) / weight));
        m.ambiguity = std::max(m.ambiguity, relative);
        m.alternatives.emplace_back(o.estimate, relative);
      }
      if (m.fit < options_.min_fit) {
        m.outcome = MatchOutcome::kNoMatch;
      } else if (options_.gate_mahalanobis2 > 0 &&
                 m.mahalanobis2 > options_.gate_mahalanobis2 *
                                      (options_.gate_full_fit > 0 ? std::min(1.0, m.fit / options_.gate_full_fit) : 1.0)) {
        m.outcome = MatchOutcome::kGated;
        // Odometry has heavy tails (read at the wrong moment, a wheel slipping): a strong,
        // unambiguous match is kept if the prediction's error is within outlier_scale of its
        // standard deviations; the prediction is then widened that much.
        const double k2 = options_.outlier_scale * options_.outlier_scale;
        if (options_.outlier_scale > 1 && m.fit >= options_.outlier_min_fit && m.ambiguity < options_.max_ambiguity) {
          const Eigen::Vector3d v(m.icp.estimate.x_m - prediction.pose.x_m, m.icp.estimate.y_m - prediction.pose.y_m,
                                  WrapAngle(m.icp.estimate.theta_rad - prediction.pose.theta_rad));
          if (v.dot((k2 * prediction.covariance + m.covariance).inverse() * v) <= options_.gate_mahalanobis2) {
            m.outcome = MatchOutcome::kAccepted;
            m.odometry_outlier = true;
          }
        }
      } else if (options_.max_ambiguity < 1 && m.ambiguity >= options_.max_ambiguity) {
        m.outcome = MatchOutcome::kAmbiguous;
      } else {
        m.outcome = MatchOutcome::kAccepted;
      }
      return m;
    };
    // The default prediction is odometry's, or after stale scans the catch-up (odometry that froze
    // while the scans saw the robot move reports the whole motion when it moves again). Another is
    // tried where the scan fits it clearly better in the search, and taken if its match is accepted
    // and strong (outlier_min_fit); else the filter stays with (or coasts on) the default.
    for (size_t k = 0; k < predictions.size(); ++k) {
      if (predictions[k].source == PredictionSource::kCatchUp) chosen = k;
    }
    const size_t fallback = chosen;
    Match result = match_from(predictions[chosen], searches[chosen]);
    // Each search's best, on every point: its posterior in nats.
    const auto nats = [&](size_t k) {
      const MapMatcher::Candidate& c = searches[k].front();
      return (match.KernelScore(c.pose, points, 1) - prior_of(predictions[k]).Penalty(c.pose)) / weight;
    };
    size_t contender = fallback;
    if (predictions.size() > 1) {
      double contender_nats = nats(fallback) + std::log(options_.hypothesis_odds);
      for (size_t k = 0; k < predictions.size(); ++k) {
        if (k == fallback) continue;
        const double n = nats(k);
        if (n > contender_nats) {
          contender_nats = n;
          contender = k;
        }
      }
    }
    if (contender != fallback) {
      Match other = match_from(predictions[contender], searches[contender]);
      if (other.outcome == MatchOutcome::kAccepted && other.fit >= options_.outlier_min_fit) {
        result = std::move(other);
        chosen = contender;
      }
    }
    const Prediction& prediction = predictions[chosen];
    if (use_walls && result.icp.ok &&
        (result.outcome == MatchOutcome::kAccepted || result.outcome == MatchOutcome::kAmbiguous)) {
      // The walls' directions at the prediction: a heading reference the local map's drift does not
      // move. Where they agree with the prediction, a match that turns the heading away from them
      // (beyond both measurements' errors) is the odd one out: gated.
      const WallMeasurement w = AlignWalls(wall_directions, prediction.pose, prediction.covariance);
      const double rw = options_.wall_sigma_rad * options_.wall_sigma_rad;
      if (w.aligned && w.trusted &&
          w.offset_rad * w.offset_rad / (prediction.covariance(2, 2) + rw) <= options_.wall_gate_mahalanobis2) {
        const double turn = WrapAngle(result.icp.estimate.theta_rad - prediction.pose.theta_rad) - w.offset_rad;
        if (turn * turn / (result.covariance(2, 2) + rw) > options_.wall_gate_mahalanobis2) {
          result.outcome = MatchOutcome::kGated;
          u.wall_gated = true;
        }
      }
    }
    pose_ = prediction.pose;
    covariance_ = prediction.covariance;
    if (result.odometry_outlier) {
      covariance_ *= options_.outlier_scale * options_.outlier_scale;
      u.widened = true;
    }
    u.prediction = prediction.source;
    u.stale_odometry = prediction.source == PredictionSource::kStale;
    u.predicted = pose_;
    u.predicted_covariance = covariance_;
    const MapMatcher::Icp& icp = result.icp;
    u.start = result.start;
    u.fit = result.fit;
    u.recoveries = result.recoveries;
    u.starts = counts.starts;
    u.pruned = counts.pruned;
    u.iterations = icp.iterations;
    u.matches = icp.matches;
    u.outcome = result.outcome;
    if (icp.ok) {
      u.kernel = icp.kernel / static_cast<double>(std::max<size_t>(1, points.size()));
      u.measurement = icp.estimate;
      u.measurement_covariance = result.covariance;
      u.mahalanobis2 = result.mahalanobis2;
      u.ambiguity = result.ambiguity;
    }
    if (u.outcome == MatchOutcome::kAmbiguous && options_.ambiguous_update) {
      // The mixture of the best and its alternatives (moment matched): the mean, and the
      // measurement's covariance plus their spread about it. Where they lie along a corridor,
      // the update constrains the heading and the position across it, and barely along it.
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      double total = 1;
      const auto offset = [&](const Pose2& z) {
        return Eigen::Vector3d(z.x_m - icp.estimate.x_m, z.y_m - icp.estimate.y_m,
                               WrapAngle(z.theta_rad - icp.estimate.theta_rad));
      };
      for (const auto& [z, w] : result.alternatives) {
        mean += w * offset(z);
        total += w;
      }
      mean /= total;
      Eigen::Matrix3d spread = mean * mean.transpose();  // the best's own (weight 1)
      for (const auto& [z, w] : result.alternatives) {
        const Eigen::Vector3d d = offset(z) - mean;
        spread += w * d * d.transpose();
      }
      spread /= total;
      u.measurement = Pose2{icp.estimate.x_m + mean(0), icp.estimate.y_m + mean(1),
                            WrapAngle(icp.estimate.theta_rad + mean(2))};
      u.measurement_covariance = result.covariance + spread;
      u.measured = true;
      pose_ = EkfPoseUpdate(pose_, &covariance_, u.measurement, u.measurement_covariance);
    }
    if (u.outcome == MatchOutcome::kAccepted) {
      u.measured = true;
      const Pose2 predicted = pose_;
      const Eigen::Matrix3d predicted_covariance = covariance_;
      pose_ = EkfPoseUpdate(pose_, &covariance_, icp.estimate, u.measurement_covariance);
      if (options_.update_score_margin > 0) {
        // The update should sit where the scan fits: if it scores clearly below the ICP pose
        // against the map, the prediction was off by more than its covariance allowed (odometry
        // jitter along a corridor, a late turn); widen it by the innovation and update again.
        const double at_icp = icp.score;
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
      // The pose is known relative to the map no better than the map is known (its walls placed
      // by earlier scans): the updated covariance keeps that much.
      // A floor, not an addition per scan (that would be a random walk growing with the scan rate),
      // in proportion to the interval's motion as the interval's own noise (a dense log's scans
      // see the map from nearly the same place: its local error is nearly the same).
      const double share = IntervalShare(anchor_path_m_, anchor_turn_rad_);
      const double fxy = share * options_.match_sigma_xy_m, fth = share * options_.match_sigma_theta_rad;
      const Eigen::Vector3d floor2(fxy * fxy, fxy * fxy, fth * fth);
      for (int i = 0; i < 3; ++i) covariance_(i, i) = std::max(covariance_(i, i), floor2(i));
    }
  }
  if (use_walls && u.outcome != MatchOutcome::kMapStart) {
    // The heading measured by the walls at the updated pose (the prediction's, when coasting).
    const WallMeasurement w = AlignWalls(wall_directions, pose_, covariance_);
    u.wall_offset_rad = w.offset_rad;
    u.wall_contrast = w.contrast;
    u.wall_measured = w.aligned && ApplyWalls(w.offset_rad, &pose_, &covariance_);
  }
  coasting_ = u.outcome == MatchOutcome::kAccepted || u.outcome == MatchOutcome::kMapStart ? 0 : coasting_ + 1;
  if (options_.adaptive_motion_noise && u.predictions == 1 &&
      (u.outcome == MatchOutcome::kAccepted || u.outcome == MatchOutcome::kGated) && !u.widened) {
    // Innovation-based adaptation (Mehra 1972): the squared Mahalanobis distance per degree of
    // freedom averages 1 when the noise is right; the odometry noise scale follows its running
    // mean (a wrong match's counts at most 10), within its bounds.
    const double q = std::min(10.0, u.mahalanobis2 / 3);
    const double n = std::max(1.0, options_.adaptive_window_scans);
    const double lo = options_.adaptive_scale_min * options_.adaptive_scale_min;
    const double hi = options_.adaptive_scale_max * options_.adaptive_scale_max;
    motion_scale2_ = std::clamp(motion_scale2_ * (1 + (q - 1) / n), lo, hi);
  }
  u.motion_noise_scale = std::sqrt(motion_scale2_ * calibration_.NoiseScale2());
  u.coasting = coasting_;
  ObserveStretch(&u, (u.outcome == MatchOutcome::kAccepted && u.fit >= options_.outlier_min_fit && !u.widened &&
                      predictions[chosen].source == PredictionSource::kOdometry) ||
                         u.outcome == MatchOutcome::kMapStart);
  // The stale-odometry state: a stale prediction taken starts (or continues) it; odometry's or the
  // catch-up ends it.
  if (predictions[chosen].source == PredictionSource::kStale) {
    if (!stale_since_) {
      stale_since_ = *last_scan_pose_;
      odometry_since_stale_ = {};
    }
    odometry_since_stale_ = odometry_since_stale_.Compose(odometry_since_scan_);
  } else {
    stale_since_.reset();
  }
  previous_odometry_turn_rad_ = odometry_since_scan_.theta_rad;
  odometry_since_scan_ = {};
  if (last_scan_pose_) last_motion_ = last_scan_pose_->Between(pose_);
  last_scan_pose_ = pose_;
  Reanchor();
  if (!MayAddPoints(u)) return u;
  // Points with no map point near them join the map at the updated pose, with their normals.
  const double c = std::cos(pose_.theta_rad), s = std::sin(pose_.theta_rad);
  const Eigen::Vector2d t(pose_.x_m, pose_.y_m);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d w = RotateBy(c, s, points[i]) + t;
    if (map_.size() > 0 && map_.HasPointWithin(w, options_.add_distance_m)) continue;
    if (map_.Add(w, RotateBy(c, s, normals[i]))) {
      ++u.added;
      if (!wall_directions.empty()) walls_.AddDirection(wall_directions[i] + pose_.theta_rad);
    }
  }
  return u;
}

double MotionHeadingVariance(const DeadReckoningOptions& motion, double path_m, double turn_rad) {
  const double a = motion.rotation_noise_rad_per_rad * turn_rad, b = motion.rotation_noise_rad_per_m * path_m;
  return a * a + b * b;
}

void LaserSlam::ObserveStretch(LaserSlamUpdate* u, bool good) {
  // A stretch of good matches from one scan pose to another is one observation of odometry's
  // error; a scan that is not good ends it unobserved, and the next good one starts another.
  bool restart = true;
  if (!good) {
    stretch_start_.reset();
  } else if (!stretch_start_) {
    stretch_start_ = pose_;
  } else if (calibration_.LongEnough(stretch_path_m_, stretch_turn_rad_)) {
    calibration_.Observe(stretch_raw_, stretch_path_m_, stretch_turn_rad_, stretch_start_->Between(pose_),
                         MotionHeadingVariance(options_.motion, stretch_path_m_, stretch_turn_rad_));
    stretch_start_ = pose_;
  } else {
    restart = false;  // too short yet: the stretch goes on
  }
  if (restart) {
    stretch_raw_ = {};
    stretch_path_m_ = stretch_turn_rad_ = 0;
  }
  u->odometry_drift_rad_per_m = calibration_.drift_rad_per_m();
  u->odometry_turn_scale = calibration_.turn_scale();
  u->odometry_distance_scale = calibration_.distance_scale();
  u->odometry_calibration_stretches = calibration_.observations();
}

LaserSlam::WallMeasurement LaserSlam::AlignWalls(const std::vector<double>& directions_robot, const Pose2& pose,
                                                  const Eigen::Matrix3d& covariance) const {
  WallMeasurement w;
  const auto a = walls_.Align(directions_robot, pose.theta_rad, options_.wall_window_rad);
  if (!a) return w;
  w.offset_rad = a->offset_rad;
  w.contrast = a->contrast;
  w.aligned = a->contrast >= options_.wall_min_contrast;
  // The alignment looks within +-wall_window_rad: it is the walls' own offset (not another direction
  // of the map's) when the heading is known to half of that.
  w.trusted = 2 * std::sqrt(covariance(2, 2)) <= options_.wall_window_rad;
  return w;
}

bool LaserSlam::ApplyWalls(double offset_rad, Pose2* pose, Eigen::Matrix3d* covariance) const {
  const double s2 = (*covariance)(2, 2) + options_.wall_sigma_rad * options_.wall_sigma_rad;
  if (offset_rad * offset_rad / s2 > options_.wall_gate_mahalanobis2) return false;
  // A heading-only EKF update: H = [0 0 1].
  const Eigen::Vector3d k = covariance->col(2) / s2;
  *pose = {pose->x_m + k(0) * offset_rad, pose->y_m + k(1) * offset_rad, WrapAngle(pose->theta_rad + k(2) * offset_rad)};
  const Eigen::RowVector3d row = covariance->row(2);
  *covariance -= k * row;
  *covariance = 0.5 * (*covariance + covariance->transpose()).eval();
  return true;
}

// ---- For filters built on this one (nav::FusedSlam).

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
  if (stretch_start_) stretch_start_ = carry(*stretch_start_);
  scan_pose_ = carry(scan_pose_);
  Reanchor();
}

void LaserSlam::SetMapping(bool add_points, double min_fit) {
  if (!(min_fit >= 0 && min_fit <= 1)) throw std::invalid_argument("laser slam: mapping min_fit must be in [0, 1]");
  add_points_ = add_points;
  min_add_fit_ = min_fit;
}

bool LaserSlam::MayAddPoints(const LaserSlamUpdate& u) const {
  if (!add_points_) return false;
  // A match that conflicts with the prediction, or another match, is not drawn into the map.
  if (u.outcome == MatchOutcome::kGated || u.outcome == MatchOutcome::kAmbiguous) return false;
  return map_.size() == 0 || u.fit >= min_add_fit_;
}

}  // namespace snapnav::nav
