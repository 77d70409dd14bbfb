#pragma once
// cv::Mat -> omni_frame_t for the omni-camera driver: a raw catadioptric image in
// one of the four wire encodings (gray8, rgb8 in R,G,B order, jpeg, png) with the
// mirror calibration.

#include <cstdint>
#include <iosfwd>
#include <string>

#include <opencv2/core/mat.hpp>

#include "snapnav/omni_frame_t.hpp"

namespace snapnav::processes {

enum class FrameEncoding { kGray8, kRgb8, kJpeg, kPng };

// "gray8", "rgb8", "jpeg" or "png"; anything else throws std::invalid_argument.
FrameEncoding ParseFrameEncoding(const std::string& name);
std::string FrameEncodingName(FrameEncoding encoding);
// The omni_frame_t::encoding constant of an encoding.
int8_t WireEncoding(FrameEncoding encoding);

// Mirror of a catadioptric camera, in image pixels (origin at the top-left pixel centre),
// with the conventions of omni_frame_t: the elevation seen grows linearly with the radius.
struct MirrorCalibration {
  double center_x_px = 0;
  double center_y_px = 0;
  double inner_radius_px = 0;      // where the useful ring starts
  double outer_radius_px = 0;      // where the useful ring ends
  double elevation_inner_rad = 0;  // elevation seen at the inner radius
  double elevation_outer_rad = 0;  // elevation seen at the outer radius

  // Finite values, centre >= 0, 0 <= inner_radius_px < outer_radius_px, elevations that
  // differ and lie within (-pi/2, pi/2); throws std::invalid_argument.
  void Validate() const;
  // Throws std::invalid_argument when the centre lies outside a width_px x height_px image.
  void CheckFitsImage(int width_px, int height_px) const;
};

struct OmniFrameOptions {
  std::string sensor_name = "omni";
  FrameEncoding encoding = FrameEncoding::kJpeg;
  int jpeg_quality = 90;  // 1..100, used for kJpeg
  MirrorCalibration mirror;

  void Validate() const;  // throws std::invalid_argument
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
