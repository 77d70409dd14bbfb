#include "slam_plot.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {

cv::Mat DrawRun(const std::vector<std::vector<nav::Pose2>>& tracks, const std::vector<std::string>& names,
                const std::vector<Eigen::Vector2d>& map, const std::string& title) {
  if (names.size() != tracks.size()) throw std::invalid_argument("DrawRun: one name per track");
  double xmin = 1e18, xmax = -1e18, ymin = 1e18, ymax = -1e18;
  auto grow = [&](double x, double y) {
    xmin = std::min(xmin, x);
    xmax = std::max(xmax, x);
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
  };
  for (const auto& p : map) grow(p.x(), p.y());
  for (const auto& t : tracks)
    for (const auto& p : t) grow(p.x_m, p.y_m);
  if (xmin > xmax) xmin = xmax = ymin = ymax = 0;  // nothing to draw
  const int size = 900, top = 40;
  const double scale = (size - 40) / std::max({xmax - xmin, ymax - ymin, 1e-3});
  cv::Mat img(size + top, size, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double x, double y) {
    return cv::Point(static_cast<int>(20 + (x - xmin) * scale), static_cast<int>(top + size - 20 - (y - ymin) * scale));
  };
  for (const auto& p : map) img.at<cv::Vec3b>(px(p.x(), p.y())) = cv::Vec3b(80, 80, 80);
  for (size_t k = 0; k < tracks.size(); ++k) {
    const cv::Scalar c = plot::SeriesColour(static_cast<int>(k));
    for (size_t i = 1; i < tracks[k].size(); ++i) {
      cv::line(img, px(tracks[k][i - 1].x_m, tracks[k][i - 1].y_m), px(tracks[k][i].x_m, tracks[k][i].y_m), c, 2,
               cv::LINE_AA);
    }
    cv::putText(img, names[k], {size - 260, top + 20 + 22 * static_cast<int>(k)}, cv::FONT_HERSHEY_SIMPLEX, 0.55, c, 2,
                cv::LINE_AA);
  }
  cv::putText(img, title, {12, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  const int bar = static_cast<int>(5.0 * scale);
  cv::line(img, {20, top + size - 8}, {20 + bar, top + size - 8}, cv::Scalar(0, 0, 0), 2);
  cv::putText(img, "5 m", {24 + bar, top + size - 4}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  return img;
}

}  // namespace snapnav::eval
