#include "snapnav/plot/plot.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace snapnav::plot {
namespace {

constexpr int kMinWidthPx = 200;
constexpr int kMinHeightPx = 150;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTickFontScale = 0.42;
constexpr double kLabelFontScale = 0.5;
constexpr double kTitleFontScale = 0.6;
constexpr int kShift = 4;  // fractional bits of the sub-pixel coordinates given to OpenCV
constexpr double kShiftScale = 1 << kShift;
constexpr int kLineThicknessPx = 2;
constexpr int kMarkerRadiusPx = 3;
constexpr int kTickLengthPx = 5;
constexpr double kBarGroupFraction = 0.8;  // of a category's slot

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(228, 228, 228);
const cv::Scalar kGreyText(110, 110, 110);
const cv::Scalar kLegendBorder(160, 160, 160);

struct Tick {
  double value;
  std::string label;
};

// Plot area in pixels and the data ranges it shows.
struct Frame {
  cv::Rect plot;
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;

  double PxX(double x) const { return plot.x + (x - x_lo) / (x_hi - x_lo) * plot.width; }
  double PxY(double y) const { return plot.y + plot.height - (y - y_lo) / (y_hi - y_lo) * plot.height; }
};

void CheckSize(cv::Size size) {
  if (size.width < kMinWidthPx || size.height < kMinHeightPx) {
    throw std::invalid_argument("plot: image size " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                                " is smaller than " + std::to_string(kMinWidthPx) + "x" + std::to_string(kMinHeightPx));
  }
}

cv::Size TextSize(const std::string& text, double scale) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, 1, &baseline);
}

// Draws text with its anchor at (x, y): h_align -1/0/1 = left/centre/right of x;
// y is the vertical centre of the capital letters.
void PutText(cv::Mat& img, const std::string& text, double x, double y, int h_align, double scale,
             const cv::Scalar& colour = kBlack) {
  if (text.empty()) return;
  const cv::Size ts = TextSize(text, scale);
  const double left = h_align < 0 ? x : h_align == 0 ? x - ts.width / 2.0 : x - ts.width;
  cv::putText(img, text, {cvRound(left), cvRound(y + ts.height / 2.0)}, kFont, scale, colour, 1, cv::LINE_AA);
}


// Tick label with just enough digits for the step.
std::string FormatTick(double value, double step) {
  char buf[64];
  const double magnitude = std::max(std::abs(value), step);
  if (magnitude >= 1e6 || step < 1e-4) {
    const int digits =
        std::max(1, static_cast<int>(std::floor(std::log10(magnitude)) - std::floor(std::log10(step) + 1e-9)) + 1);
    std::snprintf(buf, sizeof(buf), "%.*g", std::min(digits, 15), value);
  } else {
    const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
    std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
  }
  return buf;
}

// Bar value label: integers as such, else about three significant digits.
std::string FormatValue(double value) {
  char buf[64];
  const double a = std::abs(value);
  if (a < 1e5 && value == std::round(value)) {
    std::snprintf(buf, sizeof(buf), "%.0f", value);
  } else if (a >= 1e5 || a < 1e-2) {
    std::snprintf(buf, sizeof(buf), "%.3g", value);
  } else {
    std::snprintf(buf, sizeof(buf), "%.*f", a >= 100 ? 0 : a >= 10 ? 1 : 2, value);
  }
  return buf;
}

std::vector<Tick> Labelled(const std::vector<double>& values) {
  const double step = values.size() > 1 ? values[1] - values[0] : 1.0;
  std::vector<Tick> ticks;
  for (double v : values) ticks.push_back({v, FormatTick(v, step)});
  return ticks;
}

