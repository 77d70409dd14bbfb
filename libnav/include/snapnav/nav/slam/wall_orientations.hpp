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
  // Histogram bins of bin_rad over [0, pi) (a normal and its opposite fall in the same bin).
  explicit WallOrientations(double bin_rad = 0.25 * 3.14159265358979323846 / 180);
  // A wall point's normal (map frame; a zero normal is ignored), weighted.
  void Add(const Eigen::Vector2d& normal, double weight = 1);
  void Clear();
  double total() const { return total_; }

  struct Alignment {
    double offset_rad = 0;  // turn the scan by this to align its walls with the map's
    double score = 0;       // the alignment's correlation at the offset, per unit of scan weight (0-1: the share of the
                            // scan's walls lying on the map's directions)
    double contrast = 0;    // the score over its mean across the window (1: nothing to align with)
    double ambiguity = 0;   // the best other local maximum (3 kernel widths or more away) over the best (0: none)
  };
  // The offset within +-window_rad that best aligns `normals` (map frame at the current heading;
  // zero normals ignored) with the map's walls, each map direction spread by a Gaussian of
  // kernel_rad; nullopt without map or scan walls.
  std::optional<Alignment> Align(const std::vector<Eigen::Vector2d>& normals, double window_rad,
                                 double kernel_rad) const;

 private:
  double bin_rad_;
  std::vector<double> bins_;
  double total_ = 0;
  // The histogram spread by the kernel and normalised (Align), kept until a normal is added.
  mutable std::vector<double> smooth_;
  mutable double smooth_kernel_rad_ = 0;
  mutable bool smooth_valid_ = false;
};

}  // namespace snapnav::nav
