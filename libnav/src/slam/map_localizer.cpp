#include "snapnav/nav/slam/map_localizer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_set>

#include "snapnav/nav/covariance.hpp"
#include "snapnav/nav/slam/cell_key.hpp"
#include "snapnav/nav/slam/map_matcher.hpp"

namespace snapnav::nav {

const char* LocalizationStateName(LocalizationState s) {
  switch (s) {
    case LocalizationState::kLost: return "lost";
    case LocalizationState::kLocalized: return "localized";
  }
  return "?";
}

void MapLocalizerOptions::Validate() const {
  tracking.Validate();
  global.Validate();
  const auto unit = [](double v, const char* name) {
    if (!(v >= 0 && v <= 1)) throw std::invalid_argument(std::string("localize: ") + name + " must be in [0, 1]");
  };
  unit(min_global_score, "min_global_score");
  unit(max_global_ambiguity, "max_global_ambiguity");
  unit(accept_fit, "accept_fit");
  unit(lost_fit, "lost_fit");
  if (lost_after_scans < 1) throw std::invalid_argument("localize: lost_after_scans must be >= 1");
  if (window_scans < 1 || window_scans > 1000) throw std::invalid_argument("localize: window_scans must be in [1, 1000]");
  if (!(window_m >= 0)) throw std::invalid_argument("localize: window_m must be >= 0");
  if (!(reset_sigma_xy_m > 0) || !(reset_sigma_theta_rad > 0))
    throw std::invalid_argument("localize: reset_sigma_xy_m and reset_sigma_theta_deg must be positive");
}

std::vector<Eigen::Vector2d> OccupiedCellCentres(const OccupancyCells& map, double occupied_threshold) {
  std::vector<Eigen::Vector2d> points;
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (map.at(x, y) >= 100.0 * occupied_threshold) {
        points.emplace_back(map.origin_x_m + (x + 0.5) * map.resolution_m, map.origin_y_m + (y + 0.5) * map.resolution_m);
      }
    }
  }
  return points;
}

namespace {

// Unit normals of the occupied cells from their occupied neighbours within 2 cells (principal
// axes); zero where they do not lie on a line.
std::vector<Eigen::Vector2d> CellNormals(const OccupancyCells& map, double occupied_threshold) {
  std::vector<Eigen::Vector2d> normals;
  const auto occupied = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < map.width && y < map.height && map.at(x, y) >= 100.0 * occupied_threshold;
  };
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (!occupied(x, y)) continue;
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      int n = 0;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx)
          if (occupied(x + dx, y + dy)) mean += Eigen::Vector2d(dx, dy), ++n;
      Eigen::Vector2d normal = Eigen::Vector2d::Zero();
      if (n >= 3) {
        mean /= n;
        Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx)
            if (occupied(x + dx, y + dy)) {
              const Eigen::Vector2d d = Eigen::Vector2d(dx, dy) - mean;
              c += d * d.transpose();
            }
        const SymmetricEigen2 es = EigenOfSymmetric(c);
        if (es.values(0) < 0.2 * es.values(1)) normal = es.vectors.col(0).normalized();
      }
      normals.push_back(normal);
    }
  }
  return normals;
}

}  // namespace

MapLocalizer::MapLocalizer(const OccupancyCells& map, const MapLocalizerOptions& options) : options_(options) {
  options_.Validate();
  // The second pose matters only when it scores at least max_global_ambiguity of the best: the
  // search need not look lower for it (a tighter bound prunes far more of the tree).
  options_.global.ambiguity_floor = std::clamp(options_.max_global_ambiguity, 0.05, 0.99);
  global_ = std::make_unique<GlobalLocalizer>(map, options_.global);
  slam_.emplace(options_.tracking, Pose2{});
  slam_->SeedMap(OccupiedCellCentres(map, options_.global.occupied_threshold),
                 CellNormals(map, options_.global.occupied_threshold));
  slam_->SetMapping(false);
}

void MapLocalizer::Predict(const Pose2& odometry_delta, int64_t end_utime) {
  slam_->Predict(odometry_delta, end_utime);
  odometry_ = odometry_.Compose(odometry_delta);
  odometry_path_m_ += std::hypot(odometry_delta.x_m, odometry_delta.y_m);
}

bool MapLocalizer::Accumulate(const Pose2& found, double ambiguity, double* evidence) {
  // A search whose second is nearly as good (beyond the square root of max_global_ambiguity: two such
  // windows would not suffice) is no evidence either way: a place alike in every detail (a room
  // symmetric about its middle) stays undecided however long the robot drives.
  if (ambiguity > std::sqrt(options_.max_global_ambiguity)) {
    *evidence = evidence_ ? evidence_->ambiguity : 0;
    return false;
  }
  if (evidence_) {
    // Where the pose found before is now, by odometry since.
    const Pose2 carried = evidence_->pose.Compose(evidence_->odometry.Between(odometry_));
    const bool same = std::hypot(found.x_m - carried.x_m, found.y_m - carried.y_m) <= options_.global.distinct_m &&
                      std::abs(WrapAngle(found.theta_rad - carried.theta_rad)) <= options_.global.distinct_rad;
    if (same && scans_ - evidence_->scan < options_.window_scans) {
      *evidence = evidence_->ambiguity;  // the same window's scans again: no new evidence yet
      return false;
    }
    if (same) {
      evidence_ = Evidence{found, odometry_, scans_, evidence_->ambiguity * ambiguity};
      *evidence = evidence_->ambiguity;
      return evidence_->ambiguity <= options_.max_global_ambiguity;
    }
  }
  evidence_ = Evidence{found, odometry_, scans_, ambiguity};
  *evidence = ambiguity;
  return false;
}