// The y range and ticks: the data (and 0 if asked) covered by nice ticks; explicit
// ends replace the automatic ones, keeping the ticks inside them.
void MakeYAxis(const Axes& axes, const std::vector<double>& values, bool include_zero, int max_ticks, Frame* frame,
               std::vector<Tick>* ticks) {
  for (const auto& bound : {axes.y_min, axes.y_max}) {
    if (bound && !std::isfinite(*bound)) throw std::invalid_argument("plot: y_min and y_max must be finite");
  }
  if (axes.y_min && axes.y_max && !(*axes.y_min < *axes.y_max)) {
    throw std::invalid_argument("plot: y_min must be smaller than y_max");
  }
  double lo = 0, hi = 1;
  if (!values.empty()) {
    const auto [min_it, max_it] = std::minmax_element(values.begin(), values.end());
    lo = *min_it;
    hi = *max_it;
  }
  if (include_zero) {
    lo = std::min(lo, 0.0);
    hi = std::max(hi, 0.0);
  }
  if (axes.y_min) lo = *axes.y_min;
  if (axes.y_max) hi = *axes.y_max;
  if (hi < lo) lo = hi = axes.y_min ? *axes.y_min : *axes.y_max;  // the data lie beyond the one fixed end

  std::vector<double> values_ticks = NiceTicks(lo, hi, max_ticks);
  frame->y_lo = axes.y_min ? *axes.y_min : values_ticks.front();
  frame->y_hi = axes.y_max ? *axes.y_max : values_ticks.back();
  if (axes.y_min || axes.y_max) values_ticks = NiceTicks(frame->y_lo, frame->y_hi, max_ticks);
  const double eps = 1e-9 * (frame->y_hi - frame->y_lo);
  ticks->clear();
  for (const Tick& t : Labelled(values_ticks)) {
    if (t.value >= frame->y_lo - eps && t.value <= frame->y_hi + eps) ticks->push_back(t);
  }
}

// Category ticks at 0..n-1 on an axis from -0.5 to n-0.5; labels thinned out so they do
// not overlap.
std::vector<Tick> CategoryTicks(const std::vector<std::string>& categories, int plot_width_px, Frame* frame) {
  const int n = static_cast<int>(categories.size());
  frame->x_lo = -0.5;
  frame->x_hi = n - 0.5;
  int widest = 0;
  for (const auto& c : categories) widest = std::max(widest, TextSize(c, kTickFontScale).width);
  const double slot_px = static_cast<double>(plot_width_px) / std::max(n, 1);
  const int stride = std::max(1, static_cast<int>(std::ceil((widest + 8) / slot_px)));
  std::vector<Tick> ticks;
  for (int i = 0; i < n; ++i) ticks.push_back({static_cast<double>(i), i % stride == 0 ? categories[i] : ""});
  return ticks;
}

// Numeric x ticks inside the data range padded by 3% (a zero-width range is widened by
// NiceTicks); as many as fit without the labels touching.
std::vector<Tick> NumericXTicks(const std::vector<double>& xs, int plot_width_px, int right_margin_px, Frame* frame) {
  double lo = 0, hi = 1;
  if (!xs.empty()) {
    const auto [min_it, max_it] = std::minmax_element(xs.begin(), xs.end());
    lo = *min_it;
    hi = *max_it;
  }
  int max_ticks = std::clamp(plot_width_px / 80 + 1, 3, 11);
  for (;; --max_ticks) {
    const std::vector<double> values = NiceTicks(lo, hi, max_ticks);
    if (hi - lo > 1e-12 * std::max(std::abs(lo), std::abs(hi))) {  // else NiceTicks widened it
      const double pad = 0.03 * (hi - lo);
      frame->x_lo = lo - pad;
      frame->x_hi = hi + pad;
    } else {
      frame->x_lo = values.front();
      frame->x_hi = values.back();
    }
    std::vector<Tick> ticks;
    const double eps = 1e-9 * (frame->x_hi - frame->x_lo);
    for (const Tick& t : Labelled(values)) {
      if (t.value >= frame->x_lo - eps && t.value <= frame->x_hi + eps) ticks.push_back(t);
    }
    // Labels are centred under their ticks but pushed left to end within the right margin
    // (see DrawFrame); they fit if none comes within 8 px of the previous one.
    bool fits = true;
    double previous_right = -std::numeric_limits<double>::infinity();
    for (const Tick& t : ticks) {
      const double w = TextSize(t.label, kTickFontScale).width;
      const double centre = (t.value - frame->x_lo) / (frame->x_hi - frame->x_lo) * plot_width_px;
      const double right = std::min(centre + w / 2, plot_width_px + right_margin_px - 2.0);
      fits = fits && right - w >= previous_right + 8;
      previous_right = right;
    }
    if (fits || max_ticks == 3) return ticks;
  }
}

