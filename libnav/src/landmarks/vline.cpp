#include "snapnav/nav/landmarks/vline.hpp"

#include "snapnav/nav/landmarks/landmarks.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace snapnav::nav {

void VlineOptions::Validate() const {
  if (!(canny_low >= 0 && canny_high >= canny_low)) {
    throw std::invalid_argument("vline: need 0 <= canny_low <= canny_high");
  }
  if (!(blur_sigma_px >= 0)) throw std::invalid_argument("vline: blur_sigma_px must be >= 0");
  if (!(hough_rho_px > 0)) throw std::invalid_argument("vline: hough_rho_px must be > 0");
  if (!(hough_theta_deg > 0 && hough_theta_deg <= 90)) throw std::invalid_argument("vline: hough_theta_deg in (0, 90]");
  if (hough_threshold < 1) throw std::invalid_argument("vline: hough_threshold must be >= 1");
  if (!(min_segment_px > 0)) throw std::invalid_argument("vline: min_segment_px must be > 0");
  if (!(max_gap_px >= 0)) throw std::invalid_argument("vline: max_gap_px must be >= 0");
  if (!(max_tilt_deg > 0 && max_tilt_deg <= 60)) throw std::invalid_argument("vline: max_tilt_deg in (0, 60]");
  if (!(cluster_px >= 0)) throw std::invalid_argument("vline: cluster_px must be >= 0");
  if (!(min_line_px >= 0)) throw std::invalid_argument("vline: min_line_px must be >= 0");
  if (window_px < 2) throw std::invalid_argument("vline: window_px must be >= 2");
  if (bins < 2 || bins > 360) throw std::invalid_argument("vline: bins must be in 2..360");
}

