#pragma once
// Mirror calibration from images (docs/calibration.md): the mirror's rim, the camera's own
// reflection in its middle, the elevation mapping from the mirror's profile, and the mask of the
// robot's own parts.
//
// Rim: gradient edge points (Sobel on the blurred grey image, Canny's hysteresis with thresholds
// from the image's own gradient distribution). Each edge point votes for the centres along its
// gradient line (both signs: a dark housing around a bright mirror or the reverse), a Hough
// accumulator of centres; at the strongest centres, the distances of the edge points whose
// gradient is radial make a radius histogram. A candidate circle counts its radial edge points
// and the share of directions they cover; the rim is the best-supported one whose inside is more
// textured than its outside (the mirror shows the scene, the housing does not; the camera's
// reflection is the reverse). It is refined by least squares (the geometric distance, Gauss-Newton)
// on its inliers with sub-pixel edge positions, re-selecting inliers with a shrinking tolerance.
// Cables, struts, a bright window or a person break the rim's edge or add edges that are not
// radial or not on one circle: they lower the coverage, not the fit.
//
// Inner radius: the camera's reflection is a disc about the centre. Its edge is, among the
// circles inside the rim that the radial edge points cover in enough directions, the one with a
// flat inside (the reflection does not vary along a circle) and a varied outside (the scene),
// weighted by how much of it is seen; without a clear one (a plain floor around it), the
// outermost of the best-seen circles. The dead zone ends there (plus a margin).
//
// Self-occlusion: pixels of the mirror ring whose grey level stays within the noise over frames
// taken while the robot moves (the robot's own parts move with the camera), cleaned of specks,
// without still regions all round the centre (a plain floor), grown by a margin.

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "snapnav/nav/homing/omni_geometry.hpp"

namespace snapnav::nav {

struct MirrorSearchOptions {
  double min_radius_frac = 0.15;     // rim radius, fractions of the image's smaller side
  double max_radius_frac = 0.75;     // (a mirror larger than the sensor is cut by the image's border)
  int search_max_side_px = 800;      // the search runs on the image scaled down to this; the fit at full size
  double blur_sigma_px = 1.2;        // before the gradients (full-size pixels)
  double radial_cos = 0.9;           // |cos| between an edge's gradient and the radial direction
  int max_edge_points = 40000;       // the search's edge points (a random sample beyond)
  int centre_candidates = 6;         // Hough peaks examined
  double min_rim_coverage = 0.25;    // share of the rim's directions with an edge; below: not found
  double inner_min_frac = 0.08;      // the camera's reflection: searched between these fractions
  double inner_max_frac = 0.75;      //   of the rim radius
  double inner_min_coverage = 0.45;  // share of directions its edge must be seen in
  double inner_margin_px = 1.5;      // added to the reflection's radius (its soft edge)
  double inner_default_frac = 0.17;  // inner radius when no reflection is found
  // A ring around the mirror (its holder): where the strongest circle has no scene just inside it,
  // the mirror's edge is looked for this far inside it (fraction of its radius; 0: never)
  double holder_max_frac = 0.12;
  // A rim whose edge an ellipse with axes at least this far apart explains clearly better (a camera
  // tilted against the mirror's axis) is reported (a warning; 1: off)
  double ellipse_min_ratio = 1.01;
  // Warnings (MirrorCalibration::warnings): a fit worse than these is reported as poor.
  double warn_rms_px = 1.0;
  double warn_inlier_fraction = 0.5;
  double warn_coverage = 0.5;
  void Validate() const;  // throws std::invalid_argument
};

struct CircleFit {
  double center_x_px = 0, center_y_px = 0, radius_px = 0;
  double rms_px = 0;           // RMS of the inliers' distances from the circle
  int inliers = 0;             // edge points within the final tolerance, gradient radial
  double inlier_fraction = 0;  // inliers / edge points within 4 tolerances of the circle
  double coverage = 0;         // share of the circle's directions (2 degree sectors, inside the image) with an inlier
};

struct MirrorCalibration {
  MirrorModel mirror;  // centre, inner and outer radius; elevations from the profile
  CircleFit rim;
  std::optional<CircleFit> inner;     // the camera's reflection (nullopt: not found, default fraction used)
  std::optional<CircleFit> holder;    // the strongest circle, left out as the outer edge of a ring holding the
                                      // mirror (MirrorSearchOptions::holder_max_frac; nullopt: none)
  std::vector<std::string> warnings;  // a poor fit, no reflection found, the rim cut by the image border
};

// Calibrates from one image (8-bit grey or BGR; several frames: pass their mean). nullopt when
// no rim is found, with the reason in `why_not`.
std::optional<MirrorCalibration> CalibrateMirror(const cv::Mat& image, const MirrorProfile& profile,
                                                 const MirrorSearchOptions& options = {},
                                                 std::string* why_not = nullptr);

struct OcclusionOptions {
  double blur_sigma_px = 0;  // frames are blurred first (0: not; a blur mixes a thin cable with the scene)
  double max_std_grey = 0;   // a pixel whose std. dev. over the frames is below this is the robot's;
                             // 0: 3 x the noise measured on the housing outside the rim and on the
                             // camera's reflection (at least 1.5, at most 0.3 x the ring's median)
  int min_area_px = 0;       // connected parts smaller than this are dropped; 0: 0.05 % of the ring
  int grow_px = 2;           // the mask is grown by this margin
  void Validate() const;
};
struct OcclusionStats {
  int frames = 0;
  double threshold_grey = 0;    // the std. dev. threshold used
  double noise_grey = 0;        // measured noise (std. dev. on the housing)
  double scene_median_std = 0;  // median std. dev. over the ring: low means the robot hardly moved
  double masked_fraction = 0;   // of the ring
  int still_rings = 0;          // still regions all round the centre left out (a plain floor, the dead zone's edge)
};
// The self-occlusion mask (image_mask.hpp: non-zero usable, 0 the robot's parts) of frames (8-bit,
// one size, at least 3) taken while the robot moves, inside `mirror`'s ring. Throws
// std::invalid_argument on too few frames or frames of different sizes.
cv::Mat SelfOcclusionMask(const std::vector<cv::Mat>& frames, const MirrorModel& mirror,
                          const OcclusionOptions& options, OcclusionStats* stats = nullptr);

// The overlay to check a calibration by eye: the image, the rim (green), the inner circle (yellow),
// the masked pixels tinted red, the centre marked; a circle left out as the mirror's holder
// (MirrorCalibration::holder) orange.
cv::Mat DrawCalibrationOverlay(const cv::Mat& image, const MirrorModel& mirror, const cv::Mat& mask,
                               const std::optional<CircleFit>& holder = std::nullopt);

}  // namespace snapnav::nav
