#include "snapnav/plot/plot.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace snapnav::plot {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

int CountColour(const cv::Mat& img, const cv::Scalar& colour) {
  cv::Mat mask;
  cv::inRange(img, colour, colour, mask);
  return cv::countNonZero(mask);
}

int CountNonWhite(const cv::Mat& img) {
  cv::Mat mask;
  cv::inRange(img, cv::Scalar(255, 255, 255), cv::Scalar(255, 255, 255), mask);
  return static_cast<int>(img.total()) - cv::countNonZero(mask);
}

Series Sine(const std::string& name, double phase) {
  Series s{name, {}, {}};
  for (int i = 0; i <= 40; ++i) {
    s.x.push_back(i * 0.25);
    s.y.push_back(10 * std::sin(i * 0.25 + phase) + 12);
  }
  return s;
}

// True if the step is 1, 2 or 5 times a power of ten.
bool IsNiceStep(double step) {
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (std::abs(mantissa - m) < 1e-6) return true;
  }
  return false;
}

TEST(Plot, NiceTicksZeroTo97GivesStepsOf20) {
  const std::vector<double> ticks = NiceTicks(0, 97, 6);
  const std::vector<double> expected = {0, 20, 40, 60, 80, 100};
  ASSERT_EQ(ticks.size(), expected.size());
  for (size_t i = 0; i < ticks.size(); ++i) EXPECT_DOUBLE_EQ(ticks[i], expected[i]);
}

TEST(Plot, NiceTicksDecimalStepsAreExact) {
  const std::vector<double> ticks = NiceTicks(0.13, 0.67, 7);
  const std::vector<double> expected = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7};  // not 0.30000000000000004
  EXPECT_EQ(ticks, expected);
  EXPECT_EQ(NiceTicks(0.13, 0.61, 6), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8}));  // 0.1 would need 7
}

TEST(Plot, NiceTicksAreNiceCoverTheRangeAndRespectTheCount) {
  const std::vector<std::pair<double, double>> ranges = {{0, 97},      {0.13, 0.87},  {-3.2, 41}, {-0.004, -0.0011},
                                                         {1e5, 1.7e6}, {12.5, 12.51}, {-1, 1},    {3, 2}};
  for (const auto& [lo, hi] : ranges) {
    for (int max_ticks : {3, 5, 6, 10}) {
      SCOPED_TRACE(std::to_string(lo) + ".." + std::to_string(hi) + " max " + std::to_string(max_ticks));
      const std::vector<double> t = NiceTicks(lo, hi, max_ticks);
      ASSERT_GE(t.size(), 2u);
      EXPECT_LE(static_cast<int>(t.size()), max_ticks);
      EXPECT_LE(t.front(), std::min(lo, hi));
      EXPECT_GE(t.back(), std::max(lo, hi));
      const double step = t[1] - t[0];
      EXPECT_TRUE(IsNiceStep(step)) << step;
      for (size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, 1e-9 * step);
      // The step is the smallest that fits: the next smaller nice step needs too many ticks.
      const double mantissa = std::round(step / std::pow(10.0, std::floor(std::log10(step) + 1e-9)));
      const double smaller = mantissa == 2 ? step / 2 : mantissa == 5 ? step * 0.4 : step / 2;
      const double needed =
          std::ceil(std::max(lo, hi) / smaller - 1e-9) - std::floor(std::min(lo, hi) / smaller + 1e-9) + 1;
      EXPECT_GT(needed, max_ticks) << "step " << step << " is not the smallest";
    }
  }
}

TEST(Plot, NiceTicksWidensAZeroWidthRange) {
  for (double v : {0.0, 5.0, -1e-3}) {
    const std::vector<double> t = NiceTicks(v, v, 5);
    ASSERT_GE(t.size(), 2u);
    EXPECT_LT(t.front(), v);
    EXPECT_GT(t.back(), v);
  }
}

TEST(Plot, NiceTicksRejectsBadArguments) {
  EXPECT_THROW(NiceTicks(0, kNaN, 5), std::invalid_argument);
  EXPECT_THROW(NiceTicks(0, std::numeric_limits<double>::infinity(), 5), std::invalid_argument);
  EXPECT_THROW(NiceTicks(0, 1, 2), std::invalid_argument);
}

