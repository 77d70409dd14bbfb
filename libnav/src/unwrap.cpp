#include "snapnav/nav/unwrap.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

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
}

void Unwrapper::Unwrap(const cv::Mat& raw, cv::Mat* panorama) const {
  if (raw.empty()) throw std::invalid_argument("unwrap: empty image");
  if (raw.size() != raw_size_) {
    throw std::invalid_argument("unwrap: image is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) +
                                ", the calibration is for " + std::to_string(raw_size_.width) + "x" +
                                std::to_string(raw_size_.height));
  }
  cv::remap(raw, *panorama, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
}

std::optional<MirrorModel> CalibrateMirror(const cv::Mat& raw, const MirrorModel& prior,
                                           const MirrorSearchOptions& o) {
  if (raw.empty()) return std::nullopt;
  cv::Mat gray;
  if (raw.channels() == 3) cv::cvtColor(raw, gray, cv::COLOR_BGR2GRAY); else gray = raw;
  // The mirror is the large bright disc: threshold between border and content, then the
  // largest contour's enclosing circle gives the outer radius and centre.
  cv::Mat mask;
  cv::threshold(gray, mask, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {9, 9}));
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  const double side = std::min(raw.cols, raw.rows);
  double best_area = 0;
  std::optional<MirrorModel> best;
  for (const auto& contour : contours) {
    const double area = cv::contourArea(contour);
    if (area <= best_area) continue;
    cv::Point2f centre;
    float radius = 0;
    cv::minEnclosingCircle(contour, centre, radius);
    if (radius < o.min_radius_frac * side || radius > o.max_radius_frac * side) continue;
    // A disc fills most of its enclosing circle.
    if (area < 0.6 * M_PI * radius * radius) continue;
    MirrorModel m = prior;
    m.center_x_px = centre.x;
    m.center_y_px = centre.y;
    m.outer_radius_px = radius - 1.0;
    m.inner_radius_px = o.inner_radius_frac * m.outer_radius_px;
    best_area = area;
    best = m;
  }
  if (!best) return std::nullopt;
  // The inner radius: the dark disc of the camera at the centre, measured along rays.
  std::vector<double> edges;
  for (int k = 0; k < 32; ++k) {
    const double a = 2 * M_PI * k / 32;
    for (double r = 2; r < 0.6 * best->outer_radius_px; r += 0.5) {
      const int x = static_cast<int>(std::lround(best->center_x_px + r * std::cos(a)));
      const int y = static_cast<int>(std::lround(best->center_y_px + r * std::sin(a)));
      if (x < 0 || y < 0 || x >= mask.cols || y >= mask.rows) break;
      if (mask.at<uint8_t>(y, x)) {
        edges.push_back(r);
        break;
      }
    }
  }
  if (edges.size() >= 16) {
    std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
    const double inner = edges[edges.size() / 2];
    if (inner > 3 && inner < 0.6 * best->outer_radius_px) best->inner_radius_px = inner + 1.0;
  }
  return best;
}

}  // namespace snapnav::nav
