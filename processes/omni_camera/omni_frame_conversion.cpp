#include "omni_frame_conversion.hpp"

#include <cmath>
#include <stdexcept>

#include "snapnav/glue/image_msg.hpp"

namespace snapnav::processes {

FrameEncoding ParseFrameEncoding(const std::string& name) {
  if (name == "gray8") return FrameEncoding::kGray8;
  if (name == "rgb8") return FrameEncoding::kRgb8;
  if (name == "jpeg") return FrameEncoding::kJpeg;
  if (name == "png") return FrameEncoding::kPng;
  throw std::invalid_argument("unknown encoding '" + name + "' (gray8, rgb8, jpeg or png)");
}

std::string FrameEncodingName(FrameEncoding encoding) {
  switch (encoding) {
    case FrameEncoding::kGray8:
      return "gray8";
    case FrameEncoding::kRgb8:
      return "rgb8";
    case FrameEncoding::kJpeg:
      return "jpeg";
    case FrameEncoding::kPng:
      return "png";
  }
  return "?";
}

int8_t WireEncoding(FrameEncoding encoding) {
  switch (encoding) {
    case FrameEncoding::kGray8:
      return omni_frame_t::GRAY8;
    case FrameEncoding::kRgb8:
      return omni_frame_t::RGB8;
    case FrameEncoding::kJpeg:
      return omni_frame_t::JPEG;
    case FrameEncoding::kPng:
      return omni_frame_t::PNG;
  }
  throw std::invalid_argument("bad FrameEncoding");
}

void MirrorCalibration::Validate() const {
  for (double v :
       {center_x_px, center_y_px, inner_radius_px, outer_radius_px, elevation_inner_rad, elevation_outer_rad}) {
    if (!std::isfinite(v)) throw std::invalid_argument("mirror calibration values must be finite numbers");
  }
  if (center_x_px < 0 || center_y_px < 0) {
    throw std::invalid_argument("mirror centre (" + std::to_string(center_x_px) + ", " + std::to_string(center_y_px) +
                                ") px must not be negative");
  }
  if (inner_radius_px < 0) throw std::invalid_argument("mirror inner_radius_px must be >= 0");
  if (!(outer_radius_px > inner_radius_px)) {
    throw std::invalid_argument("mirror outer_radius_px (" + std::to_string(outer_radius_px) +
                                ") must be larger than inner_radius_px (" + std::to_string(inner_radius_px) + ")");
  }
  if (elevation_inner_rad == elevation_outer_rad || std::abs(elevation_inner_rad) >= M_PI / 2 ||
      std::abs(elevation_outer_rad) >= M_PI / 2) {
    throw std::invalid_argument(
        "mirror elevation_inner_deg and elevation_outer_deg must differ and lie within "
        "(-pi/2, pi/2)");
  }
}

void MirrorCalibration::CheckFitsImage(int width_px, int height_px) const {
  if (center_x_px > width_px - 1 || center_y_px > height_px - 1) {
    throw std::invalid_argument("mirror centre (" + std::to_string(center_x_px) + ", " + std::to_string(center_y_px) +
                                ") px lies outside the " + std::to_string(width_px) + "x" + std::to_string(height_px) +
                                " image");
  }
}

void OmniFrameOptions::Validate() const {
  if (sensor_name.empty()) throw std::invalid_argument("sensor_name must not be empty");
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw std::invalid_argument("jpeg_quality must be in 1..100, got " + std::to_string(jpeg_quality));
  }
  WireEncoding(encoding);
  mirror.Validate();
}

omni_frame_t MatToOmniFrame(const cv::Mat& image, int64_t utime, const OmniFrameOptions& options) {
  if (image.empty()) throw std::invalid_argument("empty image");
  if (image.depth() != CV_8U) {
    throw std::invalid_argument("expected an 8-bit image, got OpenCV depth " + std::to_string(image.depth()));
  }
  if (image.channels() != 1 && image.channels() != 3 && image.channels() != 4) {
    throw std::invalid_argument("expected 1, 3 or 4 channels, got " + std::to_string(image.channels()));
  }
  omni_frame_t msg = glue::ImageToFrame(image, WireEncoding(options.encoding), options.jpeg_quality);
  msg.utime = utime;
  msg.sensor_name = options.sensor_name;
  msg.kind = omni_frame_t::RAW_OMNI;
  msg.mirror_center_x_px = static_cast<float>(options.mirror.center_x_px);
  msg.mirror_center_y_px = static_cast<float>(options.mirror.center_y_px);
  msg.mirror_inner_radius_px = static_cast<float>(options.mirror.inner_radius_px);
  msg.mirror_outer_radius_px = static_cast<float>(options.mirror.outer_radius_px);
  msg.mirror_elevation_inner_rad = static_cast<float>(options.mirror.elevation_inner_rad);
  msg.mirror_elevation_outer_rad = static_cast<float>(options.mirror.elevation_outer_rad);
  return msg;
}

}  // namespace snapnav::processes
