#pragma once
// The directions of a map's walls, for a heading measurement that does not drift.
//
// A scan-matching filter measures its heading against the local map, which it built itself a
// little turned at every scan: the error adds up along a corridor and round a corner (0.3-0.9 deg
// a scan on the sparse CARMEN logs). A building keeps its walls parallel over a whole floor, so
// the map's own wall directions, gathered over everything mapped so far, are a reference the
// local error does not move: the scan's walls, turned by the current heading, should fall on the
// map's (modulo 180 deg, a wall has two sides). WallOrientations holds the histogram of the map's
// wall normals and aligns a scan's with it.
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace snapnav::nav {

class WallOrientations {
 public:
  // Histogram bins of bin_rad over [0, pi) (a normal and its opposite fall in the same bin); each
  // direction added is spread by a Gaussian of kernel_rad (the alignment's tolerance).
  explicit WallOrientations(double kernel_rad = 1 * kDegree, double bin_rad = 0.25 * kDegree);
  // A normal's line direction in [0, pi); NaN for a zero normal (no wall there).
  static double Direction(const Eigen::Vector2d& normal);
  // A wall point's normal (map frame; a zero normal is ignored), weighted.
  void Add(const Eigen::Vector2d& normal, double weight = 1) { AddDirection(Direction(normal), weight); }
  // The same by its Direction (NaN ignored).
  void AddDirection(double direction_rad, double weight = 1);
  void Clear();
  double total() const { return total_; }

  struct Alignment {
    double offset_rad = 0;  // turn the scan by this to align its walls with the map's
    double score = 0;       // the alignment's correlation at the offset, per unit of scan weight (0-1: the share of the
                            // scan's walls lying on the map's directions)
    double contrast = 0;    // the score over its mean across the window (1: nothing to align with)
    double ambiguity = 0;   // the best other local maximum (3 kernel widths or more away) over the best (0: none)
  };
  // The offset within +-window_rad that best aligns a scan's wall directions (Direction of its
  // normals in its own frame; NaN ignored), turned by turn_rad (its heading), with the map's walls;
  // nullopt without map or scan walls, or when the best lies at the window's edge.
  std::optional<Alignment> Align(const std::vector<double>& directions, double turn_rad, double window_rad) const;
  // The same for normals already in the map frame.
  std::optional<Alignment> Align(const std::vector<Eigen::Vector2d>& normals, double window_rad) const;

 private:
  static constexpr double kDegree = 3.14159265358979323846 / 180;
  double bin_rad_;
  double kernel_rad_;
  std::vector<double> kernel_;  // the Gaussian over 2 half + 1 bins
  // The histogram of the map's directions spread by the kernel, kept up to date by each Add (an
  // added direction touches 2 (2 half + 1) bins; re-spreading the whole histogram at every scan
  // cost a tenth of the scan's update).
  std::vector<double> smooth_;
  double total_ = 0;
  // Align's work space, kept between calls (no allocation per scan): Align is const but not for
  // concurrent calls on one object.
  mutable std::vector<double> scan_, padded_, score_;
};

}  // namespace snapnav::nav
