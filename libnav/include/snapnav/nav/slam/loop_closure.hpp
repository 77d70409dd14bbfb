#pragma once
// Loop-closure scan matching for the graph back end (GraphSlam): a scan against a submap (the
// points of a few neighbouring keyframes) over a wide window, as Olson 2009 ("Real-time
// correlative scan matching") does it: a likelihood grid of the submap (each cell
// exp(-d^2 / (2 sigma^2)), d its distance to the nearest submap point), a pyramid of grids each
// holding the maximum of the finer one over 2^k x 2^k cells, and branch and bound over the
// pyramid for every heading of the window: a coarse cell's score bounds every pose under it, so
// the exhaustive search's best pose is found while most of the window is never scored finely
// (as Cartographer's FastCorrelativeScanMatcher2D). A second search, with the best peak's
// neighbourhood excluded, finds the best distinct other pose: how ambiguous the match is.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct CorrelativeSearchOptions {
  double cell_m = 0.05;           // cell of the likelihood grid [m]
  double sigma_m = 0.05;          // kernel of a submap point [m]
  int levels = 5;                 // pyramid levels above the grid (coarsest cells 2^levels cells wide)
  double step_rad = 0.5 * 3.14159265358979323846 / 180;  // heading step
  // The second peak: the best pose at least this far from the best (in position, or in heading).
  double exclusion_m = 0.3;
  double exclusion_rad = 3 * 3.14159265358979323846 / 180;
  // Second peaks below this fraction of the best are not looked for (ambiguity reported as 0).
  double ambiguity_floor = 0.6;
};

// The likelihood grid of a submap and its pyramid.
class LikelihoodPyramid {
 public:
  // `points` in the submap's frame; the grid covers them with `margin_m` around.
  LikelihoodPyramid(const std::vector<Eigen::Vector2d>& points, const CorrelativeSearchOptions& options,
                    double margin_m);
  int width() const { return width_; }
  int height() const { return height_; }
  int levels() const { return static_cast<int>(grids_.size()) - 1; }
  double cell_m() const { return cell_; }
  const Eigen::Vector2d& origin() const { return origin_; }  // the lower left corner of cell (0, 0)
  // Level k's value at cell (ix, iy): the maximum of the grid over [ix, ix + 2^k) x [iy, iy + 2^k)
  // (0 outside the grid); 0-255 for 0-1.
  int At(int level, int ix, int iy) const {
    if (ix < -pad_ || iy < -pad_ || ix >= width_ || iy >= height_) return 0;
    return grids_[static_cast<size_t>(level)][Index(ix, iy)];
  }
  // The mean likelihood (0-1) of `points` (robot frame) at `pose` (bilinear in the finest grid).
  double Score(const Pose2& pose, const std::vector<Eigen::Vector2d>& points) const;

 private:
  double cell_;
  Eigen::Vector2d origin_;
  int width_ = 0, height_ = 0;
  int pad_ = 0, stride_ = 0;  // cells stored before the grid in x and y; a row's length
  size_t Index(int ix, int iy) const {
    return static_cast<size_t>(iy + pad_) * static_cast<size_t>(stride_) + static_cast<size_t>(ix + pad_);
  }
  std::vector<std::vector<uint8_t>> grids_;
};

struct CorrelativeSearchResult {
  bool found = false;         // a pose scored at least min_score
  Pose2 pose;                 // the best (in the pyramid's frame)
  double score = 0;           // its mean likelihood per point [0-1]
  bool second_found = false;  // a distinct pose scored at least ambiguity_floor of the best
  Pose2 second;
  double second_score = 0;
  int64_t scored = 0;         // poses scored (every level), both searches
};

// The best pose of `points` (robot frame) within +-window_xy_m and +-window_rad of `around`, and
// the best distinct other (see CorrelativeSearchOptions). Poses scoring below min_score are not
// looked for.
CorrelativeSearchResult BranchAndBoundSearch(const LikelihoodPyramid& pyramid, const std::vector<Eigen::Vector2d>& points,
                                             const Pose2& around, double window_xy_m, double window_rad,
                                             double min_score, const CorrelativeSearchOptions& options);

// A scan's points (in scan order) with points added every step_m between neighbours less than
// max_gap_m (or 5 % of their range) apart: a wall sampled sparsely far from the laser becomes a
// continuous line on the likelihood grid (not a row of peaks that make shifts along it score apart).
std::vector<Eigen::Vector2d> DensifyScan(const std::vector<Eigen::Vector2d>& points, double max_gap_m, double step_m);

// Every scan point kept at most once per cell of cell_m (the first of its cell), in scan order.
std::vector<Eigen::Vector2d> DecimatePoints(const std::vector<Eigen::Vector2d>& points, double cell_m);

}  // namespace snapnav::nav
