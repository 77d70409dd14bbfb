#pragma once
// Omni frames as panoramas of one model (library snapnav_glue_frames): raw catadioptric frames
// are unwrapped with their own mirror calibration (a default one when theirs is all zero),
// panorama frames must have the model's size and geometry. Processes that take frames (homing,
// landmarks) use it, so a frame is accepted or refused for the same reasons everywhere.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include <opencv2/core.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/homing/unwrap.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::glue {

class FramePanoramas {
 public:
  FramePanoramas(const nav::PanoramaModel& panorama, const nav::MirrorModel& default_mirror)
      : panorama_(panorama), default_mirror_(default_mirror) {}
  // The frame as a panorama of the model; nullopt when it cannot be used, with reason() (a
  // short category: "wrong size", "undecodable image", ...) and detail() saying why. The unwrap
  // map is rebuilt only when the calibration or the image size changes.
  std::optional<cv::Mat> Convert(const omni_frame_t& frame);
  // The raw frames' self-occlusion mask (image_mask.hpp: non-zero usable, 0 the robot's own parts;
  // empty: none), e.g. from `[mirror] mask` (glue::LoadMirrorMask). Raw frames of another size are
  // refused ("wrong mask size"); panorama frames are used without it.
  void SetMask(const cv::Mat& raw_mask);
  // The mask of the panorama the last Convert returned (empty: none): what the extractors ignore.
  const cv::Mat& mask() const { return mask_; }
  // Its nav::MaskClearance (empty with no mask), computed once per unwrap map: what
  // ExtractLandmarks and MakePlaceView take so as not to compute it per frame.
  const cv::Mat& mask_clearance() const { return mask_clearance_; }
  const std::string& reason() const { return reason_; }
  const std::string& detail() const { return detail_; }
  int64_t unwrapper_builds() const { return unwrapper_builds_; }

 private:
  void Fail(const std::string& reason, const std::string& detail) {
    reason_ = reason;
    detail_ = detail;
  }
  nav::PanoramaModel panorama_;
  nav::MirrorModel default_mirror_;
  cv::Mat raw_mask_, mask_, mask_clearance_;
  cv::Mat unwrapper_clearance_;              // MaskClearance of unwrapper_'s panorama mask
  std::optional<nav::Unwrapper> unwrapper_;  // for the last raw calibration and size seen
  cv::Size unwrapper_size_;
  // The last calibration the Unwrapper refused, so it is not rebuilt per frame.
  std::optional<std::pair<nav::MirrorModel, cv::Size>> refused_calibration_;
  std::string refused_reason_;
  std::string reason_, detail_;
  int64_t unwrapper_builds_ = 0;
};

}  // namespace snapnav::glue
