#pragma once
// 2D laser SLAM with an EKF on the robot pose (thesis 5.3.1).
//
// The state is the robot pose (x, y, theta) with its covariance. Odometry predicts it
// (PredictWithOdometry, motion noise growing with distance and rotation). Each scan's
// points are matched to their nearest map points within match_distance_m; a closed-form
// 2D alignment of the matches, iterated (ICP), gives a pose measurement whose covariance
// comes from the residuals and the match geometry; the EKF update fuses it with the
// prediction; scan points with no map point near them are added to the map at the
// updated pose. The map is a hash grid of cells of map_resolution_m holding one point
// each: nearest-neighbour queries and insertions cost O(1), and the map cannot grow
// faster than the area explored.

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// The EKF update with a direct pose measurement z (H = I): K = P (P + R)^-1. The angle
// innovation is wrapped. Returns the updated pose; `covariance` is updated in place.
Pose2 EkfPoseUpdate(const Pose2& pose, Eigen::Matrix3d* covariance, const Pose2& z, const Eigen::Matrix3d& r);

// The rigid transform T minimising sum |T(src_i) - dst_i|^2 (closed form, 2D Kabsch).
// nullopt with fewer than 2 pairs or a degenerate (single-point) source.
std::optional<Pose2> AlignPoints(const std::vector<Eigen::Vector2d>& src, const std::vector<Eigen::Vector2d>& dst);

// Laser ranges to points in the robot frame: beams with NaN, infinite, below range_min or
// at/above range_max (no return) are dropped. `sensor` is the laser's pose on the robot.
std::vector<Eigen::Vector2d> ScanToPoints(const std::vector<float>& ranges_m, double angle_min_rad,
                                          double angle_increment_rad, double range_min_m, double range_max_m,
                                          const Pose2& sensor = {});

// A point map on two hash grids: at most one point per cell of resolution_m (decimation),
// and buckets of bucket_m for nearest-neighbour queries (3 x 3 buckets cover a query radius
// up to bucket_m).
class PointGridMap {
 public:
  PointGridMap(double resolution_m, double bucket_m);
  // Adds p unless its cell is taken; returns whether it was added.
  bool Add(const Eigen::Vector2d& p);
  // The nearest stored point within max_distance_m, if any.
  std::optional<Eigen::Vector2d> Nearest(const Eigen::Vector2d& p, double max_distance_m) const;
  // Whether a stored point lies within `distance_m` of p.
  bool HasPointWithin(const Eigen::Vector2d& p, double distance_m) const { return Nearest(p, distance_m).has_value(); }
  size_t size() const { return points_.size(); }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }
  double resolution_m() const { return resolution_; }

 private:
  static uint64_t Key(int64_t ix, int64_t iy) {
    return (static_cast<uint64_t>(ix) << 32) ^ (static_cast<uint64_t>(iy) & 0xffffffffULL);
  }
  double resolution_, bucket_;
  std::unordered_map<uint64_t, uint32_t> cells_;                 // fine cell -> index in points_
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets_;  // bucket -> indices in points_
  std::vector<Eigen::Vector2d> points_;
};

struct LaserSlamOptions {
  DeadReckoningOptions motion;              // odometry noise Q (prediction)
  double initial_sigma_xy_m = 0.01;         // initial covariance
  double initial_sigma_theta_rad = 0.01;
  double match_distance_m = 0.25;           // a scan point matches a map point closer than this
  int icp_iterations = 15;
  double icp_convergence_m = 1e-4;          // stop when an iteration moves less than this
  double point_sigma_m = 0.03;              // noise of one matched point, floor of the residual estimate
  int min_matches = 20;                     // fewer: no measurement this scan (prediction only)
  double map_resolution_m = 0.05;           // grid cell of the map (decimation)
  double add_distance_m = 0.08;             // a scan point is new if no map point is this close
  int scan_step = 1;                        // use every n-th point of a scan
  void Validate() const;                    // throws std::invalid_argument
};

struct LaserSlamUpdate {
  bool measured = false;       // the scan gave a pose measurement
  int points = 0, matches = 0, added = 0, iterations = 0;
  Pose2 measurement;           // the ICP pose
  Eigen::Matrix3d measurement_covariance = Eigen::Matrix3d::Zero();
};

class LaserSlam {
 public:
  explicit LaserSlam(const LaserSlamOptions& options, const Pose2& start = {});

  // EKF prediction from one odometry increment (robot frame).
  void Predict(const Pose2& odometry_delta);
  // EKF update from one scan (points in the robot frame). The first scan only builds the map.
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot);

  const Pose2& pose() const { return pose_; }
  const Eigen::Matrix3d& covariance() const { return covariance_; }
  const PointGridMap& map() const { return map_; }
  int64_t scans() const { return scans_; }

 private:
  LaserSlamOptions options_;
  Pose2 pose_;
  Eigen::Matrix3d covariance_;
  PointGridMap map_;
  int64_t scans_ = 0;
};

}  // namespace snapnav::nav
