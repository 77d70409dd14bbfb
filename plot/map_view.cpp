#include "snapnav/plot/map_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "snapnav/plot/plot.hpp"

namespace snapnav::plot {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kShift = 4;  // fractional bits of the sub-pixel coordinates given to OpenCV
constexpr double kShiftScale = 1 << kShift;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kGrid(230, 230, 230);
const cv::Scalar kFrame(120, 120, 120);
const cv::Scalar kZeroLine(200, 200, 200);  // the x = 0 and y = 0 grid lines

cv::Point Fixed(const cv::Point2d& p) { return {cvRound(p.x * kShiftScale), cvRound(p.y * kShiftScale)}; }

std::string FormatMetres(double value, double step) {
  char buf[32];
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, std::abs(value) < 1e-9 * step ? 0.0 : value);
  return buf;
}

}  // namespace

void WorldBounds::Extend(double x_m, double y_m) {
  if (!std::isfinite(x_m) || !std::isfinite(y_m)) return;
  if (empty) {
    x_min = x_max = x_m;
    y_min = y_max = y_m;
    empty = false;
    return;
  }
  x_min = std::min(x_min, x_m);
  x_max = std::max(x_max, x_m);
  y_min = std::min(y_min, y_m);
  y_max = std::max(y_max, y_m);
}

void WorldBounds::Extend(const WorldBounds& other) {
  if (other.empty) return;
  Extend(other.x_min, other.y_min);
  Extend(other.x_max, other.y_max);
}

EllipseAxes CovarianceEllipse(double xx, double xy, double yy, double sigma) {
  if (!std::isfinite(xx) || !std::isfinite(xy) || !std::isfinite(yy)) {
    throw std::invalid_argument("CovarianceEllipse: covariance is not finite");
  }
  if (!(sigma > 0)) throw std::invalid_argument("CovarianceEllipse: sigma must be positive");
  // Eigenvalues of the symmetric 2x2 matrix.
  const double mean = 0.5 * (xx + yy);
  const double diff = 0.5 * (xx - yy);
  const double radius = std::hypot(diff, xy);
  const double l1 = std::max(0.0, mean + radius), l2 = std::max(0.0, mean - radius);
  EllipseAxes e;
  e.major = sigma * std::sqrt(l1);
  e.minor = sigma * std::sqrt(l2);
  e.angle_rad = radius > 0 ? 0.5 * std::atan2(2 * xy, xx - yy) : 0.0;
  return e;
}

MapView::MapView(const cv::Rect& area, const WorldBounds& bounds, double min_span_m, double margin_fraction)
    : area_(area) {
  if (area.width < 50 || area.height < 50) throw std::invalid_argument("MapView: area smaller than 50 x 50 px");
  if (!(min_span_m > 0)) throw std::invalid_argument("MapView: min_span_m must be positive");
  WorldBounds b = bounds;
  if (b.empty) b.Extend(0, 0);
  double cx = 0.5 * (b.x_min + b.x_max), cy = 0.5 * (b.y_min + b.y_max);
  double span_x = (b.x_max - b.x_min) * (1 + 2 * std::max(0.0, margin_fraction));
  double span_y = (b.y_max - b.y_min) * (1 + 2 * std::max(0.0, margin_fraction));
  span_x = std::max(span_x, min_span_m);
  span_y = std::max(span_y, min_span_m);
  scale_ = std::min(area.width / span_x, area.height / span_y);
  x0_ = cx - 0.5 * area.width / scale_;
  y0_ = cy - 0.5 * area.height / scale_;
}

WorldBounds MapView::visible() const {
  WorldBounds w;
  w.Extend(x0_, y0_);
  w.Extend(x0_ + area_.width / scale_, y0_ + area_.height / scale_);
  return w;
}

cv::Point2d MapView::ToPixel(double x_m, double y_m) const {
  return {area_.x + (x_m - x0_) * scale_, area_.y + area_.height - (y_m - y0_) * scale_};
}

