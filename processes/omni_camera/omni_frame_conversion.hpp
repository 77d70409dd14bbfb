#pragma once
// cv::Mat -> omni_frame_t for the omni-camera driver: a raw catadioptric image in
// one of the four wire encodings (gray8, rgb8 in R,G,B order, jpeg, png) with the
// mirror calibration.

#include <cstdint>
#include <string>

#include <opencv2/core/mat.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::processes {

// Throws std::invalid_argument when the mirror centre lies outside a width_px x height_px image.
void CheckMirrorFitsImage(const nav::MirrorModel& mirror, int width_px, int height_px);

struct OmniFrameOptions {
  std::string sensor_name = "omni";
  int8_t encoding = omni_frame_t::JPEG;  // omni_frame_t::GRAY8, RGB8, JPEG or PNG
  int jpeg_quality = 90;  // 1..100, used for kJpeg
  nav::MirrorModel mirror;

  void Validate() const;  // throws std::invalid_argument (mirror: nav::MirrorModel::Validate)
};

// Converts an 8-bit image as OpenCV delivers it (1 channel gray, 3 channels BGR or
// 4 channels BGRA) into a RAW_OMNI frame stamped `utime` [microseconds]:
//   gray8: one byte per pixel (colour is converted to gray), row_stride = width
//   rgb8:  R,G,B per pixel (OpenCV's BGR is swapped), row_stride = 3 * width
//   jpeg, png: the compressed file bytes of the image as captured (gray stays gray,
//          colour stays colour, alpha is dropped), row_stride = 0
// Throws std::invalid_argument for an empty image, a depth other than 8 bits or an
// unsupported channel count, and std::runtime_error when the image encoder fails.
omni_frame_t MatToOmniFrame(const cv::Mat& image, int64_t utime, const OmniFrameOptions& options);

}  // namespace snapnav::processes
