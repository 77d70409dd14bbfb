// snapnav_plot's map view: world -> pixel with equal scales, covariance ellipses, drawing clipped
// to the area, checked by the pixels.
#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "snapnav/plot/map_view.hpp"

namespace snapnav::plot {
namespace {

int CountColour(const cv::Mat& img, const cv::Scalar& colour, const cv::Rect& roi) {
  cv::Mat mask;
  cv::inRange(img(roi), colour, colour, mask);
  return cv::countNonZero(mask);
}

TEST(CovarianceEllipse, AxesAndAngle) {
  // Diagonal: the axes are the standard deviations times sigma.
  EllipseAxes e = CovarianceEllipse(4.0, 0.0, 1.0, 2.0);
  EXPECT_NEAR(e.major, 4.0, 1e-12);
  EXPECT_NEAR(e.minor, 2.0, 1e-12);
  EXPECT_NEAR(e.angle_rad, 0.0, 1e-12);
  // y larger: the major axis is along y.
  e = CovarianceEllipse(1.0, 0.0, 9.0, 1.0);
  EXPECT_NEAR(e.major, 3.0, 1e-12);
  EXPECT_NEAR(std::abs(e.angle_rad), M_PI / 2, 1e-12);
  // Correlated x and y: eigenvalues 3 and 1, major axis at 45 degrees.
  e = CovarianceEllipse(2.0, 1.0, 2.0, 1.0);
  EXPECT_NEAR(e.major, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(e.minor, 1.0, 1e-12);
  EXPECT_NEAR(e.angle_rad, M_PI / 4, 1e-12);
  // A slightly negative eigenvalue (rounding) is zero.
  e = CovarianceEllipse(1.0, 1.0 + 1e-12, 1.0, 1.0);
  EXPECT_GE(e.minor, 0.0);
  EXPECT_THROW(CovarianceEllipse(NAN, 0, 1, 2), std::invalid_argument);
  EXPECT_THROW(CovarianceEllipse(1, 0, 1, 0), std::invalid_argument);
}

TEST(MapView, EqualScalesCentredWithMargin) {
  WorldBounds b;
  b.Extend(0, 0);
  b.Extend(10, 2);
  b.Extend(NAN, 100);  // ignored
  EXPECT_DOUBLE_EQ(b.y_max, 2);
  const MapView view(cv::Rect(100, 50, 400, 400), b, 1.0, 0.0);
  EXPECT_NEAR(view.pixels_per_m(), 40.0, 1e-9);  // 10 m across 400 px
  const cv::Point2d origin = view.ToPixel(0, 0), far = view.ToPixel(10, 2);
  EXPECT_NEAR(origin.x, 100, 1e-9);
  EXPECT_NEAR(far.x, 500, 1e-9);
  EXPECT_NEAR(origin.y - far.y, 80, 1e-9);        // y up, same scale
  EXPECT_NEAR((origin.y + far.y) / 2, 250, 1e-9);  // centred vertically
  EXPECT_TRUE(view.Contains(5, 1));
  EXPECT_FALSE(view.Contains(5, 10));
  const WorldBounds v = view.visible();
  EXPECT_NEAR(v.x_min, 0, 1e-9);
  EXPECT_NEAR(v.y_max - v.y_min, 10, 1e-9);
}

TEST(MapView, EmptyBoundsShowTheMinimumSpan) {
  const MapView view(cv::Rect(0, 0, 200, 100), WorldBounds{}, 2.0);
  EXPECT_NEAR(view.pixels_per_m(), 50.0, 1e-9);  // 2 m on the shorter side
  EXPECT_TRUE(view.Contains(0, 0));
  EXPECT_THROW(MapView(cv::Rect(0, 0, 20, 20), WorldBounds{}), std::invalid_argument);
  EXPECT_THROW(MapView(cv::Rect(0, 0, 200, 200), WorldBounds{}, 0.0), std::invalid_argument);
}

TEST(MapView, DrawsInsideTheAreaOnly) {
  cv::Mat img(300, 400, CV_8UC3, cv::Scalar(255, 255, 255));
  WorldBounds b;
  b.Extend(0, 0);
  b.Extend(4, 4);
  const cv::Rect area(60, 20, 250, 230);
  const MapView view(area, b, 1.0);
  view.DrawAxes(img);
  const cv::Scalar red(0, 0, 255), blue(255, 0, 0), green(0, 200, 0);
  // A line leaving the area far to the right, an ellipse, a pose.
  view.DrawPolyline(img, {{0, 0}, {2, 2}, {100, 2}}, red, 3);
  view.DrawCovarianceEllipse(img, 2, 2, 0.25, 0, 0.04, 2.0, blue, 2);
  view.DrawPose(img, 3, 1, 0.5, 10, green);
  EXPECT_GT(CountColour(img, red, area), 50);
  EXPECT_GT(CountColour(img, blue, area), 50);
  EXPECT_GT(CountColour(img, green, area), 20);
  // Nothing outside the area in those colours.
  cv::Mat outside = img.clone();
  outside(area).setTo(cv::Scalar(255, 255, 255));
  EXPECT_EQ(CountColour(outside, red, {0, 0, 400, 300}), 0);
  // A zero covariance draws nothing.
  cv::Mat before = img.clone();
  view.DrawCovarianceEllipse(img, 2, 2, 0, 0, 0, 2.0, cv::Scalar(1, 2, 3), 2);
  EXPECT_EQ(cv::norm(img, before, cv::NORM_L1), 0.0);
  // The ellipse is as wide as 2 sigma: sigma_x = 0.5 m -> semi-axis 1 m.
  cv::Mat e(300, 400, CV_8UC3, cv::Scalar(255, 255, 255));
  view.DrawCovarianceEllipse(e, 2, 2, 0.25, 0, 0.04, 2.0, blue, 1);
  cv::Mat mask;
  cv::inRange(e, cv::Scalar(200, 0, 0), cv::Scalar(255, 120, 120), mask);
  const cv::Rect box = cv::boundingRect(mask);
  EXPECT_NEAR(box.width, 2 * view.pixels_per_m(), 3);
  EXPECT_NEAR(box.height, 2 * 0.4 * view.pixels_per_m(), 3);
}

TEST(Legend, OneRowPerEntry) {
  cv::Mat img(200, 300, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Rect r = DrawLegend(img, {10, 10},
                                {{"a line", cv::Scalar(0, 0, 255)},
                                 {"a dot", cv::Scalar(0, 255, 0), LegendMark::kDot},
                                 {"an arrow", cv::Scalar(255, 0, 0), LegendMark::kArrow}});
  EXPECT_EQ(r.height, 60);
  EXPECT_GT(r.width, 40);
  EXPECT_GT(CountColour(img, cv::Scalar(0, 0, 255), r), 10);
  EXPECT_GT(CountColour(img, cv::Scalar(0, 255, 0), r), 10);
}

}  // namespace
}  // namespace snapnav::plot
