#include "snapnav/nav/homing/unwrap.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/homing/image_mask.hpp"

namespace snapnav::nav {

Unwrapper::Unwrapper(const MirrorModel& mirror, const PanoramaModel& panorama, cv::Size raw_size)
    : mirror_(mirror), panorama_(panorama), raw_size_(raw_size) {
  mirror_.Validate();
  panorama_.Validate();
  if (raw_size.width <= 0 || raw_size.height <= 0) throw std::invalid_argument("unwrap: empty raw image size");
  const double lo = std::min(mirror.elevation_inner_rad, mirror.elevation_outer_rad);
  const double hi = std::max(mirror.elevation_inner_rad, mirror.elevation_outer_rad);
  if (panorama.elevation_bottom_rad < lo - 1e-6 || panorama.elevation_top_rad > hi + 1e-6) {
    throw std::invalid_argument("unwrap: the panorama's elevations lie outside what the mirror sees");
  }
  if (mirror.center_x_px < 0 || mirror.center_y_px < 0 || mirror.center_x_px >= raw_size.width ||
      mirror.center_y_px >= raw_size.height) {
    throw std::invalid_argument("unwrap: mirror centre (" + std::to_string(mirror.center_x_px) + ", " +
                                std::to_string(mirror.center_y_px) + ") lies outside the " +
                                std::to_string(raw_size.width) + "x" + std::to_string(raw_size.height) + " image");
  }
  cv::Mat map_x(panorama.height_px, panorama.width_px, CV_32FC1), map_y(panorama.height_px, panorama.width_px, CV_32FC1);
  for (int c = 0; c < panorama.width_px; ++c) {
    const double bearing = panorama.BearingOfColumn(c);
    for (int r = 0; r < panorama.height_px; ++r) {
      const auto px = MirrorPixel(mirror, bearing, panorama.ElevationOfRow(r));
      map_x.at<float>(r, c) = px ? static_cast<float>(px->x()) : -1.f;
      map_y.at<float>(r, c) = px ? static_cast<float>(px->y()) : -1.f;
    }
  }
  cv::convertMaps(map_x, map_y, map1_, map2_, CV_16SC2);  // fixed point: faster remap
  // Where the ring runs past the image's border, the panorama would show the border's black: masked.
  cv::Mat inside;
  cv::remap(cv::Mat(raw_size, CV_8UC1, cv::Scalar(255)), inside, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(0));
  if (cv::countNonZero(inside != 255) > 0) inside_ = inside == 255;
  panorama_mask_ = inside_;
}

void Unwrapper::Unwrap(const cv::Mat& raw, cv::Mat* panorama) const {
  if (raw.empty()) throw std::invalid_argument("unwrap: empty image");
  if (raw.size() != raw_size_) {
    throw std::invalid_argument("unwrap: image is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) +
                                ", the calibration is for " + std::to_string(raw_size_.width) + "x" +
                                std::to_string(raw_size_.height));
  }
  cv::remap(raw, *panorama, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  if (!panorama_mask_.empty() && (panorama->channels() == 1 || panorama->channels() == 3)) {
    FillMasked(panorama_mask_, panorama);
  }
}

void Unwrapper::SetMask(const cv::Mat& raw_mask) {
  CheckMask(raw_mask, raw_size_, "unwrap");
  if (raw_mask.empty()) {
    panorama_mask_ = inside_;
    return;
  }
  cv::Mat usable = raw_mask != 0, sampled;
  // Bilinear: 255 only where every raw pixel with a weight is usable (and inside the image).
  cv::remap(usable, sampled, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  // A new matrix: assigning the comparison would write into the one panorama_mask_ may share with inside_.
  cv::Mat mask = sampled == 255;
  panorama_mask_ = mask;
}

}  // namespace snapnav::nav