namespace {

// Column difference a - b wrapped into [-width/2, width/2).
double WrapColumns(double diff, double width) {
  diff = std::fmod(diff + width / 2, width);
  if (diff < 0) diff += width;
  return diff - width / 2;
}

double FoldColumn(double col, double width) {
  col = std::fmod(col, width);
  if (col < 0) col += width;
  return col < width ? col : 0.0;  // fmod of a tiny negative plus width can round to width
}

// The blurred panorama's Sobel derivatives on an image padded by wrapping columns: every
// column of the panorama sees its true neighbours, and a line across the seam appears
// whole (twice: once in the interior, once in the padding).
struct Prepared {
  int width = 0, height = 0;
  int pad = 0;     // padded column = panorama column + pad
  cv::Mat dx, dy;  // CV_16S, height x (width + 2 pad)
};

void CheckImage(const cv::Mat& gray, const VlineOptions& o) {
  if (gray.empty()) throw std::invalid_argument("vline: empty panorama");
  if (gray.type() != CV_8UC1) {
    throw std::invalid_argument("vline: need an 8-bit single-channel panorama, got type " +
                                std::to_string(gray.type()));
  }
  if (gray.cols < o.window_px || gray.rows < 3) {
    throw std::invalid_argument("vline: panorama " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                                " is narrower than window_px " + std::to_string(o.window_px) + " or lower than 3 rows");
  }
}

Prepared Prepare(const cv::Mat& gray, const VlineOptions& o) {
  o.Validate();
  CheckImage(gray, o);
  Prepared p;
  p.width = gray.cols;
  p.height = gray.rows;
  // Wide enough for the descriptor window, and for a line of the largest tilt across the seam.
  const int tilt_extent = static_cast<int>(std::ceil(gray.rows * std::tan(o.max_tilt_deg * M_PI / 180)));
  p.pad = std::min(std::max(o.window_px / 2 + 2, tilt_extent + 4), gray.cols);
  cv::Mat padded;
  cv::copyMakeBorder(gray, padded, 0, 0, p.pad, p.pad, cv::BORDER_WRAP);
  if (o.blur_sigma_px > 0) {
    cv::GaussianBlur(padded, padded, {0, 0}, o.blur_sigma_px, o.blur_sigma_px, cv::BORDER_REPLICATE);
  }
  cv::Sobel(padded, p.dx, CV_16S, 1, 0, 3, 1, 0, cv::BORDER_REPLICATE);
  cv::Sobel(padded, p.dy, CV_16S, 0, 1, 3, 1, 0, cv::BORDER_REPLICATE);
  return p;
}

struct Segment {
  double column = 0;  // panorama column of the midpoint, in [0, width)
  int top = 0, bottom = 0;
  double length = 0;  // Euclidean [px]
  double slope = 0;   // column change per row
};

std::vector<VerticalLine> Detect(const Prepared& p, const VlineOptions& o) {
  cv::Mat edges;
  cv::Canny(p.dx, p.dy, edges, o.canny_low, o.canny_high);
  // Edge pixels of near-horizontal edges cannot vote for a near-vertical line.
  const double keep_deg = std::min(89.0, o.max_tilt_deg + 30);
  const float tan_keep = static_cast<float>(std::tan(keep_deg * M_PI / 180));
  for (int y = 0; y < edges.rows; ++y) {
    uint8_t* e = edges.ptr<uint8_t>(y);
    const int16_t* gx = p.dx.ptr<int16_t>(y);
    const int16_t* gy = p.dy.ptr<int16_t>(y);
    for (int x = 0; x < edges.cols; ++x) {
      if (e[x] && std::abs(gy[x]) > tan_keep * std::abs(gx[x])) e[x] = 0;
    }
  }
  std::vector<cv::Vec4i> raw;
  cv::HoughLinesP(edges, raw, o.hough_rho_px, o.hough_theta_deg * M_PI / 180, o.hough_threshold, o.min_segment_px,
                  o.max_gap_px);

  const double w = p.width;
  const double max_tilt_rad = o.max_tilt_deg * M_PI / 180;
  std::vector<Segment> segments;
  segments.reserve(raw.size());
  for (const cv::Vec4i& s : raw) {
    const int dx = s[2] - s[0], dy = s[3] - s[1];
    if (std::atan2(std::abs(dx), std::abs(dy)) > max_tilt_rad) continue;  // the theta threshold
    Segment seg;
    seg.column = FoldColumn(0.5 * (s[0] + s[2]) - p.pad, w);
    seg.top = std::min(s[1], s[3]);
    seg.bottom = std::max(s[1], s[3]);
    seg.length = std::hypot(dx, dy);
    seg.slope = dy != 0 ? static_cast<double>(dx) / dy : 0.0;
    segments.push_back(seg);
  }
  if (segments.empty()) return {};

  // Clustering: the longest free segment seeds a line and takes every free segment whose
  // midpoint lies within cluster_px of the seed extended along its own slope (the pieces of a
  // tilted line have different midpoint columns). Both copies of a segment near the seam
  // fall into the same cluster.
  std::vector<int> order(segments.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return segments[a].length > segments[b].length; });
  std::vector<bool> taken(segments.size(), false);
  std::vector<VerticalLine> lines;
  for (const int seed : order) {
    if (taken[seed]) continue;
    const Segment& s0 = segments[seed];
    const double seed_row = 0.5 * (s0.top + s0.bottom);
    double sum_w = 0, sum_offset = 0, sum_slope = 0;
    int top = s0.top, bottom = s0.bottom;
    for (size_t j = 0; j < segments.size(); ++j) {
      if (taken[j]) continue;
      const Segment& sj = segments[j];
      const double offset = WrapColumns(sj.column - s0.column - s0.slope * (0.5 * (sj.top + sj.bottom) - seed_row), w);
      if (std::abs(offset) > o.cluster_px) continue;
      taken[j] = true;
      sum_w += sj.length;
      sum_offset += sj.length * offset;
      sum_slope += sj.length * sj.slope;
      top = std::min(top, sj.top);
      bottom = std::max(bottom, sj.bottom);
    }
    // The line passes column `column` at row seed_row.
    const double column = s0.column + sum_offset / sum_w;
    const double slope = sum_slope / sum_w;
    // The line's support: rows with an edge pixel within one column of the line (Canny's
    // column jitter breaks HoughLinesP's segments; its pieces are counted here). The line
    // grows beyond its segments' rows along such edge pixels, over gaps up to max_gap_px.
    auto has_edge = [&](int y) {
      const long x = std::lround(column + p.pad + slope * (y - seed_row));
      const uint8_t* e = edges.ptr<uint8_t>(y) + std::clamp(x, 1L, static_cast<long>(edges.cols) - 2);
      return e[-1] || e[0] || e[1];
    };
    const int max_gap = static_cast<int>(o.max_gap_px);
    for (int y = top - 1, gap = 0; y >= 0 && gap <= max_gap; --y) {
      gap = has_edge(y) ? 0 : gap + 1;
      if (gap == 0) top = y;
    }
    for (int y = bottom + 1, gap = 0; y < p.height && gap <= max_gap; ++y) {
      gap = has_edge(y) ? 0 : gap + 1;
      if (gap == 0) bottom = y;
    }
    int covered = 0;
    for (int y = top; y <= bottom; ++y) covered += has_edge(y);
    if (covered < o.min_line_px) continue;

    VerticalLine line;
    line.top_px = top;
    line.bottom_px = bottom;
    line.length_px = covered;
    // Sub-pixel column at the centre row: parabola through the horizontal-gradient profile
    // across the line, summed along the line over its rows.
    double profile[5] = {0, 0, 0, 0, 0}, base_sum = 0;
    int n = 0;
    for (int y = static_cast<int>(line.top_px); y <= static_cast<int>(line.bottom_px); ++y, ++n) {
      const int base = static_cast<int>(std::lround(column + p.pad + slope * (y - seed_row)));
      base_sum += base;
      const int16_t* gx = p.dx.ptr<int16_t>(y);
      for (int k = -2; k <= 2; ++k) {
        const int x = std::clamp(base + k, 0, p.dx.cols - 1);
        profile[k + 2] += std::abs(gx[x]);
      }
    }
    double refined = column;
    const int peak = 1 + static_cast<int>(std::max_element(profile + 1, profile + 4) - (profile + 1));
    if (profile[peak] > 0) {
      const double pm = profile[peak - 1], p0 = profile[peak], pp = profile[peak + 1];
      const double denom = pm - 2 * p0 + pp;
      const double offset = denom < 0 ? std::clamp(0.5 * (pm - pp) / denom, -0.5, 0.5) : 0.0;
      refined = base_sum / n - p.pad + (peak - 2) + offset;
    }
    line.column_px = FoldColumn(refined, w);
    lines.push_back(line);
  }
  // One edge whose segments fell into two clusters gives two lines at (nearly) the same
  // column over the same rows: keep the longer one.
  std::stable_sort(lines.begin(), lines.end(),
                   [](const VerticalLine& a, const VerticalLine& b) { return a.length_px > b.length_px; });
  std::vector<VerticalLine> kept;
  for (const VerticalLine& line : lines) {
    const bool duplicate = std::any_of(kept.begin(), kept.end(), [&](const VerticalLine& k) {
      return std::abs(WrapColumns(line.column_px - k.column_px, w)) <= 0.5 * o.cluster_px + 1 &&
             line.top_px <= k.bottom_px && k.top_px <= line.bottom_px;
    });
    if (!duplicate) kept.push_back(line);
  }
  std::sort(kept.begin(), kept.end(),
            [](const VerticalLine& a, const VerticalLine& b) { return a.column_px < b.column_px; });
  return kept;
}