bool MapView::Contains(double x_m, double y_m) const {
  const cv::Point2d p = ToPixel(x_m, y_m);
  return p.x >= area_.x && p.x < area_.x + area_.width && p.y >= area_.y && p.y < area_.y + area_.height;
}

void MapView::DrawAxes(cv::Mat& img, const std::string& x_label, const std::string& y_label) const {
  img(area_ & cv::Rect(0, 0, img.cols, img.rows)).setTo(kWhite);
  const WorldBounds w = visible();
  const int max_x_ticks = std::clamp(area_.width / 70 + 1, 3, 15);
  const int max_y_ticks = std::clamp(area_.height / 50 + 1, 3, 15);
  const double font = 0.4;
  for (int axis = 0; axis < 2; ++axis) {
    const double lo = axis == 0 ? w.x_min : w.y_min, hi = axis == 0 ? w.x_max : w.y_max;
    const std::vector<double> ticks = NiceTicks(lo, hi, axis == 0 ? max_x_ticks : max_y_ticks);
    const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
    for (double t : ticks) {
      if (t < lo || t > hi) continue;
      const std::string label = FormatMetres(t, step);
      int baseline = 0;
      const cv::Size ts = cv::getTextSize(label, kFont, font, 1, &baseline);
      if (axis == 0) {
        const int px = cvRound(ToPixel(t, 0).x);
        cv::line(img, {px, area_.y}, {px, area_.y + area_.height - 1}, t == 0 ? kZeroLine : kGrid, 1);
        cv::line(img, {px, area_.y + area_.height}, {px, area_.y + area_.height + 4}, kFrame, 1);
        cv::putText(img, label, {px - ts.width / 2, area_.y + area_.height + 8 + ts.height}, kFont, font, kBlack, 1,
                    cv::LINE_AA);
      } else {
        const int py = cvRound(ToPixel(0, t).y);
        cv::line(img, {area_.x, py}, {area_.x + area_.width - 1, py}, t == 0 ? kZeroLine : kGrid, 1);
        cv::line(img, {area_.x - 4, py}, {area_.x - 1, py}, kFrame, 1);
        cv::putText(img, label, {area_.x - 7 - ts.width, py + ts.height / 2}, kFont, font, kBlack, 1, cv::LINE_AA);
      }
    }
  }
  cv::rectangle(img, area_, kFrame, 1);
  int baseline = 0;
  const cv::Size xs = cv::getTextSize(x_label, kFont, 0.45, 1, &baseline);
  cv::putText(img, x_label, {area_.x + area_.width / 2 - xs.width / 2, area_.y + area_.height + 36}, kFont, 0.45,
              kBlack, 1, cv::LINE_AA);
  PutTextVertical(img, y_label, {area_.x - 38, area_.y + area_.height / 2}, 0.45);
}

void MapView::DrawScaleBar(cv::Mat& img) const {
  const double target_m = area_.width / scale_ / 6;
  double step = std::pow(10.0, std::floor(std::log10(target_m)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * step <= target_m) {
      step *= m;
      break;
    }
  }
  const int len = cvRound(step * scale_);
  const cv::Point a(area_.x + 15, area_.y + area_.height - 15), b(a.x + len, a.y);
  cv::rectangle(img, {a.x - 5, a.y - 22}, {b.x + 5 + 40, a.y + 6}, kWhite, cv::FILLED);
  cv::line(img, a, b, kBlack, 2);
  cv::line(img, {a.x, a.y - 5}, {a.x, a.y + 3}, kBlack, 2);
  cv::line(img, {b.x, b.y - 5}, {b.x, b.y + 3}, kBlack, 2);
  char label[32];
  std::snprintf(label, sizeof(label), step >= 1 ? "%.0f m" : step >= 0.1 ? "%.1f m" : "%.2f m", step);
  cv::putText(img, label, {a.x, a.y - 9}, kFont, 0.42, kBlack, 1, cv::LINE_AA);
}

