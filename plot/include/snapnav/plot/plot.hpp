#pragma once
// snapnav_plot: small line and bar charts drawn with OpenCV (core, imgproc, imgcodecs),
// so evaluation tools can write PNG figures next to their summary.json.
//
// Charts are white CV_8UC3 images with a title, axis labels, "nice" ticks (1/2/5 x 10^k),
// light grid lines and a legend box at the top right. Lines are anti-aliased. Input with
// nothing to plot (no series, all-NaN values) gives a chart with a "no data" note.

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace snapnav::plot {

// One line of a LineChart. NaN (or infinite) y values are gaps: the line is broken there.
// x may be empty, in which case the points are at x = 0, 1, 2, ...; otherwise x and y
// must have the same length.
struct Series {
  std::string name;
  std::vector<double> x, y;
};

struct Axes {
  std::string title, x_label, y_label;
  std::optional<double> y_min, y_max;  // fixed y range ends; unset ends follow the data
  bool y_from_zero = false;            // the automatic y range includes 0
  // LineChart: if non-empty, x is the category index 0..n-1 and the x ticks carry these
  // labels. (BarChart takes its categories from the groups.)
  std::vector<std::string> x_categories;
  bool value_labels = false;  // BarChart: print each bar's value at its end
};

// Lines with point markers and a legend. Throws std::invalid_argument if size is smaller
// than 200x150, a series' x and y lengths differ, or y_min >= y_max.
cv::Mat LineChart(const Axes& axes, const std::vector<Series>& series, cv::Size size = {800, 500});

// One category of a BarChart: one value per series (NaN: no bar).
struct BarGroup {
  std::string category;
  std::vector<double> values;
};

// Grouped bars from 0 (the y range always includes 0), one colour per series, and a legend.
// Throws std::invalid_argument if size is smaller than 200x150, a group's value count
// differs from series_names.size(), or y_min >= y_max.
cv::Mat BarChart(const Axes& axes, const std::vector<std::string>& series_names, const std::vector<BarGroup>& groups,
                 cv::Size size = {800, 500});

// Writes `image` (8-bit, 1/3/4 channels) as PNG, whatever the extension of `path`.
// Throws std::invalid_argument on an empty image and std::runtime_error naming the path
// when it cannot be encoded or written.
void SavePng(const cv::Mat& image, const std::string& path);

// Text turned 90 degrees counter-clockwise (reading bottom to top), centred on `centre`, black on a
// white patch (an axis label); clipped to the image; nothing for empty text.
void PutTextVertical(cv::Mat& img, const std::string& text, cv::Point centre, double scale);

// A fixed palette of 10 distinguishable colours (BGR, Tableau 10), repeating for higher
// indices. Negative indices wrap too.
cv::Scalar SeriesColour(int index);

// Tick values: the multiples of a step 1, 2 or 5 x 10^k, at most max_ticks of them, from
// the largest multiple <= lo to the smallest >= hi (the smallest such step). lo and hi may
// come in either order; a zero-width range is widened (by 10% of |lo|, or 1 around 0).
// Throws std::invalid_argument for non-finite bounds or max_ticks < 3.
std::vector<double> NiceTicks(double lo, double hi, int max_ticks);

}  // namespace snapnav::plot