TEST(Plot, LineChartOfTwoSeriesDrawsBothColours) {
  Axes axes;
  axes.title = "Homing error";
  axes.x_label = "time [s]";
  axes.y_label = "error [m]";
  const cv::Mat img = LineChart(axes, {Sine("a", 0), Sine("b", 1.5)});
  ASSERT_EQ(img.size(), cv::Size(800, 500));
  ASSERT_EQ(img.type(), CV_8UC3);
  EXPECT_GT(CountNonWhite(img), 8000);

  // The same chart with nothing to plot still has both legend entries: the data must add
  // many pixels of each colour on top of those.
  Series empty_a{"a", {1, 2}, {kNaN, kNaN}}, empty_b{"b", {1, 2}, {kNaN, kNaN}};
  const cv::Mat legend_only = LineChart(axes, {empty_a, empty_b});
  for (int i : {0, 1}) {
    SCOPED_TRACE(i);
    EXPECT_GT(CountColour(legend_only, SeriesColour(i)), 10);
    EXPECT_GT(CountColour(img, SeriesColour(i)), CountColour(legend_only, SeriesColour(i)) + 500);
  }
}

TEST(Plot, PaletteColoursDiffer) {
  for (int i = 0; i < 10; ++i) {
    for (int j = i + 1; j < 10; ++j) EXPECT_GT(cv::norm(SeriesColour(i) - SeriesColour(j)), 40) << i << " " << j;
  }
  EXPECT_EQ(SeriesColour(10), SeriesColour(0));
  EXPECT_EQ(SeriesColour(-1), SeriesColour(9));
}

TEST(Plot, BarChartDrawsBarsInBothColours) {
  Axes axes;
  axes.title = "Success rate";
  axes.y_label = "%";
  axes.value_labels = true;
  const std::vector<BarGroup> groups = {{"lab", {80, 60}}, {"corridor", {55, 70}}, {"hall", {90, 20}}};
  const cv::Mat img = BarChart(axes, {"HOG-ALV", "ALV"}, groups);
  ASSERT_EQ(img.size(), cv::Size(800, 500));
  // A bar of 20% is still tens of pixels high and wide; the legend swatch is ~150 pixels.
  EXPECT_GT(CountColour(img, SeriesColour(0)), 5000);
  EXPECT_GT(CountColour(img, SeriesColour(1)), 5000);
  EXPECT_EQ(CountColour(img, SeriesColour(2)), 0);

  // Halving a value removes pixels of its colour only.
  std::vector<BarGroup> lower = groups;
  lower[0].values[1] = 30;
  const cv::Mat img2 = BarChart(axes, {"HOG-ALV", "ALV"}, lower);
  EXPECT_LT(CountColour(img2, SeriesColour(1)), CountColour(img, SeriesColour(1)) - 1000);
  EXPECT_NEAR(CountColour(img2, SeriesColour(0)), CountColour(img, SeriesColour(0)), 50);
}

TEST(Plot, BarChartHandlesNegativeAndMissingValues) {
  const cv::Mat img = BarChart({}, {"a", "b"}, {{"x", {-3, kNaN}}, {"y", {2, 5}}}, {300, 200});
  EXPECT_GT(CountColour(img, SeriesColour(0)), 200);
  EXPECT_THROW(BarChart({}, {"a", "b"}, {{"x", {1}}}), std::invalid_argument);
}

TEST(Plot, NaNGapsBreakTheLine) {
  Series s{"gappy", {}, {}};
  for (int i = 0; i < 30; ++i) {
    s.x.push_back(i);
    s.y.push_back(i >= 10 && i < 20 ? kNaN : 5.0);
  }
  Axes axes;
  axes.y_min = 0;
  axes.y_max = 10;
  const cv::Mat img = LineChart(axes, {s});
  // The row with the most series-coloured pixels is the line; along it the colour must come
  // in two runs separated by a long gap (the markers and the legend sample are elsewhere or short).
  const cv::Scalar colour = SeriesColour(0);
  cv::Mat mask;
  cv::inRange(img, colour, colour, mask);
  int best_row = 0, best_count = -1;
  for (int r = 0; r < mask.rows; ++r) {
    const int n = cv::countNonZero(mask.row(r));
    if (n > best_count) best_count = n, best_row = r;
  }
  ASSERT_GT(best_count, 200);
  int longest_gap = 0, gap = 0, first = -1, last = -1;
  for (int c = 0; c < mask.cols; ++c) {
    if (mask.at<uchar>(best_row, c)) {
      if (first < 0) first = c;
      if (last >= 0) longest_gap = std::max(longest_gap, gap);
      last = c;
      gap = 0;
    } else {
      ++gap;
    }
  }
  // Ten missing points of 29 intervals: roughly a third of the line's length.
  EXPECT_GT(longest_gap, (last - first) / 5);
}

