#pragma once
// Omni image to panorama (thesis 3.1, Appendix A.1): polar unwrap through the
// mirror model with bilinear sampling. The sampling map is computed once per
// calibration and reused for every frame.

#include <optional>

#include <opencv2/core.hpp>

#include "snapnav/nav/omni_geometry.hpp"

namespace snapnav::nav {

class Unwrapper {
 public:
  // Throws std::invalid_argument if either model is invalid or the panorama looks
  // outside the mirror's elevation range.
  Unwrapper(const MirrorModel& mirror, const PanoramaModel& panorama, cv::Size raw_size);

  // Unwraps `raw` (any 8-bit type, raw_size) into `panorama`. Throws std::invalid_argument
  // on an empty image or one of another size than the calibration's.
  void Unwrap(const cv::Mat& raw, cv::Mat* panorama) const;

  const MirrorModel& mirror() const { return mirror_; }
  const PanoramaModel& panorama() const { return panorama_; }

 private:
  MirrorModel mirror_;
  PanoramaModel panorama_;
  cv::Size raw_size_;
  cv::Mat map1_, map2_;  // fixed-point maps for cv::remap
};

struct MirrorSearchOptions {
  double min_radius_frac = 0.25;  // of the smaller image side
  double max_radius_frac = 0.52;
  double inner_radius_frac = 0.17; // inner radius as a fraction of the outer one when it cannot be measured
};

// Finds the mirror circle in a raw catadioptric image: the centre and outer radius of
// the bright ring against the dark border, and the inner (camera) disc. Elevations are
// not observable from one image and are copied from `prior`. nullopt when no circle is found.
std::optional<MirrorModel> CalibrateMirror(const cv::Mat& raw, const MirrorModel& prior,
                                           const MirrorSearchOptions& options = {});

}  // namespace snapnav::nav
