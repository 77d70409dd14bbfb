#pragma once
// Snapshot homing with HOG landmarks (thesis chapter 3).
//
// The band of a panorama (3.1.1) is divided into cells; each cell holds a
// histogram of oriented gradients (centred gradient filter, signed orientation
// over 360 degrees in `bins` sectors). The visual compass (3.1.2) finds the
// column shift that minimises the distance between the cell descriptors of
// two panoramas. The HOG average landmark vector (3.1.3) of bin q is
// ALV_q = sum_p |H_qp| (cos phi_p, sin phi_p) over cells p at bearing phi_p;
// the homing direction is sum_q (ALV_home,q - ALV_current,q) over the bins
// whose difference reaches threshold_frac of the strongest one.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "snapnav/nav/omni_geometry.hpp"

namespace snapnav::nav {

enum class OrientationRange {
  kAll,             // every gradient
  kVertical,        // gradients within 45 deg of horizontal: vertical edges (thesis fig. 3.8)
  kHorizontal,      // the others
  kNarrowVertical,  // within narrow_range_deg of horizontal (thesis fig. 3.10)
};
std::optional<OrientationRange> ParseOrientationRange(const std::string& name);

struct HogOptions {
  int band_top_px = 0;          // first row of the band (3.1.1)
  int band_height_px = 0;       // rows of the band; 0: to the bottom
  int cell_size_px = 40;        // square cells (thesis: 20, 40, 60, 80)
  int bins = 8;                 // orientation sectors over 360 degrees (36: the quantised variant)
  OrientationRange range = OrientationRange::kAll;
  double narrow_range_deg = 22.5;
  bool equalize_histogram = false;  // 3.1.5
  void Validate() const;            // throws std::invalid_argument
};

// Per pixel column and cell row, the gradient magnitude per orientation bin, as
// prefix sums over columns: the histogram of any run of columns (a cell at any
// shift) costs O(bins).
class ColumnHistograms {
 public:
  // `panorama` is an 8-bit grey or BGR panorama. Throws std::invalid_argument on an empty
  // image or a band that does not fit.
  ColumnHistograms(const cv::Mat& panorama, const HogOptions& options);

  int width() const { return width_; }
  int cell_rows() const { return cell_rows_; }
  int bins() const { return bins_; }
  // Adds the histogram of columns [x0, x0 + n) (wrapping around) of cell row `row` to out[0..bins).
  void AddRun(int row, int x0, int n, double* out) const;

 private:
  int width_ = 0, cell_rows_ = 0, bins_ = 0;
  std::vector<double> prefix_;  // [(row * (width + 1) + x) * bins + b]
};

// Cell descriptors of a panorama at a column shift: cell (r, p) covers columns
// [shift + p * cell, shift + (p + 1) * cell).
struct HogCells {
  int cell_rows = 0, cell_cols = 0, bins = 0;
  std::vector<double> values;  // [(r * cell_cols + p) * bins + q]
  double at(int r, int p, int q) const { return values[(r * cell_cols + p) * bins + q]; }
};
HogCells CellsAtShift(const ColumnHistograms& h, int cell_size_px, int shift_px);

struct CompassResult {
  double shift_px = 0;      // current column = home column + shift (sub-column)
  double rotation_rad = 0;  // heading of the current view relative to home, counter-clockwise
  double min_distance = 0;  // descriptor distance at the best shift
  std::vector<double> distance_by_shift;  // D(s) for s = 0..width-1 (thesis fig. 3.2)
};
// Visual compass (3.1.2). Throws std::invalid_argument when the two histograms differ in shape.
CompassResult VisualCompass(const ColumnHistograms& home, const ColumnHistograms& current, int cell_size_px);

// Which difference of the ALVs points home. The thesis (3.1.3) uses home - current;
// where approaching a surface magnifies its texture (fewer strong gradients per cell),
// current - home points home instead: an empirical property of the scene.
enum class AlvDifference { kHomeMinusCurrent, kCurrentMinusHome };

struct HogAlvOptions {
  double threshold_frac = 0.0;  // keep bins whose ALV difference >= frac * strongest (thesis: 0.3, 0.5)
  AlvDifference difference = AlvDifference::kHomeMinusCurrent;
  int min_bins = 1;             // fewer kept bins: no answer
  void Validate() const;
};

struct HomingEstimate {
  double direction_rad = 0;    // in the current robot frame
  double magnitude = 0;
  double compass_rotation_rad = 0;
  int bins_used = 0;           // landmarks (dominant bins) used
};

// The HOG-ALV homing direction from the home snapshot to the current view, after
// aligning the current view with the compass. nullopt when no bin passes the threshold
// or the ALV difference vanishes.
std::optional<HomingEstimate> HogHoming(const ColumnHistograms& home, const ColumnHistograms& current,
                                        const HogOptions& hog, const HogAlvOptions& alv, const PanoramaModel& panorama);

// The per-bin ALVs of cells (bearing of cell column p from the panorama model).
std::vector<Eigen::Vector2d> BinAlvs(const HogCells& cells, int cell_size_px, const PanoramaModel& panorama);

}  // namespace snapnav::nav
