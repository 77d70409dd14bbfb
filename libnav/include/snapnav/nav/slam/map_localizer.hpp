#pragma once
// Localization in a fixed, saved map (laser-slam --mode localize; as MRPT's pf-localization or
// ROS's AMCL): the robot's pose against a map made before, the map never updated.
//
// Two states. LOST (at the start: the pose is unknown; or after tracking failed): each scan, the
// last few scans chained by odometry (window_scans, window_m) are searched for over the whole
// map's free space (GlobalLocalizer: branch and bound over a likelihood pyramid, every heading);
// the best pose is refined against the map (the scan matcher's correlative search and ICP, as the
// tracker matches) and accepted only when its score is high enough (min_global_score), no
// distinct other pose scores nearly as well (max_global_ambiguity) and the refined scan fits the
// map (accept_fit); otherwise the search goes on with the next scans. LOCALIZED: laser SLAM's
// EKF and robust scan matcher (LaserSlam, its map the saved one, mapping off) track the pose
// from odometry and each scan; a scan whose fit to the map falls below lost_fit is bad, and
// lost_after_scans bad scans in a row (a kidnapping, a map that no longer holds) mean LOST again.
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/slam/global_localizer.hpp"
#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/slam/occupancy_cells.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct MapLocalizerOptions {
  LaserSlamOptions tracking;     // the tracker (laser_slam.ini's [laser_slam]); its map options are the saved map's
  GlobalSearchOptions global;    // the global search (its ambiguity_floor is set to max_global_ambiguity)
  double min_global_score = 0.5;      // a global search's best is taken only at or above this mean likelihood [0-1]
  double max_global_ambiguity = 0.8;  // ... and when the best distinct other pose scores below this fraction of it [0-1]
  // ... or, where the place is alike elsewhere (a repeated hall), when searches over independent
  // windows (at least window_scans apart) keep finding the same pose, carried on by odometry (within
  // the search's distinct_m and distinct_rad), and the product of their ambiguities is below
  // max_global_ambiguity (each search's best against its second as independent evidence; a search
  // whose ambiguity is above the square root of max_global_ambiguity counts for nothing, so a place
  // alike in every detail stays undecided). false: each search alone.
  bool accumulate_evidence = true;
  double accept_fit = 0.6;            // ... and when the refined scan's fit (points within match_distance_m / 2 of the map) is at least this [0-1]
  double lost_fit = 0.3;              // a tracked scan that fits less than this is bad [0-1]
  int lost_after_scans = 5;           // this many bad scans in a row: lost [count]
  int window_scans = 10;              // the global search matches the last this many scans together (odometry-chained) [count]
  double window_m = 3;                // ... that lie within this much travel [m]
  double reset_sigma_xy_m = 0.05;     // the tracker restarts from an accepted global pose with these std. devs. [m]
  double reset_sigma_theta_rad = 2 * kRadPerDeg;
  void Validate() const;              // throws std::invalid_argument naming the bad option
};

enum class LocalizationState { kLost, kLocalized };
const char* LocalizationStateName(LocalizationState s);

struct LocalizationUpdate {
  LocalizationState state = LocalizationState::kLost;  // after this scan
  bool searched = false;      // a global search ran on this scan
  bool relocalized = false;   // ... and its pose was accepted
  bool lost_now = false;      // tracking was declared lost at this scan
  GlobalSearchResult global;  // the search's result (searched)
  double evidence = 0;        // the ambiguities' product over the searches that found this pose (accumulate_evidence; 0: none)
  double refined_fit = 0;     // the refined global pose's fit (searched)
  Pose2 refined;              // ... the pose
  double fit = 0;             // the tracker's fit of this scan [0-1]
  int bad_scans = 0;          // bad scans in a row
  int window_scans = 0;       // scans the search matched together
  LaserSlamUpdate tracking;   // the tracker's update
};

class MapLocalizer {
 public:
  // `map`: the saved map's cells. Throws std::invalid_argument on bad options or a map without
  // occupied or free cells.
  MapLocalizer(const OccupancyCells& map, const MapLocalizerOptions& options);

  void Predict(const Pose2& odometry_delta, int64_t end_utime);
  LocalizationUpdate Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime);
  // Starts tracking from a given pose (an operator's guess), as if a global search had found it.
  void SetPose(const Pose2& pose, const Eigen::Matrix3d& covariance);

  LocalizationState state() const { return state_; }
  const Pose2& pose() const { return slam_->pose(); }
  const Eigen::Matrix3d& covariance() const { return slam_->covariance(); }
  int64_t scans() const { return scans_; }
  int64_t global_searches() const { return searches_; }
  int64_t relocalizations() const { return relocalizations_; }
  int64_t losses() const { return losses_; }
  size_t map_points() const { return slam_->map().size(); }
  const GlobalLocalizer& global() const { return *global_; }
  const MapLocalizerOptions& options() const { return options_; }

 private:
  struct WindowScan {
    Pose2 odometry;                        // odometry's pose at the scan (its own frame)
    std::vector<Eigen::Vector2d> points;   // thinned, robot frame
  };
  MapLocalizerOptions options_;
  std::unique_ptr<GlobalLocalizer> global_;
  std::optional<LaserSlam> slam_;
  LocalizationState state_ = LocalizationState::kLost;
  Pose2 odometry_;                 // odometry's increments chained
  double odometry_path_m_ = 0;     // ... and its path length
  std::deque<std::pair<double, WindowScan>> window_;  // (path length at the scan, scan)
  int bad_scans_ = 0;
  // accumulate_evidence: whether the pose `found` with this ambiguity, with what the searches before
  // found, is enough (the product so far in *evidence).
  bool Accumulate(const Pose2& found, double ambiguity, double* evidence);
  int64_t scans_ = 0, searches_ = 0, relocalizations_ = 0, losses_ = 0;
  // accumulate_evidence: the pose the searches keep finding, where it was found (map frame and
  // odometry), the scan, and the product of the ambiguities so far.
  struct Evidence {
    Pose2 pose, odometry;
    int64_t scan = 0;
    double ambiguity = 1;
  };
  std::optional<Evidence> evidence_;
};

// The map points the tracker matches against: the centre of every occupied cell (at or above
// occupied_threshold).
std::vector<Eigen::Vector2d> OccupiedCellCentres(const OccupancyCells& map, double occupied_threshold);

}  // namespace snapnav::nav