void MapLocalizer::SetPose(const Pose2& pose, const Eigen::Matrix3d& covariance) {
  slam_->ResetPose(pose, covariance);
  state_ = LocalizationState::kLocalized;
  bad_scans_ = 0;
}

LocalizationUpdate MapLocalizer::Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime) {
  LocalizationUpdate u;
  ++scans_;
  // The tracker runs on every scan (its odometry models stay current); its pose counts only when
  // localized.
  u.tracking = slam_->Update(points_robot, utime);
  u.fit = u.tracking.fit;

  // The window of recent scans for the global search (thinned: the search filters them again).
  {
    WindowScan w;
    w.odometry = odometry_;
    std::unordered_set<uint64_t> seen;
    const double cell = options_.global.resolution_m;
    for (const Eigen::Vector2d& p : points_robot) {
      if (seen.insert(CellKey(p, cell)).second) w.points.push_back(p);
    }
    window_.emplace_back(odometry_path_m_, std::move(w));
    while (static_cast<int>(window_.size()) > options_.window_scans ||
           (window_.size() > 1 && odometry_path_m_ - window_.front().first > options_.window_m)) {
      window_.pop_front();
    }
  }

  if (state_ == LocalizationState::kLocalized) {
    const bool bad = points_robot.empty() || u.fit < options_.lost_fit;
    bad_scans_ = bad ? bad_scans_ + 1 : 0;
    if (bad_scans_ >= options_.lost_after_scans) {
      state_ = LocalizationState::kLost;
      u.lost_now = true;
      evidence_.reset();
      ++losses_;
      // Only the scans since the trouble began belong to where the robot is now.
      while (static_cast<int>(window_.size()) > bad_scans_) window_.pop_front();
    }
  }
  u.bad_scans = bad_scans_;

  if (state_ == LocalizationState::kLost && !points_robot.empty()) {
    // The window's scans in the frame of this one, by odometry.
    std::vector<Eigen::Vector2d> points;
    const Pose2 now = window_.back().second.odometry;
    for (const auto& [_, w] : window_) {
      const Pose2 rel = now.Between(w.odometry);
      for (const Eigen::Vector2d& p : w.points) points.push_back(rel.Transform(p));
    }
    u.window_scans = static_cast<int>(window_.size());
    u.searched = true;
    ++searches_;
    u.global = global_->Search(points);
    if (u.global.found) {
      // Refined as the tracker matches: the correlative search close around it, then ICP.
      const MapMatcher matcher(slam_->map(), options_.tracking);
      const std::vector<Eigen::Vector2d> normals = ScanNormals(points_robot);
      const size_t stride = std::max<size_t>(1, points_robot.size() / 90);
      const double half = options_.global.resolution_m;
      const Eigen::Matrix3d cov = Eigen::Vector3d(half * half, half * half, std::pow(options_.global.heading_step_rad, 2)).asDiagonal();
      std::vector<MapMatcher::Candidate> candidates =
          slam_->map().has_likelihood()
              ? matcher.SearchPoses(u.global.best, cov, 2 * options_.global.heading_step_rad, 1.5 * half, 0, points_robot, stride)
              : matcher.SearchHeading(u.global.best, 2 * options_.global.heading_step_rad, half, points_robot, stride);
      if (candidates.empty()) candidates.push_back({u.global.best, 0});
      Pose2 start;
      MapMatcher::RefineCounts counts;
      MapMatcher::Icp icp = matcher.RefineBest(candidates, points_robot, normals, &start, &counts);
      if (icp.ok && !icp.scored) matcher.ScoreEstimate(points_robot, &icp);
      u.refined = icp.ok ? icp.estimate : u.global.best;
      u.refined_fit = icp.ok ? icp.fit : matcher.Fit(u.global.best, points_robot, 1);
      bool accept = false;
      if (u.global.score >= options_.min_global_score && u.refined_fit >= options_.accept_fit) {
        accept = u.global.ambiguity <= options_.max_global_ambiguity;
        if (!accept && options_.accumulate_evidence) accept = Accumulate(u.refined, u.global.ambiguity, &u.evidence);
      }
      if (accept) {
        evidence_.reset();
        const Eigen::Matrix3d reset =
            Eigen::Vector3d(std::pow(options_.reset_sigma_xy_m, 2), std::pow(options_.reset_sigma_xy_m, 2),
                            std::pow(options_.reset_sigma_theta_rad, 2))
                .asDiagonal();
        SetPose(u.refined, reset);
        u.relocalized = true;
        u.fit = u.refined_fit;
        ++relocalizations_;
      }
    }
  }
  u.state = state_;
  return u;
}

}  // namespace snapnav::nav
