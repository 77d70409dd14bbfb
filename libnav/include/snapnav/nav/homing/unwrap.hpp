#pragma once
// Omni image to panorama (thesis 3.1, Appendix A.1): polar unwrap through the
// mirror model with bilinear sampling. The sampling map is computed once per
// calibration and reused for every frame.

#include <optional>

#include <opencv2/core.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/homing/mirror_calibration.hpp"

namespace snapnav::nav {

class Unwrapper {
 public:
  // Throws std::invalid_argument if either model is invalid, the panorama looks outside the
  // mirror's elevation range or the mirror's centre lies outside the image. The rim may run past
  // the image's border (a real camera's mirror often does): the panorama's pixels seen there are
  // masked (panorama_mask), as the robot's own parts are.
  Unwrapper(const MirrorModel& mirror, const PanoramaModel& panorama, cv::Size raw_size);

  // Unwraps `raw` (any 8-bit type, raw_size) into `panorama`. Throws std::invalid_argument
  // on an empty image or one of another size than the calibration's. With a mask (SetMask), the
  // panorama's masked pixels are filled from their usable neighbours in the row (FillMasked):
  // nothing of the robot's own parts reaches the panorama.
  void Unwrap(const cv::Mat& raw, cv::Mat* panorama) const;

  // The raw image's self-occlusion mask (image_mask.hpp: CV_8UC1 of raw_size, non-zero usable;
  // empty: none). A panorama pixel is masked when any raw pixel its bilinear sample reads is, or
  // lies outside the image. Throws std::invalid_argument on a mask of another size or type.
  void SetMask(const cv::Mat& raw_mask);
  // The panorama's mask: the raw mask's and the pixels outside the image (empty when there is no
  // raw mask and the whole ring lies inside the image).
  const cv::Mat& panorama_mask() const { return panorama_mask_; }

  const MirrorModel& mirror() const { return mirror_; }
  const PanoramaModel& panorama() const { return panorama_; }

 private:
  MirrorModel mirror_;
  PanoramaModel panorama_;
  cv::Size raw_size_;
  cv::Mat map1_, map2_;  // fixed-point maps for cv::remap
  cv::Mat inside_;  // the panorama's pixels whose samples lie inside the image (empty: all of them)
  cv::Mat panorama_mask_;
};

// The mirror calibration from images (CalibrateMirror, MirrorSearchOptions): mirror_calibration.hpp.

}  // namespace snapnav::nav
