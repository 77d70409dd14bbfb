#pragma once
// Snapshot homing with HOG landmarks (thesis chapter 3).
//
// The band of a panorama (3.1.1) is divided into cells; each cell holds a
// histogram of oriented gradients (centred gradient filter, signed orientation
// over 360 degrees in `bins` sectors; 36 bins is the thesis' quantised variant).
// The visual compass (3.1.2) finds the column shift that minimises the distance
// between the cell descriptors of two panoramas. The HOG average landmark vector
// (3.1.3) of bin q is ALV_q = sum_p w(H_qp) (cos phi_p, sin phi_p) over cells p
// at bearing phi_p; the homing direction is the sum over bins of the ALV
// differences that reach threshold_frac of the strongest one.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"

namespace snapnav::nav {

enum class OrientationRange {
  kAll,             // every gradient
  kVertical,        // gradients within 45 deg of horizontal: vertical edges (thesis fig. 3.8)
  kHorizontal,      // the others
  kNarrowVertical,  // within narrow_range_deg of horizontal (thesis fig. 3.10)
};
std::optional<OrientationRange> ParseOrientationRange(const std::string& name);
const char* OrientationRangeName(OrientationRange range);

struct HogOptions {
  int band_top_px = 0;          // first row of the band (3.1.1)
  int band_height_px = 0;       // rows of the band; 0: to the bottom. Only whole cells are used.
  int cell_size_px = 40;        // square cells (thesis: 20, 40, 60, 80)
  int bins = 8;                 // orientation sectors over 360 degrees (36: the quantised variant)
  OrientationRange range = OrientationRange::kAll;
  double narrow_range_deg = 22.5;
  // With a mask: a cell with more than this share of its pixels masked is left out; a cell with
  // less counts with its histogram scaled up to the whole cell (ColumnHistograms). In [0, 1).
  double max_masked_share = 0.9;
  void Validate() const;        // throws std::invalid_argument
};

// Centred-difference gradients of a grey panorama (the columns wrap around).
struct Gradients {
  cv::Mat magnitude;  // CV_32F
  cv::Mat angle_rad;  // CV_32F, [0, 2 pi)
};
// `gray` is an 8-bit single-channel panorama. Throws std::invalid_argument on an empty image.
Gradients ComputeGradients(const cv::Mat& gray);

// Per pixel column and cell row, the gradient magnitude per orientation bin, as
// prefix sums over columns: the histogram of any run of columns (a cell at any
// shift) costs O(bins).
//
// With a mask (image_mask.hpp: non-zero usable, the panorama's size), masked pixels add nothing;
// a cell's histogram is scaled up by the share of its pixels that are usable, and a cell with
// more than HogOptions::max_masked_share of its pixels masked is left out (HogCells::valid): the
// compass and the ALVs compare only cells usable in both views.
class ColumnHistograms {
 public:
  // Throws std::invalid_argument when the band does not fit the image, or the mask is not of
  // the gradients' size.
  ColumnHistograms(const Gradients& gradients, const HogOptions& options, const cv::Mat& mask = cv::Mat());
  // Convenience: gradients of an 8-bit grey or BGR panorama.
  ColumnHistograms(const cv::Mat& panorama, const HogOptions& options);

  int width() const { return width_; }
  int cell_rows() const { return cell_rows_; }
  int bins() const { return bins_; }
  int cell_size() const { return cell_size_; }
  bool masked() const { return !masked_prefix_.empty(); }
  double max_masked_share() const { return max_masked_share_; }
  // Adds the histogram of columns [x0, x0 + n) (wrapping around) of cell row `row` to out[0..bins).
  void AddRun(int row, int x0, int n, double* out) const;
  // Share of the masked pixels of columns [x0, x0 + n) (wrapping) of cell row `row` (0 without a mask).
  double MaskedShare(int row, int x0, int n) const;

