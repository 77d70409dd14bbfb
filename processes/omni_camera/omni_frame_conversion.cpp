#include "omni_frame_conversion.hpp"

#include <cmath>
#include <stdexcept>

#include "snapnav/glue/image_msg.hpp"

namespace snapnav::processes {

void CheckMirrorFitsImage(const nav::MirrorModel& mirror, int width_px, int height_px) {
  if (mirror.center_x_px > width_px - 1 || mirror.center_y_px > height_px - 1) {
    throw std::invalid_argument("mirror centre (" + std::to_string(mirror.center_x_px) + ", " +
                                std::to_string(mirror.center_y_px) +
                                ") px lies outside the " + std::to_string(width_px) + "x" + std::to_string(height_px) +
                                " image");
  }
}

void OmniFrameOptions::Validate() const {
  if (sensor_name.empty()) throw std::invalid_argument("sensor_name must not be empty");
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    throw std::invalid_argument("jpeg_quality must be in 1..100, got " + std::to_string(jpeg_quality));
  }
  if (glue::FrameEncodingName(encoding) == "?") throw std::invalid_argument("unknown frame encoding " + std::to_string(encoding));
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
  omni_frame_t msg = glue::ImageToFrame(image, options.encoding, options.jpeg_quality);
  msg.utime = utime;
  msg.sensor_name = options.sensor_name;
  msg.kind = omni_frame_t::RAW_OMNI;
  glue::SetMirror(options.mirror, &msg);
  return msg;
}

}  // namespace snapnav::processes
