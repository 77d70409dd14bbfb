#pragma once
// snapnav_plot: a metric top view of the plane for maps and trajectories (x to the right, y up,
// the same scale on both axes), drawn with OpenCV: world -> pixel, a grid with tick labels in
// metres, a scale bar, covariance ellipses, robot poses, arrows, and a legend of coloured entries.
// The viewer process and the evaluation figures draw with it.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace snapnav::plot {

// An axis-aligned world rectangle [m]; empty until a point is added.
struct WorldBounds {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
  bool empty = true;
  // Grows the rectangle to contain (x, y); non-finite points are ignored.
  void Extend(double x_m, double y_m);
  void Extend(const WorldBounds& other);
};

// The axes of the ellipse of a 2D covariance [[xx, xy], [xy, yy]] scaled by `sigma` (2: the
// 2-sigma ellipse): semi-axes (major >= minor, same unit as sqrt of the covariance) and the
// angle of the major axis counter-clockwise from x [rad]. Negative eigenvalues (rounding) are
// taken as 0. Throws std::invalid_argument for non-finite input or sigma <= 0.
struct EllipseAxes {
  double major = 0, minor = 0, angle_rad = 0;
};
EllipseAxes CovarianceEllipse(double xx, double xy, double yy, double sigma);

class MapView {
 public:
  // Shows `bounds` inside the pixel rectangle `area` with equal scales, centred, widened by
  // `margin_fraction` of its span on each side and to at least `min_span_m` on each axis. Empty
  // bounds show min_span_m around the origin. Throws std::invalid_argument for an area smaller than
  // 50 x 50 px or a non-positive min_span_m.
  MapView(const cv::Rect& area, const WorldBounds& bounds, double min_span_m = 1.0, double margin_fraction = 0.05);

  const cv::Rect& area() const { return area_; }
  double pixels_per_m() const { return scale_; }
  // The world rectangle the whole area shows.
  WorldBounds visible() const;

  cv::Point2d ToPixel(double x_m, double y_m) const;
  bool Contains(double x_m, double y_m) const;

  // White background, light grid lines at "nice" metre ticks, tick labels below and left of
  // the area (keep about 45 px free there), the axis labels, and a frame.
  void DrawAxes(cv::Mat& img, const std::string& x_label = "x [m]", const std::string& y_label = "y [m]") const;
  // A bar of a nice length (1/2/5 x 10^k m, about a sixth of the width) at the bottom left.
  void DrawScaleBar(cv::Mat& img) const;

  // Everything below is clipped to the area. Thickness in pixels; lines are anti-aliased.
  void DrawPolyline(cv::Mat& img, const std::vector<cv::Point2d>& world, const cv::Scalar& colour,
                    int thickness = 1) const;
  // Single pixels (size 1) or small filled squares of `size_px`.
  void DrawPoints(cv::Mat& img, const std::vector<cv::Point2f>& world, const cv::Scalar& colour, int size_px = 1) const;
  void DrawCircle(cv::Mat& img, double x_m, double y_m, int radius_px, const cv::Scalar& colour,
                  int thickness = 1) const;  // thickness < 0: filled
  // The `sigma` ellipse of the position covariance [m^2] centred at (x, y); nothing when the
  // covariance is zero or not finite.
  void DrawCovarianceEllipse(cv::Mat& img, double x_m, double y_m, double xx, double xy, double yy, double sigma,
                             const cv::Scalar& colour, int thickness = 1) const;
  // A robot: a filled isosceles triangle of `size_px` pointing along theta.
  void DrawPose(cv::Mat& img, double x_m, double y_m, double theta_rad, int size_px, const cv::Scalar& colour) const;
  // An arrow from (x, y) along `angle_rad` (world frame, counter-clockwise from x), `length_px` long.
  void DrawArrow(cv::Mat& img, double x_m, double y_m, double angle_rad, int length_px, const cv::Scalar& colour,
                 int thickness = 2) const;

 private:
  cv::Rect area_;
  double scale_ = 1;        // pixels per metre
  double x0_ = 0, y0_ = 0;  // world point at the area's bottom-left corner
};

// Legend entries: a short line (kLine), a filled dot (kDot), a hollow circle (kCircle), a
// triangle (kPose) or an arrow (kArrow) in the entry's colour, then the label.
enum class LegendMark { kLine, kDot, kCircle, kPose, kArrow, kNone };
struct LegendEntry {
  std::string label;
  cv::Scalar colour;
  LegendMark mark = LegendMark::kLine;
  bool dashed = false;  // kLine: a broken line
};
// Draws the entries one per line from `top_left` (row height 20 px) and returns the rectangle
// they cover.
cv::Rect DrawLegend(cv::Mat& img, cv::Point top_left, const std::vector<LegendEntry>& entries,
                    double font_scale = 0.45);

// Text with its left end at x and the vertical centre of capitals at y (OpenCV's simplex font).
void DrawText(cv::Mat& img, const std::string& text, cv::Point left_centre, double font_scale = 0.45,
              const cv::Scalar& colour = cv::Scalar(0, 0, 0), int thickness = 1);

}  // namespace snapnav::plot
