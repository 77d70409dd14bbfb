#pragma once
// Vertical-line landmarks (thesis 4.1.1-4.1.2).
//
// Detection (4.1.1): the panorama is padded by wrapping its columns (it is a cylinder),
// blurred, Canny edges are mapped into the Hough space (cv::HoughLinesP, the probabilistic
// transform), segments further than max_tilt_deg from vertical are dropped (the theta
// threshold), and the segments are clustered by column into one line per landmark.
//
// Description (4.1.1): a window of window_px columns centred on the line, over the full
// panorama height (wrapping), holds R-HOG histograms of signed gradient orientations; the
// thesis' first variant is one histogram (8 dims), its final one six sub-windows (48 dims).
//
// Matching (4.1.2): nearest descriptor with the mutual ("both pick each other") check, the
// loosened rule that also accepts the home line's second-best current line, and a threshold
// on the column displacement of a match.

#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/landmarks/landmark_set.hpp"

namespace snapnav::nav {

struct VlineOptions {
  // Edges: Gaussian blur (0: none), then Canny with a 3x3 Sobel aperture.
  double canny_low = 50, canny_high = 150;
  double blur_sigma_px = 1.0;
  // Hough (4.1.1): cv::HoughLinesP on the edges. Edge pixels whose gradient is further than
  // max_tilt_deg + 30 deg from horizontal cannot lie on a near-vertical line; they are
  // dropped before the transform (fewer votes, no segments built along horizontal edges).
  double hough_rho_px = 1, hough_theta_deg = 1;
  int hough_threshold = 20;    // accumulator votes
  double min_segment_px = 15;  // shortest segment HoughLinesP returns
  double max_gap_px = 3;       // largest gap HoughLinesP bridges within a segment
  double max_tilt_deg = 10;    // keep segments within this of vertical (the theta threshold), (0, 60]
  // Clustering: the longest unassigned segment seeds a line and takes every unassigned segment
  // whose midpoint lies within cluster_px (wrapping) of the seed extended along its slope;
  // repeat. Lines left within cluster_px / 2 + 1 of a longer one over overlapping rows are
  // the same edge and dropped.
  double cluster_px = 4;
  // Lines with fewer rows of edge support than this are dropped (see VerticalLine::length_px).
  double min_line_px = 20;
  // R-HOG window: window_px columns centred on the line, the full panorama height (thesis 40, 80).
  int window_px = 40;
  int bins = 8;  // signed orientation sectors over 360 deg
  // true: 2 columns (left / right of the line) x 3 rows of cells -> 6 x bins dims (thesis: 48);
  // false: one histogram of the whole window -> bins dims.
  bool divided = true;
  void Validate() const;  // throws std::invalid_argument naming the bad option
};

// One clustered vertical line of a panorama.
struct VerticalLine {
  double column_px = 0;  // sub-pixel column in [0, width) at the line's centre row (pixel j is centred on j)
  double top_px = 0;     // first row of the line
  double bottom_px = 0;  // last row
  // Rows of top..bottom with a Canny edge pixel within one column of the line: the clustered
  // segments' rows, each row once (the two copies of a line in the wrap padding, parallel
  // segments), plus the pieces HoughLinesP leaves out where Canny's edge jitters by a column.
  // top..bottom extends the segments along such edge pixels over gaps up to max_gap_px.
  double length_px = 0;
};

// Vertical lines of an 8-bit grey panorama, sorted by column; none on a featureless image.
// Hough segments are found on the wrap-padded image and their columns folded into [0, width);
// the two copies of a line near the seam cluster into one line.
// Throws std::invalid_argument on an empty image, a type other than CV_8UC1, a panorama
// narrower than window_px or lower than 3 rows, or bad options.
std::vector<VerticalLine> DetectVerticalLines(const cv::Mat& gray, const VlineOptions& options);

// R-HOG descriptors of `lines` in `gray`: one CV_32F row per line (0 rows, the descriptor
// width columns when there are no lines).
//
// Gradients are the 3x3 Sobel derivatives of the blurred panorama (the ones Canny sees);
// orientation is signed over 360 deg (a dark-to-bright edge differs from a bright-to-dark
// one), each pixel votes its magnitude into the two nearest orientation bins (bin q centred
// on q * 360 / bins deg: a vertical edge falls on one bin). Divided windows: cell (r, c)
// covers the left (c = 0) or right (c = 1) half of the window and a third of the rows;
// pixels within half a pixel of the line's column split between the halves, and rows vote
// into the two nearest row cells (linear in the distance to the cell centres). Layout:
// element (r * cells_x + c) * bins + q. Normalisation over the whole descriptor (the window
// is one HOG block): L2-Hys, i.e. unit L2 norm, clip at 1.2 / sqrt(dims) (Dalal-Triggs' 0.2
// for 36 dims, scaled to the descriptor size), unit L2 norm again. A window without any
// gradient gives a zero row.
cv::Mat DescribeVerticalLines(const cv::Mat& gray, const std::vector<VerticalLine>& lines, const VlineOptions& options);

// Detection plus description as a LandmarkSet (method kVline): x_px = column, y_px = centre
// row of the segments, strength = length_px, scale_px = window_px, angle_deg = -1.
LandmarkSet DetectVlineLandmarks(const cv::Mat& gray, const VlineOptions& options);

// Line matching (4.1.2).
struct VlineMatchOptions {
  // Each current line c takes its nearest home line h (L2 distance of the descriptors).
  // mutual: keep the match only if h's nearest current line is c. false: keep every nearest.
  bool mutual = true;
  // With mutual: also keep it if c is h's second-nearest current line (the thesis' loosened
  // rule). A home line can then be matched by two current lines.
  bool relaxed_second_best = true;
  // Discard matches whose column difference (current - home - shift_px, wrapped into
  // [-width/2, width/2)) exceeds this in magnitude; <= 0: no threshold.
  double max_x_displacement_px = 60;
};

struct LineMatch {
  int home = -1, current = -1;  // landmark indices
  float distance = 0;           // L2 distance of the descriptors
};

// Matches of current lines to home lines, sorted by current index. `shift_px` is the
// expected column shift of the current view: current column = home column + shift_px
// (e.g. CompassResult::shift_px). Throws std::invalid_argument when descriptors are not
// CV_32F, differ in width, or do not have one row per landmark, or when the displacement
// threshold is on and the panoramas differ in width. Either set empty: no matches.
std::vector<LineMatch> MatchVerticalLines(const LandmarkSet& home, const LandmarkSet& current,
                                          const VlineMatchOptions& options, double shift_px = 0);

}  // namespace snapnav::nav