// Margins around the plot area: title on top, tick labels and x label below, y label and
// tick labels on the left.
struct Layout {
  int top, bottom, right, y_label_band;
};

Layout MakeLayout(const Axes& axes) {
  Layout l;
  const int title_h = TextSize("Hg", kTitleFontScale).height;
  const int label_h = TextSize("Hg", kLabelFontScale).height;
  const int tick_h = TextSize("0", kTickFontScale).height;
  l.top = axes.title.empty() ? 16 : title_h + 26;
  l.bottom = kTickLengthPx + tick_h + 14 + (axes.x_label.empty() ? 0 : label_h + 14);
  l.right = 20;
  l.y_label_band = axes.y_label.empty() ? 6 : label_h + 16;
  return l;
}

// Sets frame->plot's horizontal extent from the y tick labels' width.
void PlaceHorizontally(const Layout& layout, const std::vector<Tick>& y_ticks, cv::Size size, Frame* frame) {
  int widest = 0;
  for (const Tick& t : y_ticks) widest = std::max(widest, TextSize(t.label, kTickFontScale).width);
  const int left = std::min(layout.y_label_band + widest + kTickLengthPx + 8, size.width / 2);
  frame->plot.x = left;
  frame->plot.width = size.width - left - layout.right;
}

void DrawFrame(cv::Mat& img, const Axes& axes, const Layout& layout, const Frame& f, const std::vector<Tick>& x_ticks,
               const std::vector<Tick>& y_ticks) {
  const cv::Rect& p = f.plot;
  const int bottom = p.y + p.height;
  for (const Tick& t : y_ticks) {
    const int y = cvRound(f.PxY(t.value));
    cv::line(img, {p.x, y}, {p.x + p.width, y}, kGrid, 1);
    cv::line(img, {p.x - kTickLengthPx, y}, {p.x, y}, kBlack, 1);
    PutText(img, t.label, p.x - kTickLengthPx - 4, y, 1, kTickFontScale);
  }
  const int tick_h = TextSize("0", kTickFontScale).height;
  for (const Tick& t : x_ticks) {
    const int x = cvRound(f.PxX(t.value));
    cv::line(img, {x, bottom}, {x, bottom + kTickLengthPx}, kBlack, 1);
    // Centred under the tick, but kept inside the image (long labels at the ends).
    const double half_w = TextSize(t.label, kTickFontScale).width / 2.0;
    const double cx = std::clamp<double>(x, half_w + 2, std::max(half_w + 2, img.cols - half_w - 2));
    PutText(img, t.label, cx, bottom + kTickLengthPx + 6 + tick_h / 2.0, 0, kTickFontScale);
  }
  cv::rectangle(img, p, kBlack, 1);
  if (!axes.title.empty()) PutText(img, axes.title, img.cols / 2.0, layout.top / 2.0, 0, kTitleFontScale);
  if (!axes.x_label.empty()) {
    const int label_h = TextSize("Hg", kLabelFontScale).height;
    PutText(img, axes.x_label, p.x + p.width / 2.0, img.rows - 10 - label_h / 2.0, 0, kLabelFontScale);
  }
  PutTextVertical(img, axes.y_label, {layout.y_label_band / 2, p.y + p.height / 2}, kLabelFontScale);
}

void DrawNoData(cv::Mat& img, const Frame& f) {
  PutText(img, "no data", f.plot.x + f.plot.width / 2.0, f.plot.y + f.plot.height / 2.0, 0, kLabelFontScale, kGreyText);
}

enum class LegendMark { kLine, kBox };

