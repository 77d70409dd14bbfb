#pragma once
// Several frames of one view, taken by a robot that stands still for a few seconds, fused into
// one view without what moved (snapnav's improvement for homing among walking people; the
// thesis homes from single snapshots):
//   persistent  landmarks that are found again at the same place in most frames (static
//               landmarks stay, landmarks on walking people move or vanish);
//   median      the per-pixel median of the frames (a person covering a pixel in fewer than
//               half of the frames is replaced by what is behind), for any method, HOG included.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/landmarks/landmark_set.hpp"

namespace snapnav::nav {

enum class ViewFusion { kPersistent, kMedian };
std::optional<ViewFusion> ParseViewFusion(const std::string& name);
const char* ViewFusionName(ViewFusion fusion);  // "persistent", "median"

struct PersistenceOptions {
  double min_fraction = 0.6;     // a landmark is kept when found in at least this share of the frames (and two)
  double max_shift_px = 3;       // an observation of the same landmark: within this many columns (wrapping) ...
  double max_row_shift_px = 3;   // ... and rows (vertical lines: rows are not compared, a line's middle moves
                                 // when a person hides part of it)
  double max_descriptor_distance_frac = 0.4;  // ... and descriptors closer than this share of their mean norm
  void Validate() const;         // throws std::invalid_argument
};

// The landmarks of `frames` (one still view, same method and panorama size) found in at least
// min_fraction of them, and in two at least (found again). Observations are chained into tracks frame by frame: each landmark joins
// the unclaimed track of nearest descriptor within the position gate, or starts a new one. A
// kept track is represented by its first observation. `seen` (if given) receives the number of
// frames each kept landmark was found in. One frame is returned unchanged; no frames, or sets
// of different methods or sizes, throw std::invalid_argument.
LandmarkSet PersistentLandmarks(const std::vector<LandmarkSet>& frames, const PersistenceOptions& options,
                                std::vector<int>* seen = nullptr);

// Per-pixel median (the lower one for an even count) of same-size, same-type 8-bit images.
cv::Mat MedianImage(const std::vector<cv::Mat>& frames);

}  // namespace snapnav::nav
