#pragma once
// Homing with landmark correspondences (thesis 4.1-4.3).
//
// Landmarks of the home and the current panorama (vertical lines, SIFT or SURF keypoints)
// are matched by their descriptors; each match is one landmark seen from both places. The
// current view's heading relative to home comes from the matches (the mode of the bearing
// differences) or from outside; the average landmark vectors over the matched landmarks then
// give the direction home:
//   unit      ALV = 1/N sum u_n, u_n the unit vector towards landmark n (4.2.1);
//   weighted  ALV = sum Q_n u_n / sum Q_n, Q_n the match quality (4.2.2, 4.3.2);
//   scale     the current landmark vector is scaled by s_home / s_current, the ratio of the
//             keypoint scales standing in for the distance ratio d_current / d_home (4.2.3).
// With the top-N selection only the N matches of smallest descriptor distance count.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/landmarks/landmark_set.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"

namespace snapnav::nav {

// SIFT (4.2) with OpenCV's implementation, on the panorama padded by wrapping its columns so
// that keypoints near the seam are found once, with their whole neighbourhood.
struct SiftOptions {
  int max_features = 0;             // strongest N keypoints; 0: all
  int octave_layers = 3;
  double contrast_threshold = 0.04;
  double edge_threshold = 10;
  double sigma = 1.6;
  void Validate() const;            // throws std::invalid_argument
};
// `gray`: 8-bit single channel panorama. Throws std::invalid_argument on an empty or non-grey image.
LandmarkSet DetectSift(const cv::Mat& gray, const SiftOptions& options);

// Runs `detect` on `gray` padded by `pad_px` wrapped columns on each side and keeps the landmarks
// whose column falls in the original image (column folded back into [0, width)), with their
// descriptor rows. For extractors that do not know about the panorama's seam.
template <typename Detect>
LandmarkSet DetectWrapped(const cv::Mat& gray, int pad_px, Detect&& detect);
LandmarkSet CropWrapped(const LandmarkSet& padded, int pad_px, int width_px, int height_px);

// Descriptor matching (4.1.2, 4.2, 4.3).
struct MatchOptions {
  double ratio = 0.8;            // Lowe's ratio test: best < ratio * second best; >= 1: off
  bool mutual = true;            // current c -> best home h is kept only if h's best current is c
  bool relaxed_second_best = false;  // 4.1.2: also keep it if c is h's second-best current
  double max_distance = 0;       // descriptor distance limit; <= 0: off
  double max_x_displacement_px = 0;  // column difference limit after removing the shift (wrapping); <= 0: off
  void Validate() const;
};
struct LandmarkMatch {
  int home = -1, current = -1;
  float distance = 0;   // descriptor distance (L2)
  float ratio = 1;      // best / second-best distance over the home landmarks (1: only one candidate)
};
// Matches each current landmark to the home landmarks. `shift_px`: expected column offset
// current - home (from a known rotation) for the displacement limit. Sets with different
// descriptor lengths throw std::invalid_argument; an empty set gives no matches.
std::vector<LandmarkMatch> MatchLandmarks(const LandmarkSet& home, const LandmarkSet& current,
                                          const MatchOptions& options, double shift_px = 0);

// Heading of the current view relative to home (counter-clockwise, like the visual compass)
// from matched bearings: the mode of the bearing differences (1 degree histogram smoothed over
// `window_rad`), refined by the mean of the differences within `window_rad` of it. nullopt
// without matches.
std::optional<double> RotationFromMatches(const LandmarkSet& home, const LandmarkSet& current,
                                          const std::vector<LandmarkMatch>& matches, const PanoramaModel& panorama,
                                          double window_rad = 0.17);

enum class AlvVariant { kUnit, kWeighted, kScale };
std::optional<AlvVariant> ParseAlvVariant(const std::string& name);
const char* AlvVariantName(AlvVariant variant);  // "unit", "weighted", "scale"
// How the weighted ALV turns a match into its weight Q_n.
enum class MatchWeight {
  kDistance,  // Q = exp(-d / mean d over the used matches): the descriptor distance (4.2.2)
  kScore,     // Q = 1 - best / second-best distance: the matching score (4.3.2)
};
const char* MatchWeightName(MatchWeight weight);

struct LandmarkAlvOptions {
  AlvVariant variant = AlvVariant::kUnit;
  MatchWeight weight = MatchWeight::kScore;
  int top_n = 0;                 // matches with the smallest descriptor distance; 0: all (thesis: 3, 5, 20)
  AlvDifference difference = AlvDifference::kCurrentMinusHome;
  double max_scale_ratio = 4;    // scale variant: s_home / s_current is clamped to [1/r, r]
  // Scale variant, snapnav's improvement: with the distance ratio each landmark alone gives the
  // home direction (k u_current - u_home is parallel to home - current), so the landmarks must
  // agree. consensus: the direction is the mean of the per-landmark directions within
  // consensus_window_rad of their mode (mismatches drop out), and an estimated rotation is
  // refined within +-rotation_refine_rad to the one that makes them agree best.
  bool consensus = false;
  double consensus_window_rad = 0.6;
  double rotation_refine_rad = 0.17;
  int min_landmarks = 1;         // fewer usable matches: no estimate
  void Validate() const;
};

// The homing direction from matched landmarks, the current view turned by `rotation_rad`
// relative to home (refined by the consensus when `refine_rotation`). nullopt when fewer than
// min_landmarks matches remain or the ALV difference vanishes. HomingEstimate::bins_used counts
// the landmarks used; `used` (if given) receives the indices into `matches` of those landmarks
// (the top-N selection, or the consensus' inliers).
std::optional<HomingEstimate> LandmarkAlvHoming(const LandmarkSet& home, const LandmarkSet& current,
                                                const std::vector<LandmarkMatch>& matches, double rotation_rad,
                                                const PanoramaModel& panorama, const LandmarkAlvOptions& options,
                                                bool refine_rotation = false, std::vector<int>* used = nullptr);

enum class RotationSource { kMatches, kNone };  // kNone: views share a heading (aligned database)

// Homing from landmark sets against one home set.
struct LandmarkHomingConfig {
  MatchOptions match;
  LandmarkAlvOptions alv;
  RotationSource rotation = RotationSource::kMatches;
  double rotation_window_rad = 0.17;
  void Validate() const;
};
struct LandmarkHoming {
  HomingEstimate estimate;
  int matches = 0;  // matches after the descriptor checks
  std::vector<LandmarkMatch> matched;  // those matches
  std::vector<int> used;               // indices into `matched` of the landmarks the estimate used
};
class LandmarkHomer {
 public:
  LandmarkHomer(const LandmarkHomingConfig& config, const PanoramaModel& panorama);
  // Throws std::invalid_argument when the set's panorama size differs from the model.
  void SetHome(LandmarkSet home);
  bool has_home() const { return home_.has_value(); }
  const LandmarkSet& home() const;
  // nullopt: no landmarks, too few matches, or a vanishing ALV difference ("no landmarks", not a
  // bogus vector). `known_rotation_rad` replaces the rotation from the matches.
  std::optional<LandmarkHoming> Home(const LandmarkSet& current,
                                     std::optional<double> known_rotation_rad = std::nullopt) const;
  const LandmarkHomingConfig& config() const { return config_; }

 private:
  void CheckSize(const LandmarkSet& set) const;
  LandmarkHomingConfig config_;
  PanoramaModel panorama_;
  std::optional<LandmarkSet> home_;
};

// ---------------------------------------------------------------------------------------------
template <typename Detect>
LandmarkSet DetectWrapped(const cv::Mat& gray, int pad_px, Detect&& detect) {
  if (pad_px <= 0) return detect(gray);
  const int pad = std::min(pad_px, gray.cols);
  cv::Mat padded;
  cv::copyMakeBorder(gray, padded, 0, 0, pad, pad, cv::BORDER_WRAP);
  return CropWrapped(detect(padded), pad, gray.cols, gray.rows);
}

}  // namespace snapnav::nav