// Legend box in the top-right corner of the plot area.
void DrawLegend(cv::Mat& img, const Frame& f, const std::vector<std::string>& names, LegendMark mark) {
  if (names.empty()) return;
  constexpr int kSamplePx = 22, kPadPx = 8, kRowPx = 18;
  int widest = 0;
  for (const auto& n : names) widest = std::max(widest, TextSize(n, kTickFontScale).width);
  const int w = kPadPx + kSamplePx + 6 + widest + kPadPx;
  const int h = kPadPx + kRowPx * static_cast<int>(names.size()) - 4 + kPadPx / 2;
  const cv::Rect box(std::max(f.plot.x + 1, f.plot.x + f.plot.width - 8 - w), f.plot.y + 8, w, h);
  cv::rectangle(img, box, kWhite, cv::FILLED);
  cv::rectangle(img, box, kLegendBorder, 1);
  for (size_t i = 0; i < names.size(); ++i) {
    const cv::Scalar colour = SeriesColour(static_cast<int>(i));
    const int cy = box.y + kPadPx + kRowPx * static_cast<int>(i) + 5;
    const int x0 = box.x + kPadPx;
    if (mark == LegendMark::kLine) {
      cv::line(img, {x0, cy}, {x0 + kSamplePx, cy}, colour, kLineThicknessPx, cv::LINE_AA);
      cv::circle(img, {x0 + kSamplePx / 2, cy}, kMarkerRadiusPx, colour, cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(img, cv::Rect(x0 + 4, cy - 5, kSamplePx - 8, 11), colour, cv::FILLED);
    }
    PutText(img, names[i], x0 + kSamplePx + 6, cy, -1, kTickFontScale);
  }
}

// Liang-Barsky: clips segment a-b to rect r (in pixels); false if nothing is left.
bool ClipSegment(const cv::Rect2d& r, cv::Point2d* a, cv::Point2d* b) {
  const double dx = b->x - a->x, dy = b->y - a->y;
  double t0 = 0, t1 = 1;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a->x - r.x, r.x + r.width - a->x, a->y - r.y, r.y + r.height - a->y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  const cv::Point2d start = *a;
  *a = start + t0 * cv::Point2d(dx, dy);
  *b = start + t1 * cv::Point2d(dx, dy);
  return true;
}

cv::Point Fixed(const cv::Point2d& p) { return {cvRound(p.x * kShiftScale), cvRound(p.y * kShiftScale)}; }

// The points of a series, x filled in with indices when absent.
std::vector<double> XsOf(const Series& s) {
  if (!s.x.empty()) return s.x;
  std::vector<double> xs(s.y.size());
  for (size_t i = 0; i < xs.size(); ++i) xs[i] = static_cast<double>(i);
  return xs;
}

void DrawSeries(cv::Mat& img, const Frame& f, const std::vector<double>& xs, const std::vector<double>& ys,
                const cv::Scalar& colour) {
  const cv::Rect2d clip(f.plot.x, f.plot.y, f.plot.width, f.plot.height);
  // Pixel positions, NaN where the point is missing. Far-off values are limited so the
  // arithmetic stays finite; they are clipped anyway.
  constexpr double kFarPx = 1e7;
  std::vector<cv::Point2d> px(xs.size());
  for (size_t i = 0; i < xs.size(); ++i) {
    if (std::isfinite(xs[i]) && std::isfinite(ys[i])) {
      px[i] = {std::clamp(f.PxX(xs[i]), -kFarPx, kFarPx), std::clamp(f.PxY(ys[i]), -kFarPx, kFarPx)};
    } else {
      px[i] = {std::nan(""), std::nan("")};
    }
  }
  for (size_t i = 1; i < px.size(); ++i) {
    cv::Point2d a = px[i - 1], b = px[i];
    if (std::isnan(a.x) || std::isnan(b.x) || !ClipSegment(clip, &a, &b)) continue;
    cv::line(img, Fixed(a), Fixed(b), colour, kLineThicknessPx, cv::LINE_AA, kShift);
  }
  for (const cv::Point2d& p : px) {
    const bool inside = p.x >= clip.x - 0.5 && p.x <= clip.x + clip.width + 0.5 && p.y >= clip.y - 0.5 &&
                        p.y <= clip.y + clip.height + 0.5;  // the frame's edges included
    if (std::isnan(p.x) || !inside) continue;
    cv::circle(img, Fixed(p), kMarkerRadiusPx << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
  }
}

int MaxYTicks(int plot_height_px) { return std::clamp(plot_height_px / 45 + 1, 3, 11); }

}  // namespace

void PutTextVertical(cv::Mat& img, const std::string& text, cv::Point centre, double scale) {
  if (text.empty()) return;
  int baseline = 0;
  const cv::Size ts = cv::getTextSize(text, kFont, scale, 1, &baseline);
  cv::Mat patch(ts.height + baseline + 4, ts.width + 4, img.type(), kWhite);
  cv::putText(patch, text, {2, ts.height + 2}, kFont, scale, kBlack, 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(patch, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect dst(centre.x - turned.cols / 2, centre.y - turned.rows / 2, turned.cols, turned.rows);
  const cv::Rect visible = dst & cv::Rect(0, 0, img.cols, img.rows);
  if (visible.empty()) return;
  turned(visible - dst.tl()).copyTo(img(visible));
}

std::vector<double> NiceTicks(double lo, double hi, int max_ticks) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) throw std::invalid_argument("NiceTicks: lo and hi must be finite");
  if (max_ticks < 3) throw std::invalid_argument("NiceTicks: max_ticks must be at least 3");
  if (lo > hi) std::swap(lo, hi);
  if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    const double pad = lo == 0 ? 1.0 : 0.1 * std::abs(lo);
    lo -= pad;
    hi += pad;
  }
  const double range = hi - lo;
  if (!std::isfinite(range)) throw std::invalid_argument("NiceTicks: range too large");
  // Steps m * 10^k from below the smallest possible one upwards; the first that needs at
  // most max_ticks ticks wins. A step >= range needs at most 3, so this ends.
  const int k0 = static_cast<int>(std::floor(std::log10(range / max_ticks))) - 1;
  for (int k = k0;; ++k) {
    const double scale = std::pow(10.0, std::abs(k));
    for (int m : {1, 2, 5}) {
      const double step = k < 0 ? m / scale : m * scale;
      const double first = std::floor(lo / step + 1e-9), last = std::ceil(hi / step - 1e-9);
      if (last - first + 1 > max_ticks) continue;
      std::vector<double> ticks;
      for (double i = first; i <= last; ++i) {
        // i * m / 10^-k keeps decimal steps exact (0.6, not 0.6000000000000001).
        double v = k < 0 ? i * m / scale : i * m * scale;
        if (std::abs(v) < 1e-9 * step) v = 0;  // no "-0"
        ticks.push_back(v);
      }
      return ticks;
    }
  }
}