cv::Mat Describe(const Prepared& p, const std::vector<VerticalLine>& lines, const VlineOptions& o) {
  const int cells_x = o.divided ? 2 : 1, cells_y = o.divided ? 3 : 1;
  const int bins = o.bins, dims = cells_x * cells_y * bins;
  cv::Mat out(static_cast<int>(lines.size()), dims, CV_32F, cv::Scalar(0));
  if (lines.empty()) return out;

  cv::Mat fx, fy, magnitude, angle;
  p.dx.convertTo(fx, CV_32F);
  p.dy.convertTo(fy, CV_32F);
  cv::cartToPolar(fx, fy, magnitude, angle, false);  // signed orientation in [0, 2 pi]

  // Each row votes into the two nearest row cells (all into the end cell beyond the outer centres).
  struct RowVote {
    int cell0, cell1;
    float w0, w1;
  };
  std::vector<RowVote> row_votes(static_cast<size_t>(p.height));
  const double cell_h = static_cast<double>(p.height) / cells_y;
  for (int y = 0; y < p.height; ++y) {
    const double t = (y + 0.5) / cell_h - 0.5;
    const int r0 = static_cast<int>(std::floor(t));
    const float f = static_cast<float>(t - r0);
    if (r0 < 0) {
      row_votes[y] = {0, 0, 1.0f, 0.0f};
    } else if (r0 >= cells_y - 1) {
      row_votes[y] = {cells_y - 1, cells_y - 1, 1.0f, 0.0f};
    } else {
      row_votes[y] = {r0, r0 + 1, 1.0f - f, f};
    }
  }

  const float to_bin = static_cast<float>(bins / (2 * M_PI));
  const int half = o.window_px / 2;
  std::vector<int> cols(static_cast<size_t>(o.window_px));
  std::vector<float> right(static_cast<size_t>(o.window_px));
  std::vector<float> hist(static_cast<size_t>(dims));
  const float clip = static_cast<float>(1.2 / std::sqrt(static_cast<double>(dims)));
  for (size_t i = 0; i < lines.size(); ++i) {
    const double x0 = lines[i].column_px;
    const long first = std::lround(x0) - half;
    for (int k = 0; k < o.window_px; ++k) {
      cols[k] = static_cast<int>(first + k + p.pad);  // in the padded image: no wrapping needed
      // Share of the right half: a ramp one pixel wide across the line's column.
      right[k] = cells_x == 1 ? 0.0f : static_cast<float>(std::clamp(first + k - x0 + 0.5, 0.0, 1.0));
    }
    std::fill(hist.begin(), hist.end(), 0.0f);
    for (int y = 0; y < p.height; ++y) {
      const float* m = magnitude.ptr<float>(y);
      const float* a = angle.ptr<float>(y);
      const RowVote& rv = row_votes[y];
      for (int k = 0; k < o.window_px; ++k) {
        const float mag = m[cols[k]];
        if (mag == 0) continue;
        const float t = a[cols[k]] * to_bin;
        int q0 = static_cast<int>(t);
        const float f = t - q0;
        q0 %= bins;
        const int q1 = (q0 + 1) % bins;
        const float v0 = mag * (1 - f), v1 = mag * f;
        const float wr = right[k], wl = 1 - wr;
        const float cw[4] = {rv.w0 * wl, rv.w0 * wr, rv.w1 * wl, rv.w1 * wr};
        const int cell[4] = {rv.cell0 * cells_x, rv.cell0 * cells_x + cells_x - 1, rv.cell1 * cells_x,
                             rv.cell1 * cells_x + cells_x - 1};
        for (int c = 0; c < 4; ++c) {
          if (cw[c] == 0) continue;
          float* h = &hist[static_cast<size_t>(cell[c]) * bins];
          h[q0] += cw[c] * v0;
          h[q1] += cw[c] * v1;
        }
      }
    }
    // L2-Hys over the whole descriptor.
    double norm = 0;
    for (float v : hist) norm += static_cast<double>(v) * v;
    if (norm <= 0) continue;  // no gradient in the window: zero row
    norm = std::sqrt(norm);
    double norm2 = 0;
    for (float& v : hist) {
      v = std::min(static_cast<float>(v / norm), clip);
      norm2 += static_cast<double>(v) * v;
    }
    norm2 = std::sqrt(norm2);
    float* row = out.ptr<float>(static_cast<int>(i));
    for (int d = 0; d < dims; ++d) row[d] = static_cast<float>(hist[d] / norm2);
  }
  return out;
}

}  // namespace

