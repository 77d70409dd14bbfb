#pragma once
// Global localization in a fixed occupancy grid (laser-slam --mode localize): where in the whole
// map a scan fits, from no prior at all. A correlative search (Olson 2009) of every pose on the
// map's free space at a coarse grid and a set of headings, made fast by branch and bound over a
// pyramid of max-pooled likelihood grids (Hess et al. 2016, Cartographer's fast correlative
// matcher): a node of 2^h x 2^h positions at one heading scores each point at the maximum of the
// likelihood over the node's window, an upper bound of every position in it, so whole regions
// are pruned once a leaf scores above them. The search keeps the best pose and the best pose
// distinct from it (the ambiguity of the answer); the caller refines the best (ICP) and decides.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/slam/occupancy_cells.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct GlobalSearchOptions {
  double resolution_m = 0.1;       // grid of the searched positions and of the likelihood [m]
  double heading_step_rad = 0.0174533;  // headings searched: 0, step, 2 step, ... [rad] (1 deg)
  double sigma_m = 0.15;           // a point scores exp(-d^2 / (2 sigma^2)), d to the nearest occupied cell [m]
  int depth = 6;                   // levels of the pyramid above the leaves (root nodes 2^depth cells wide)
  double max_range_m = 60;         // points farther from the robot are not searched [m]
  int max_points = 250;            // at most this many points scored (a 0.1 m voxel filter, then thinned)
  double occupied_threshold = 0.65;  // a map cell at or above this occupancy is a wall [0-1]
  double free_threshold = 0.196;     // ... at or below it free: the robot may stand there [0-1]
  // The best distinct other pose: more than this far in position, or in heading, from the best.
  double distinct_m = 0.5;
  double distinct_rad = 0.26;      // 15 deg
  // The second pose is searched down to this fraction of the best's score (below it the
  // ambiguity is reported as that fraction at most).
  double ambiguity_floor = 0.5;
  void Validate() const;           // throws std::invalid_argument naming the bad option
};

struct GlobalSearchResult {
  bool found = false;
  Pose2 best;               // the robot pose of the best leaf (centre of its cell)
  double score = 0;         // its mean likelihood per point [0-1]
  bool has_second = false;
  Pose2 second;             // the best leaf distinct from it (GlobalSearchOptions::distinct_*)
  double second_score = 0;  // [0-1]
  double ambiguity = 0;     // second_score / score (0: none above the floor)
  int points = 0;           // points scored
  int64_t nodes = 0;        // nodes of the tree scored (all levels)
  int64_t leaves = 0;       // ... of them leaves
};

// The search over one fixed map: the pyramid is built once (Prepare), each Search is one scan.
class GlobalLocalizer {
 public:
  // Throws std::invalid_argument on bad options or an empty map (no occupied or no free cell).
  GlobalLocalizer(const OccupancyCells& map, const GlobalSearchOptions& options);

  // The best robot pose for these points (robot frame) anywhere on the map's free space.
  GlobalSearchResult Search(const std::vector<Eigen::Vector2d>& points_robot) const;

  int width() const { return width_; }    // cells of the search grid (padding included)
  int height() const { return height_; }
  int64_t free_cells() const { return free_cells_; }  // candidate positions
  size_t memory_bytes() const;
  const GlobalSearchOptions& options() const { return options_; }
  // The likelihood of a world point on the finest level (0-1; tests, figures).
  double Likelihood(double x_m, double y_m) const;

 private:
  struct Node {
    int x = 0, y = 0, heading = 0, level = 0;
    int score = 0;  // sum of the level's bytes over the points
  };
  struct Best {
    bool found = false;
    int x = 0, y = 0, heading = 0;
    int score = 0;
  };
  int ScoreAt(const std::vector<int>& offsets, int level, int x, int y) const;
  bool Distinct(const Best& a, int x, int y, int heading) const;
  Pose2 PoseOf(int x, int y, int heading) const;

  GlobalSearchOptions options_;
  int width_ = 0, height_ = 0, pad_ = 0;
  double origin_x_ = 0, origin_y_ = 0;  // world corner of search cell (0, 0) (padding included)
  int headings_ = 0;
  // levels_[h][y * width_ + x]: the max of the likelihood (0-255) over the cells [x, x + 2^h) x
  // [y, y + 2^h); free_[h]: whether a free cell lies in that window.
  std::vector<std::vector<uint8_t>> levels_, free_;
  int64_t free_cells_ = 0;
};

}  // namespace snapnav::nav