cv::Scalar SeriesColour(int index) {
  // Tableau 10, BGR.
  static const cv::Scalar kPalette[] = {
      {180, 119, 31}, {14, 127, 255},  {44, 160, 44},   {40, 39, 214},  {189, 103, 148},
      {75, 86, 140},  {194, 119, 227}, {127, 127, 127}, {34, 189, 188}, {207, 190, 23},
  };
  constexpr int kCount = sizeof(kPalette) / sizeof(kPalette[0]);
  return kPalette[((index % kCount) + kCount) % kCount];
}

cv::Mat LineChart(const Axes& axes, const std::vector<Series>& series, cv::Size size) {
  CheckSize(size);
  std::vector<std::vector<double>> xs_of;
  std::vector<double> xs, ys;  // every plotted point's coordinates, for the ranges
  for (const Series& s : series) {
    if (!s.x.empty() && s.x.size() != s.y.size()) {
      throw std::invalid_argument("LineChart: series '" + s.name + "' has " + std::to_string(s.x.size()) +
                                  " x values but " + std::to_string(s.y.size()) + " y values");
    }
    xs_of.push_back(XsOf(s));
    for (size_t i = 0; i < s.y.size(); ++i) {
      if (std::isfinite(xs_of.back()[i]) && std::isfinite(s.y[i])) {
        xs.push_back(xs_of.back()[i]);
        ys.push_back(s.y[i]);
      }
    }
  }

  cv::Mat img(size, CV_8UC3, kWhite);
  const Layout layout = MakeLayout(axes);
  Frame f;
  f.plot.y = layout.top;
  f.plot.height = size.height - layout.top - layout.bottom;
  std::vector<Tick> y_ticks;
  MakeYAxis(axes, ys, axes.y_from_zero, MaxYTicks(f.plot.height), &f, &y_ticks);
  PlaceHorizontally(layout, y_ticks, size, &f);
  const std::vector<Tick> x_ticks = axes.x_categories.empty() ? NumericXTicks(xs, f.plot.width, layout.right, &f)
                                                              : CategoryTicks(axes.x_categories, f.plot.width, &f);
  DrawFrame(img, axes, layout, f, x_ticks, y_ticks);

  if (ys.empty()) DrawNoData(img, f);
  for (size_t i = 0; i < series.size(); ++i) {
    DrawSeries(img, f, xs_of[i], series[i].y, SeriesColour(static_cast<int>(i)));
  }
  std::vector<std::string> names;
  for (size_t i = 0; i < series.size(); ++i) {
    names.push_back(series[i].name.empty() ? "series " + std::to_string(i) : series[i].name);
  }
  DrawLegend(img, f, names, LegendMark::kLine);
  return img;
}