std::vector<VerticalLine> DetectVerticalLines(const cv::Mat& gray, const VlineOptions& options) {
  return Detect(Prepare(gray, options), options);
}

cv::Mat DescribeVerticalLines(const cv::Mat& gray, const std::vector<VerticalLine>& lines,
                              const VlineOptions& options) {
  const Prepared p = Prepare(gray, options);
  for (const VerticalLine& l : lines) {
    if (!(l.column_px >= 0 && l.column_px < p.width)) {
      throw std::invalid_argument("vline: line column " + std::to_string(l.column_px) + " outside [0, " +
                                  std::to_string(p.width) + ")");
    }
  }
  return Describe(p, lines, options);
}

LandmarkSet DetectVlineLandmarks(const cv::Mat& gray, const VlineOptions& options) {
  const Prepared p = Prepare(gray, options);
  const std::vector<VerticalLine> lines = Detect(p, options);
  LandmarkSet set;
  set.method = LandmarkMethod::kVline;
  set.width_px = p.width;
  set.height_px = p.height;
  if (lines.empty()) return set;
  set.descriptors = Describe(p, lines, options);
  set.landmarks.reserve(lines.size());
  for (const VerticalLine& l : lines) {
    Landmark m;
    m.x_px = static_cast<float>(l.column_px);
    m.y_px = static_cast<float>(0.5 * (l.top_px + l.bottom_px));
    m.strength = static_cast<float>(l.length_px);
    m.scale_px = static_cast<float>(options.window_px);
    m.angle_deg = -1;
    set.landmarks.push_back(m);
  }
  return set;
}

std::vector<LineMatch> MatchVerticalLines(const LandmarkSet& home, const LandmarkSet& current,
                                          const VlineMatchOptions& options, double shift_px) {
  for (const LandmarkSet* s : {&home, &current}) {
    if (s->empty()) continue;
    if (s->descriptors.type() != CV_32F || s->descriptors.rows != s->size()) {
      throw std::invalid_argument("vline match: descriptors must be CV_32F with one row per landmark");
    }
  }
  if (home.empty() || current.empty()) return {};
  if (home.descriptors.cols != current.descriptors.cols) {
    throw std::invalid_argument("vline match: descriptor widths differ (" + std::to_string(home.descriptors.cols) +
                                " vs " + std::to_string(current.descriptors.cols) + ")");
  }
  const bool gate = options.max_x_displacement_px > 0;
  if (gate && (home.width_px != current.width_px || home.width_px <= 0)) {
    throw std::invalid_argument("vline match: the panoramas differ in width (" + std::to_string(home.width_px) +
                                " vs " + std::to_string(current.width_px) + ")");
  }
  // The generic matcher without the ratio test is exactly the thesis' rule set.
  MatchOptions generic;
  generic.ratio = 1.0;
  generic.mutual = options.mutual;
  generic.relaxed_second_best = options.relaxed_second_best;
  generic.max_x_displacement_px = gate ? options.max_x_displacement_px : 0;
  std::vector<LineMatch> matches;
  for (const auto& m : MatchLandmarks(home, current, generic, shift_px)) matches.push_back({m.home, m.current, m.distance});
  return matches;
}

}  // namespace snapnav::nav