 private:
  void Build(const Gradients& g, const HogOptions& o, const cv::Mat& mask);
  int width_ = 0, cell_rows_ = 0, bins_ = 0, cell_size_ = 0;
  double max_masked_share_ = 0.9;
  std::vector<double> prefix_;  // [(row * (width + 1) + x) * bins + b]
  std::vector<int> masked_prefix_;  // [row * (width + 1) + x]: masked pixels of columns < x; empty without a mask
};

// Cell descriptors of a panorama at a column shift: cell (r, p) covers columns
// [shift + p * cell, shift + (p + 1) * cell).
struct HogCells {
  int cell_rows = 0, cell_cols = 0, bins = 0;
  std::vector<double> values;  // [(r * cell_cols + p) * bins + q]
  std::vector<uint8_t> valid;  // [r * cell_cols + p]: usable (mask); empty: every cell
  double at(int r, int p, int q) const { return values[(static_cast<size_t>(r) * cell_cols + p) * bins + q]; }
  bool usable(int r, int p) const { return valid.empty() || valid[static_cast<size_t>(r) * cell_cols + p]; }
};
HogCells CellsAtShift(const ColumnHistograms& h, int cell_size_px, int shift_px);

// Mean Shannon entropy [bits] of the cells' normalised orientation histograms, weighted by
// cell energy (thesis fig. 3.13: how much structure a cell size captures).
double CellEntropyBits(const HogCells& cells);

struct CompassResult {
  double shift_px = 0;      // current column = home column + shift (sub-column)
  double rotation_rad = 0;  // heading of the current view relative to home, counter-clockwise
  double min_distance = 0;  // descriptor distance at the best shift
  std::vector<double> distance_by_shift;  // D(s) for s = 0..width-1 (thesis fig. 3.2)
};
// Visual compass (3.1.2). Throws std::invalid_argument when the two histograms differ in shape.
CompassResult VisualCompass(const ColumnHistograms& home, const ColumnHistograms& current, int cell_size_px);

// Which difference of the ALVs points home. With landmark vectors pointing from the robot
// to the landmarks (our bearings), Lambrinos' ALV model gives current - home; the thesis
// writes home - current (3.1.3) with its own bearing convention. Both are offered.
enum class AlvDifference { kHomeMinusCurrent, kCurrentMinusHome };
// How a cell's bin value weighs its landmark vector: the thesis' magnitude |H_qp|, or
// log(1 + |H_qp| / log_scale), which counts landmarks more evenly (a near, long edge no
// longer outweighs several far ones).
enum class CellWeight { kMagnitude, kLog };

struct HogAlvOptions {
  double threshold_frac = 0.0;  // keep bins whose ALV difference >= frac * strongest (thesis: 0.3, 0.5)
  AlvDifference difference = AlvDifference::kCurrentMinusHome;
  CellWeight weight = CellWeight::kMagnitude;
  double log_scale = 100.0;     // [grey levels x pixels] for CellWeight::kLog
  int min_bins = 1;             // fewer kept bins: no answer
  void Validate() const;
};

// The per-bin ALVs of cells (bearing of cell column p from the panorama model). `use` (if given,
// one flag per cell as HogCells::valid): only those cells count.
std::vector<Eigen::Vector2d> BinAlvs(const HogCells& cells, int cell_size_px, const PanoramaModel& panorama,
                                     const HogAlvOptions& options = {}, const std::vector<uint8_t>* use = nullptr);

struct HomingEstimate {
  double direction_rad = 0;    // in the current robot frame
  double magnitude = 0;
  double compass_rotation_rad = 0;
  int bins_used = 0;           // landmarks (dominant bins) used
};

// The HOG-ALV homing direction from the home snapshot to the current view, after
// aligning the current view with the compass result. nullopt when no bin passes the
// threshold or the ALV difference vanishes.
std::optional<HomingEstimate> HogHoming(const ColumnHistograms& home, const ColumnHistograms& current,
                                        const HogOptions& hog, const HogAlvOptions& alv,
                                        const PanoramaModel& panorama, const CompassResult& compass);
// Same, with the compass computed on `hog`'s own descriptors.
std::optional<HomingEstimate> HogHoming(const ColumnHistograms& home, const ColumnHistograms& current,
                                        const HogOptions& hog, const HogAlvOptions& alv,
                                        const PanoramaModel& panorama);

// Warping compensation (3.1.6): per column, the bottom edge of the objects (Canny on
// the blurred panorama, first edge above the floor) gives the distance to the object
// from the camera height; rows are re-mapped so that the output shows heights
// [height_bottom_m, height_top_m] on the object instead of elevations.
struct WarpCompensationOptions {
  double camera_height_m = 0.55;
  double height_bottom_m = 0.0;   // bottom row of the output shows this height on the object
  double height_top_m = 2.0;      // top row
  double blur_sigma_px = 1.5;
  double canny_low = 40, canny_high = 120;
  double min_distance_m = 0.3, max_distance_m = 8.0;  // clamp of the distance estimate
  int median_columns = 9;         // median filter over columns of the distance estimate (odd)
  void Validate() const;
};
// `gray` is an 8-bit grey panorama of model `panorama`. Returns the compensated panorama
// (same size) and, if `distances_m` is not null, the estimated distance per column.
cv::Mat CompensateWarping(const cv::Mat& gray, const PanoramaModel& panorama, const WarpCompensationOptions& options,
                          std::vector<double>* distances_m = nullptr);

// Everything the HOG homing of one image pair needs, in one place: preprocessing,
// the homing descriptors, the compass descriptors and the ALV options.
struct HogHomingConfig {
  HogOptions hog;                 // homing descriptors (band, cells, bins, range)
  HogOptions compass_hog;         // compass descriptors (may differ from the homing band)
  bool use_compass = true;        // false: both views share a heading (aligned database, external heading)
  HogAlvOptions alv;
  bool equalize_histogram = false;  // 3.1.5
  bool warp_compensation = false;   // 3.1.6
  WarpCompensationOptions warp;
  void Validate() const;
};

// Stateful homing against one home snapshot: the home's descriptors are computed once.
class HogHomer {
 public:
  HogHomer(const HogHomingConfig& config, const PanoramaModel& panorama);
  // The panorama's self-occlusion mask (image_mask.hpp; empty: none): masked pixels are filled
  // and left out of the cells (ColumnHistograms). Set it before the home. Throws
  // std::invalid_argument on a mask of another size than the model's.
  void SetMask(const cv::Mat& panorama_mask);
  // Throws std::invalid_argument when the image does not match the panorama model.
  void SetHome(const cv::Mat& panorama);
  bool has_home() const { return home_.has_value(); }
  // Homing vector from the current panorama (8-bit grey or BGR, the model's size).
  // `known_rotation_rad`: the heading of the current view relative to home when known;
  // otherwise the compass (or, with use_compass = false, zero). Throws std::logic_error
  // without a home, std::invalid_argument on a bad image.
  std::optional<HomingEstimate> Home(const cv::Mat& panorama,
                                     std::optional<double> known_rotation_rad = std::nullopt) const;
  const HogHomingConfig& config() const { return config_; }
  const PanoramaModel& panorama() const { return panorama_; }

 private:
  struct Views {
    ColumnHistograms hog, compass;
  };
  Views Describe(const cv::Mat& panorama) const;

  HogHomingConfig config_;
  PanoramaModel panorama_;
  cv::Mat mask_, cell_mask_;  // the mask, and grown by a pixel (the centred differences)
  std::optional<Views> home_;
};

}  // namespace snapnav::nav