void MapView::DrawPolyline(cv::Mat& img, const std::vector<cv::Point2d>& world, const cv::Scalar& colour,
                           int thickness) const {
  if (world.size() < 2) return;
  cv::Mat roi = img(area_);
  std::vector<cv::Point> pts;
  pts.reserve(world.size());
  const cv::Point2d origin(area_.x, area_.y);
  for (const auto& w : world) {
    const cv::Point2d p = ToPixel(w.x, w.y) - origin;
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    // OpenCV clips lines itself; keep the fixed-point values in range.
    pts.push_back(Fixed({std::clamp(p.x, -1e5, 1e5), std::clamp(p.y, -1e5, 1e5)}));
  }
  cv::polylines(roi, pts, false, colour, thickness, cv::LINE_AA, kShift);
}

void MapView::DrawPoints(cv::Mat& img, const std::vector<cv::Point2f>& world, const cv::Scalar& colour,
                         int size_px) const {
  const cv::Vec3b c(static_cast<uint8_t>(colour[0]), static_cast<uint8_t>(colour[1]), static_cast<uint8_t>(colour[2]));
  for (const auto& w : world) {
    const cv::Point2d p = ToPixel(w.x, w.y);
    if (!(p.x >= area_.x && p.x < area_.x + area_.width && p.y >= area_.y && p.y < area_.y + area_.height)) continue;
    if (size_px <= 1) {
      img.at<cv::Vec3b>(static_cast<int>(p.y), static_cast<int>(p.x)) = c;
    } else {
      const int h = size_px / 2;
      const cv::Rect r = cv::Rect(static_cast<int>(p.x) - h, static_cast<int>(p.y) - h, size_px, size_px) & area_;
      img(r).setTo(colour);
    }
  }
}

void MapView::DrawCircle(cv::Mat& img, double x_m, double y_m, int radius_px, const cv::Scalar& colour,
                         int thickness) const {
  cv::Mat roi = img(area_);
  const cv::Point2d p = ToPixel(x_m, y_m) - cv::Point2d(area_.x, area_.y);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || std::abs(p.x) > 1e5 || std::abs(p.y) > 1e5) return;
  cv::circle(roi, Fixed(p), radius_px * (1 << kShift), colour, thickness, cv::LINE_AA, kShift);
}

void MapView::DrawCovarianceEllipse(cv::Mat& img, double x_m, double y_m, double xx, double xy, double yy,
                                    double sigma, const cv::Scalar& colour, int thickness) const {
  if (!std::isfinite(xx) || !std::isfinite(xy) || !std::isfinite(yy) || (xx <= 0 && yy <= 0)) return;
  const EllipseAxes e = CovarianceEllipse(xx, xy, yy, sigma);
  const double a_px = e.major * scale_, b_px = e.minor * scale_;
  if (a_px < 0.5 || a_px > 1e5) return;
  cv::Mat roi = img(area_);
  const cv::Point2d p = ToPixel(x_m, y_m) - cv::Point2d(area_.x, area_.y);
  if (std::abs(p.x) > 1e5 || std::abs(p.y) > 1e5) return;
  // Image rows grow downwards: a counter-clockwise world angle is clockwise in the image.
  cv::ellipse(roi, cv::RotatedRect(p, cv::Size2f(static_cast<float>(2 * a_px), static_cast<float>(std::max(1.0, 2 * b_px))),
                                   static_cast<float>(-e.angle_rad * 180 / M_PI)),
              colour, thickness, cv::LINE_AA);
}