TEST(Plot, NothingToPlotGivesAnEmptyFrame) {
  Axes axes;
  axes.title = "nothing";
  for (const std::vector<Series>& input : {std::vector<Series>{}, std::vector<Series>{{"nan", {}, {kNaN, kNaN, kNaN}}},
                                           std::vector<Series>{{"empty", {}, {}}}}) {
    const cv::Mat img = LineChart(axes, input);
    EXPECT_GT(CountNonWhite(img), 1000);  // frame, ticks, title, "no data"
  }
  EXPECT_EQ(CountColour(LineChart(axes, {}), SeriesColour(0)), 0);
  EXPECT_GT(CountNonWhite(BarChart(axes, {}, {})), 1000);
  EXPECT_GT(CountNonWhite(BarChart(axes, {"a"}, {{"g", {kNaN}}})), 1000);
}

TEST(Plot, ZeroWidthAndExtremeRangesDoNotCrash) {
  const Series vertical{"v", {3, 3, 3}, {1, 2, 4}};
  EXPECT_GT(CountColour(LineChart({}, {vertical}), SeriesColour(0)), 100);
  const Series flat{"f", {0, 1, 2}, {7, 7, 7}};
  EXPECT_GT(CountColour(LineChart({}, {flat}), SeriesColour(0)), 100);
  const Series single{"p", {2}, {2}};
  EXPECT_NO_THROW(LineChart({}, {single}));
  const Series huge{"h", {0, 1, 2}, {-1e300, 1e300, 0}};
  EXPECT_NO_THROW(LineChart({}, {huge}));
  Axes clipped;
  clipped.y_min = 0;
  clipped.y_max = 1;
  EXPECT_NO_THROW(LineChart(clipped, {Sine("outside", 0)}));
  Axes one_end;
  one_end.y_max = -100;  // all data above it
  EXPECT_NO_THROW(LineChart(one_end, {Sine("above", 0)}));
}

TEST(Plot, CategoryAxisPlacesPointsAtIndices) {
  Axes axes;
  axes.x_categories = {"run 1", "run 2", "run 3", "run 4"};
  axes.y_from_zero = true;
  const Series s{"rmse", {}, {0.3, 0.5, kNaN, 0.4}};
  EXPECT_GT(CountColour(LineChart(axes, {s}), SeriesColour(0)), 200);
}

TEST(Plot, RejectsInvalidInput) {
  EXPECT_THROW(LineChart({}, {}, {199, 500}), std::invalid_argument);
  EXPECT_THROW(LineChart({}, {}, {800, 149}), std::invalid_argument);
  EXPECT_THROW(BarChart({}, {}, {}, {100, 100}), std::invalid_argument);
  EXPECT_NO_THROW(LineChart({}, {}, {200, 150}));
  EXPECT_THROW(LineChart({}, {{"bad", {1, 2, 3}, {1, 2}}}), std::invalid_argument);
  Axes inverted;
  inverted.y_min = 2;
  inverted.y_max = 1;
  EXPECT_THROW(LineChart(inverted, {Sine("s", 0)}), std::invalid_argument);
}

TEST(Plot, SavePngWritesAReadableFile) {
  const cv::Mat img = LineChart({}, {Sine("s", 0)}, {320, 240});
  const std::string path = testing::TempDir() + "snapnav_plot_test.png";
  SavePng(img, path);
  const cv::Mat back = cv::imread(path, cv::IMREAD_COLOR);
  std::remove(path.c_str());
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(cv::norm(img, back, cv::NORM_INF), 0);
}

TEST(Plot, SavePngToUnwritablePathThrowsNamingThePath) {
  const cv::Mat img = LineChart({}, {}, {200, 150});
  const std::string path = "/nonexistent-snapnav-dir/sub/figure.png";
  try {
    SavePng(img, path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_THROW(SavePng(cv::Mat(), "x.png"), std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::plot