cv::Mat BarChart(const Axes& axes, const std::vector<std::string>& series_names, const std::vector<BarGroup>& groups,
                 cv::Size size) {
  CheckSize(size);
  std::vector<double> values;
  std::vector<std::string> categories;
  for (const BarGroup& g : groups) {
    if (g.values.size() != series_names.size()) {
      throw std::invalid_argument("BarChart: group '" + g.category + "' has " + std::to_string(g.values.size()) +
                                  " values for " + std::to_string(series_names.size()) + " series");
    }
    for (double v : g.values) {
      if (std::isfinite(v)) values.push_back(v);
    }
    categories.push_back(g.category);
  }

  cv::Mat img(size, CV_8UC3, kWhite);
  const Layout layout = MakeLayout(axes);
  Frame f;
  f.plot.y = layout.top;
  f.plot.height = size.height - layout.top - layout.bottom;
  std::vector<Tick> y_ticks;
  MakeYAxis(axes, values, true, MaxYTicks(f.plot.height), &f, &y_ticks);
  PlaceHorizontally(layout, y_ticks, size, &f);
  std::vector<Tick> x_ticks;
  if (groups.empty()) {
    f.x_lo = 0;
    f.x_hi = 1;
  } else {
    x_ticks = CategoryTicks(categories, f.plot.width, &f);
  }
  DrawFrame(img, axes, layout, f, x_ticks, y_ticks);
  if (values.empty()) DrawNoData(img, f);

  const int top = f.plot.y, bottom = f.plot.y + f.plot.height;
  auto to_row = [&](double v) { return cvRound(std::clamp(f.PxY(v), double(top), double(bottom))); };
  const int base_row = to_row(0.0);
  const double slot_px = static_cast<double>(f.plot.width) / std::max<size_t>(groups.size(), 1);
  const double bar_px = slot_px * kBarGroupFraction / std::max<size_t>(series_names.size(), 1);
  const int gap_px = bar_px > 6 ? 1 : 0;  // white line between neighbouring bars
  for (size_t g = 0; g < groups.size(); ++g) {
    const double group_left = f.PxX(static_cast<double>(g)) - slot_px * kBarGroupFraction / 2;
    for (size_t s = 0; s < series_names.size(); ++s) {
      const double v = groups[g].values[s];
      if (!std::isfinite(v)) continue;
      const int x0 = cvRound(group_left + s * bar_px);
      const int x1 = std::max(x0 + 1, cvRound(group_left + (s + 1) * bar_px) - gap_px);
      const int row = to_row(v);
      const cv::Rect bar(x0, std::min(row, base_row), x1 - x0, std::max(1, std::abs(row - base_row)));
      cv::rectangle(img, bar & f.plot, SeriesColour(static_cast<int>(s)), cv::FILLED);
      if (axes.value_labels) {
        const double label_y = v >= 0 ? bar.y - 9 : bar.y + bar.height + 9;
        PutText(img, FormatValue(v), (x0 + x1) / 2.0, label_y, 0, kTickFontScale * 0.9);
      }
    }
  }
  if (f.y_lo < 0 && f.y_hi > 0) cv::line(img, {f.plot.x, base_row}, {f.plot.x + f.plot.width, base_row}, kBlack, 1);
  DrawLegend(img, f, series_names, LegendMark::kBox);
  return img;
}

void SavePng(const cv::Mat& image, const std::string& path) {
  if (image.empty()) throw std::invalid_argument("SavePng: empty image for '" + path + "'");
  std::vector<uchar> png;
  try {
    if (!cv::imencode(".png", image, png)) throw std::runtime_error("encoder failed");
  } catch (const std::exception& e) {
    throw std::runtime_error("SavePng: cannot encode '" + path + "' as PNG: " + e.what());
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("SavePng: cannot open '" + path + "' for writing: " + std::strerror(errno));
  out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  out.close();
  if (!out) throw std::runtime_error("SavePng: cannot write '" + path + "'");
}

}  // namespace snapnav::plot