void MapView::DrawPose(cv::Mat& img, double x_m, double y_m, double theta_rad, int size_px,
                       const cv::Scalar& colour) const {
  const cv::Point2d c = ToPixel(x_m, y_m) - cv::Point2d(area_.x, area_.y);
  if (!std::isfinite(c.x) || !std::isfinite(c.y) || std::abs(c.x) > 1e5 || std::abs(c.y) > 1e5) return;
  const double s = size_px;
  auto at = [&](double forward, double left) {
    // Image y is down: world (cos, sin) -> image (cos, -sin).
    const double dx = forward * std::cos(theta_rad) - left * std::sin(theta_rad);
    const double dy = forward * std::sin(theta_rad) + left * std::cos(theta_rad);
    return Fixed({c.x + dx, c.y - dy});
  };
  const std::vector<cv::Point> tri{at(s, 0), at(-0.6 * s, 0.55 * s), at(-0.6 * s, -0.55 * s)};
  cv::Mat roi = img(area_);
  cv::fillConvexPoly(roi, tri, colour, cv::LINE_AA, kShift);
  cv::polylines(roi, tri, true, kBlack, 1, cv::LINE_AA, kShift);
}

void MapView::DrawArrow(cv::Mat& img, double x_m, double y_m, double angle_rad, int length_px,
                        const cv::Scalar& colour, int thickness) const {
  const cv::Point2d a = ToPixel(x_m, y_m) - cv::Point2d(area_.x, area_.y);
  if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(angle_rad) || std::abs(a.x) > 1e5 ||
      std::abs(a.y) > 1e5) {
    return;
  }
  const cv::Point2d b(a.x + length_px * std::cos(angle_rad), a.y - length_px * std::sin(angle_rad));
  cv::Mat roi = img(area_);
  cv::arrowedLine(roi, Fixed(a), Fixed(b), colour, thickness, cv::LINE_AA, kShift, 0.25);
}

cv::Rect DrawLegend(cv::Mat& img, cv::Point top_left, const std::vector<LegendEntry>& entries, double font_scale) {
  constexpr int kRow = 20, kMark = 26;
  int width = 0;
  for (size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    const int cy = top_left.y + static_cast<int>(i) * kRow + kRow / 2;
    const int x = top_left.x;
    switch (e.mark) {
      case LegendMark::kLine:
        if (e.dashed) {
          for (int s = 0; s < kMark - 4; s += 7) cv::line(img, {x + s, cy}, {x + std::min(s + 4, kMark - 4), cy}, e.colour, 2);
        } else {
          cv::line(img, {x, cy}, {x + kMark - 4, cy}, e.colour, 2, cv::LINE_AA);
        }
        break;
      case LegendMark::kDot:
        cv::circle(img, {x + kMark / 2 - 2, cy}, 4, e.colour, cv::FILLED, cv::LINE_AA);
        break;
      case LegendMark::kCircle:
        cv::circle(img, {x + kMark / 2 - 2, cy}, 5, e.colour, 1, cv::LINE_AA);
        break;
      case LegendMark::kPose: {
        const std::vector<cv::Point> tri{{x + kMark - 6, cy}, {x + 4, cy - 6}, {x + 4, cy + 6}};
        cv::fillConvexPoly(img, tri, e.colour, cv::LINE_AA);
        break;
      }
      case LegendMark::kArrow:
        cv::arrowedLine(img, {x, cy}, {x + kMark - 4, cy}, e.colour, 2, cv::LINE_AA, 0, 0.35);
        break;
      case LegendMark::kNone:
        break;
    }
    const int text_x = e.mark == LegendMark::kNone ? x : x + kMark + 4;
    DrawText(img, e.label, {text_x, cy}, font_scale);
    int baseline = 0;
    width = std::max(width, text_x - x + cv::getTextSize(e.label, kFont, font_scale, 1, &baseline).width);
  }
  return {top_left.x, top_left.y, width, static_cast<int>(entries.size()) * kRow};
}

void DrawText(cv::Mat& img, const std::string& text, cv::Point left_centre, double font_scale,
              const cv::Scalar& colour, int thickness) {
  if (text.empty()) return;
  int baseline = 0;
  const cv::Size ts = cv::getTextSize(text, kFont, font_scale, thickness, &baseline);
  cv::putText(img, text, {left_centre.x, left_centre.y + ts.height / 2}, kFont, font_scale, colour, thickness,
              cv::LINE_AA);
}

}  // namespace snapnav::plot
