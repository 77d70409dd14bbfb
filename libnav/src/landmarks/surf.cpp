#include "snapnav/nav/landmarks/surf.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <string>

namespace snapnav::nav {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kDegPerRad = 180.0f / kPi;

// ---------------------------------------------------------------------------------------------
// Box filters on the integral image.

// The four integral-image offsets of a box relative to the entry of its centre pixel:
// sum = p[d] - p[b] - p[c] + p[a].
struct BoxOffsets {
  int a = 0, b = 0, c = 0, d = 0;
};
// The box of pixel columns [dx0, dx1] and rows [dy0, dy1] (inclusive, relative to the centre).
BoxOffsets MakeBox(int stride, int dx0, int dy0, int dx1, int dy1) {
  BoxOffsets o;
  o.a = dy0 * stride + dx0;
  o.b = dy0 * stride + dx1 + 1;
  o.c = (dy1 + 1) * stride + dx0;
  o.d = (dy1 + 1) * stride + dx1 + 1;
  return o;
}
inline int Sum(const uint32_t* p, const BoxOffsets& o) { return static_cast<int>(p[o.d] - p[o.b] - p[o.c] + p[o.a]); }

// The box filters of size L (odd multiple of 3) for Dxx, Dyy, Dxy, lobe l = L / 3:
//   Dyy: columns [-(l-1), l-1] by rows [-(L-1)/2, (L-1)/2], weights +1 -2 +1 over three bands
//        of l rows, computed as the whole box minus 3 times the middle band; Dxx transposed;
//   Dxy: four l x l squares with a one-pixel gap at the axes, + in the quadrants where x and y
//        have the same sign.
struct HessianFilter {
  int size = 0;
  float inv_area = 0;  // 1 / L^2
  BoxOffsets xx_all, xx_mid, yy_all, yy_mid, xy_pp, xy_mm, xy_pm, xy_mp;

  HessianFilter(int stride, int filter_size) : size(filter_size) {
    const int l = size / 3, h = size / 2, w = l - 1, m = (l - 1) / 2;
    inv_area = 1.0f / (static_cast<float>(size) * size);
    xx_all = MakeBox(stride, -h, -w, h, w);
    xx_mid = MakeBox(stride, -m, -w, m, w);
    yy_all = MakeBox(stride, -w, -h, w, h);
    yy_mid = MakeBox(stride, -w, -m, w, m);
    xy_pp = MakeBox(stride, 1, 1, l, l);
    xy_mm = MakeBox(stride, -l, -l, -1, -1);
    xy_pm = MakeBox(stride, 1, -l, l, -1);
    xy_mp = MakeBox(stride, -l, 1, -1, l);
  }
  // Area-normalised second derivatives at the pixel whose integral entry is p.
  void Derivatives(const uint32_t* p, float* dxx, float* dyy, float* dxy) const {
    *dxx = static_cast<float>(Sum(p, xx_all) - 3 * Sum(p, xx_mid)) * inv_area;
    *dyy = static_cast<float>(Sum(p, yy_all) - 3 * Sum(p, yy_mid)) * inv_area;
    *dxy = static_cast<float>(Sum(p, xy_pp) + Sum(p, xy_mm) - Sum(p, xy_pm) - Sum(p, xy_mp)) * inv_area;
  }
  float Determinant(const uint32_t* p) const {
    float dxx, dyy, dxy;
    Derivatives(p, &dxx, &dyy, &dxy);
    return dxx * dyy - 0.81f * dxy * dxy;
  }
};

// One filter size on the sample grid of an octave: sample (c, r) is pixel (c * step, r * step).
// [c0, c1] x [r0, r1] are the samples where the filter fits inside the image. The inner sizes of
// an octave are computed densely (0 where the filter does not fit); the first and the last only
// bound the non-maximum suppression and are evaluated on demand around the candidates.
struct ResponseLayer {
  ResponseLayer(const IntegralImage& ii, int filter_size, int sample_step, bool dense)
      : filter(ii.stride(), filter_size), integral(&ii), size(filter_size), step(sample_step) {
    const int width = ii.width(), height = ii.height();
    cols = (width + step - 1) / step;
    rows = (height + step - 1) / step;
    const int h = size / 2;  // the filter reaches h pixels either side of its centre
    c0 = (h + step - 1) / step;
    c1 = width - 1 - h >= 0 ? (width - 1 - h) / step : -1;
    r0 = (h + step - 1) / step;
    r1 = height - 1 - h >= 0 ? (height - 1 - h) / step : -1;
    if (!dense) return;
    det.assign(static_cast<size_t>(cols) * rows, 0.0f);
    for (int r = r0; r <= r1; ++r) {
      const uint32_t* row = ii.data() + static_cast<size_t>(r) * step * ii.stride();
      float* out = det.data() + static_cast<size_t>(r) * cols;
      if (step == 1) {  // the costly case, kept simple for the vectoriser
        for (int c = c0; c <= c1; ++c) out[c] = filter.Determinant(row + c);
      } else {
        for (int c = c0; c <= c1; ++c) out[c] = filter.Determinant(row + c * step);
      }
    }
  }
  // The response at sample (c, r), which must lie in [c0, c1] x [r0, r1].
  float at(int c, int r) const {
    if (!det.empty()) return det[static_cast<size_t>(r) * cols + c];
    return filter.Determinant(integral->data() + static_cast<size_t>(r) * step * integral->stride() + c * step);
  }

  HessianFilter filter;
  const IntegralImage* integral;
  int size, step;
  int cols = 0, rows = 0, c0 = 0, c1 = -1, r0 = 0, r1 = -1;
  std::vector<float> det;  // dense layers only
};

int FilterSize(int octave, int interval) { return 3 * ((1 << (octave + 1)) * (interval + 1) + 1); }

// The 3x3x3 neighbourhood of a sample: v[layer][dr + 1][dc + 1], layer 0 below, 1 the sample's, 2 above.
struct Cube {
  float v[3][3][3];
  float at(int layer, int dc, int dr) const { return v[layer][dr + 1][dc + 1]; }
};

// Solves the 3x3 system a x = b (Cramer's rule); false if a is (nearly) singular.
bool Solve3(const double a[3][3], const double b[3], double x[3]) {
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  const double scale = std::abs(a[0][0]) + std::abs(a[1][1]) + std::abs(a[2][2]);
  if (!(std::abs(det) > 1e-12 * scale * scale * scale)) return false;
  for (int k = 0; k < 3; ++k) {
    double m[3][3];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[i][j] = j == k ? b[i] : a[i][j];
    }
    x[k] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
            m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) /
           det;
  }
  return true;
}

// Refines the maximum at the centre of `n` by the 3D quadratic through its neighbourhood (central
// differences); returns the offset in samples and layers, false when it exceeds half a sample
// (or layer) in any direction or the fit is degenerate. The bound has a small tolerance: a
// feature midway between two samples (a tie, which the suppression gives to one of them) fits
// at an offset of 0.5 plus a little from the cross terms, and is kept.
constexpr double kMaxOffset = 0.55;
bool Interpolate(const Cube& n, double offset[3], double* value) {
  const double v = n.at(1, 0, 0);
  const double g[3] = {0.5 * (n.at(1, 1, 0) - n.at(1, -1, 0)), 0.5 * (n.at(1, 0, 1) - n.at(1, 0, -1)),
                       0.5 * (n.at(2, 0, 0) - n.at(0, 0, 0))};
  const double dxx = n.at(1, 1, 0) + n.at(1, -1, 0) - 2 * v;
  const double dyy = n.at(1, 0, 1) + n.at(1, 0, -1) - 2 * v;
  const double dss = n.at(2, 0, 0) + n.at(0, 0, 0) - 2 * v;
  const double dxy = 0.25 * (n.at(1, 1, 1) - n.at(1, -1, 1) - n.at(1, 1, -1) + n.at(1, -1, -1));
  const double dxs = 0.25 * (n.at(2, 1, 0) - n.at(2, -1, 0) - n.at(0, 1, 0) + n.at(0, -1, 0));
  const double dys = 0.25 * (n.at(2, 0, 1) - n.at(2, 0, -1) - n.at(0, 0, 1) + n.at(0, 0, -1));
  const double hessian[3][3] = {{dxx, dxy, dxs}, {dxy, dyy, dys}, {dxs, dys, dss}};
  const double minus_g[3] = {-g[0], -g[1], -g[2]};
  if (!Solve3(hessian, minus_g, offset)) return false;
  if (std::abs(offset[0]) > kMaxOffset || std::abs(offset[1]) > kMaxOffset || std::abs(offset[2]) > kMaxOffset) {
    return false;
  }
  *value = v + 0.5 * (g[0] * offset[0] + g[1] * offset[1] + g[2] * offset[2]);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Haar wavelets: right (lower) half minus left (upper) half, halves of h columns (rows) either
// side of the centre pixel, 2h + 1 long.

// Near the border: the two halves clipped to the image; their mean grey levels are compared
// and scaled to the full half area, so a border does not look like an edge. 0 when a half is
// entirely outside.
float ClippedHalfDifference(const IntegralImage& ii, cv::Rect a, cv::Rect b, int half_area) {
  const cv::Rect image(0, 0, ii.width(), ii.height());
  a &= image;
  b &= image;
  if (a.empty() || b.empty()) return 0;
  const auto mean = [&ii](const cv::Rect& r) {
    return static_cast<float>(ii.BoxSum(r.x, r.y, r.x + r.width, r.y + r.height)) / static_cast<float>(r.area());
  };
  return (mean(b) - mean(a)) * static_cast<float>(half_area);
}

// Both responses of the wavelets of half size h centred on pixel (x, y).
inline void Haar(const IntegralImage& ii, int x, int y, int h, float* dx, float* dy) {
  if (x - h >= 0 && y - h >= 0 && x + h < ii.width() && y + h < ii.height()) {
    // The 12 integral-image entries both need: rows y-h, y, y+1, y+h+1; columns x-h, x, x+1, x+h+1.
    const size_t stride = static_cast<size_t>(ii.stride());
    const uint32_t* top = ii.data() + static_cast<size_t>(y - h) * stride;
    const uint32_t* above = ii.data() + static_cast<size_t>(y) * stride;
    const uint32_t* below = above + stride;
    const uint32_t* bottom = ii.data() + static_cast<size_t>(y + h + 1) * stride;
    const int x0 = x - h, x1 = x + h + 1;
    const int right = static_cast<int>(bottom[x1] - bottom[x + 1] - top[x1] + top[x + 1]);
    const int left = static_cast<int>(bottom[x] - bottom[x0] - top[x] + top[x0]);
    const int lower = static_cast<int>(bottom[x1] - bottom[x0] - below[x1] + below[x0]);
    const int upper = static_cast<int>(above[x1] - above[x0] - top[x1] + top[x0]);
    *dx = static_cast<float>(right - left);
    *dy = static_cast<float>(lower - upper);
    return;
  }
  const int side = 2 * h + 1;
  *dx = ClippedHalfDifference(ii, {x - h, y - h, h, side}, {x + 1, y - h, h, side}, h * side);
  *dy = ClippedHalfDifference(ii, {x - h, y - h, side, h}, {x - h, y + 1, side, h}, h * side);
}

// s = 1.2 L / 9 for a keypoint of size (filter size) L.
inline float ScaleOf(float size_px) { return 1.2f * size_px / 9.0f; }

// ---------------------------------------------------------------------------------------------
// Precomputed sample patterns (in units of the keypoint scale s).

// Orientation: the grid points within radius 6 and their Gaussian weights (sigma 2).
struct OrientationSample {
  int i, j;
  float weight;
};
const std::vector<OrientationSample>& OrientationPattern() {
  static const std::vector<OrientationSample> pattern = [] {
    std::vector<OrientationSample> p;
    for (int j = -6; j <= 6; ++j) {
      for (int i = -6; i <= 6; ++i) {
        if (i * i + j * j < 36) p.push_back({i, j, std::exp(-(i * i + j * j) / (2.0f * 2.0f * 2.0f))});
      }
    }
    return p;
  }();
  return pattern;
}

// Descriptor: 20 x 20 sample positions (k - 9.5, k = 0..19) and their Gaussian weights (sigma 3.3).
struct DescriptorPattern {
  std::array<float, 20> offset;
  std::array<float, 400> weight;  // [row * 20 + column]
};
const DescriptorPattern& DescriptorSamples() {
  static const DescriptorPattern pattern = [] {
    DescriptorPattern p;
    for (int k = 0; k < 20; ++k) p.offset[k] = static_cast<float>(k) - 9.5f;
    const float two_sigma2 = 2.0f * 3.3f * 3.3f;
    for (int b = 0; b < 20; ++b) {
      for (int a = 0; a < 20; ++a) {
        p.weight[b * 20 + a] = std::exp(-(p.offset[a] * p.offset[a] + p.offset[b] * p.offset[b]) / two_sigma2);
      }
    }
    return p;
  }();
  return pattern;
}

void CheckGray(const cv::Mat& gray) {
  if (gray.empty()) throw std::invalid_argument("surf: empty image");
  if (gray.type() != CV_8UC1) {
    throw std::invalid_argument("surf: need an 8-bit single-channel image, got type " + std::to_string(gray.type()) +
                                " with " + std::to_string(gray.channels()) + " channel(s)");
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

void SurfOptions::Validate() const {
  if (!(hessian_threshold >= 0) || !std::isfinite(hessian_threshold)) {
    throw std::invalid_argument("surf: hessian_threshold must be finite and >= 0, got " +
                                std::to_string(hessian_threshold));
  }
  if (octaves < 1 || octaves > 8) {
    throw std::invalid_argument("surf: octaves must be in 1..8, got " + std::to_string(octaves));
  }
  if (intervals < 3 || intervals > 16) {
    throw std::invalid_argument(
        "surf: intervals must be in 3..16 (non-maximum suppression needs a size on each "
        "side), got " +
        std::to_string(intervals));
  }
  if (init_sample < 1 || init_sample > 16) {
    throw std::invalid_argument("surf: init_sample must be in 1..16 px, got " + std::to_string(init_sample));
  }
  if (max_keypoints < 0) {
    throw std::invalid_argument("surf: max_keypoints must be >= 0 (0: all), got " + std::to_string(max_keypoints));
  }
}

IntegralImage::IntegralImage(const cv::Mat& gray) {
  CheckGray(gray);
  width_ = gray.cols;
  height_ = gray.rows;
  stride_ = width_ + 1;
  sums_.assign(static_cast<size_t>(height_ + 1) * stride_, 0u);
  for (int y = 0; y < height_; ++y) {
    const uint8_t* in = gray.ptr<uint8_t>(y);
    const uint32_t* above = sums_.data() + static_cast<size_t>(y) * stride_;
    uint32_t* out = sums_.data() + static_cast<size_t>(y + 1) * stride_;
    uint32_t row_sum = 0;  // modulo 2^32, like the entries
    for (int x = 0; x < width_; ++x) {
      row_sum += in[x];
      out[x + 1] = above[x + 1] + row_sum;
    }
  }
}

int IntegralImage::ClippedBoxSum(int x0, int y0, int x1, int y1) const {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, width_), y1 = std::min(y1, height_);
  if (x0 >= x1 || y0 >= y1) return 0;
  return BoxSum(x0, y0, x1, y1);
}

std::vector<Landmark> FastHessian(const IntegralImage& integral, const SurfOptions& options,
                                  std::vector<int8_t>* laplacian_signs) {
  options.Validate();
  std::vector<Landmark> keypoints;
  std::vector<int8_t> signs;
  const int width = integral.width(), height = integral.height();
  if (integral.empty()) {
    if (laplacian_signs) laplacian_signs->clear();
    return keypoints;
  }
  const float threshold = static_cast<float>(options.hessian_threshold);

  for (int o = 0; o < options.octaves; ++o) {
    const int step = options.init_sample << o;
    // Stop when even the smallest filter of the octave does not fit, or the grid is too coarse.
    if (FilterSize(o, 0) > std::min(width, height) || step >= std::min(width, height)) break;
    std::vector<ResponseLayer> layers;
    layers.reserve(options.intervals);
    for (int i = 0; i < options.intervals; ++i) {
      layers.emplace_back(integral, FilterSize(o, i), step, i > 0 && i + 1 < options.intervals);
    }

    // 3x3x3 maxima of the inner layers, inside the region where the largest filter fits (so that
    // every neighbour of a candidate is a valid response of every layer).
    for (int i = 1; i + 1 < options.intervals; ++i) {
      const ResponseLayer &below = layers[i - 1], &mid = layers[i], &above = layers[i + 1];
      for (int r = above.r0 + 1; r <= above.r1 - 1; ++r) {
        const float* row = mid.det.data() + static_cast<size_t>(r) * mid.cols;
        for (int c = above.c0 + 1; c <= above.c1 - 1; ++c) {
          const float v = row[c];
          if (v <= threshold) continue;
          // First the 8 neighbours in the same layer (dense), then the 18 in the layers around it.
          // A tie goes to the later sample in (layer, row, column) order, so that a feature
          // exactly between two samples keeps one of them.
          Cube n;
          bool maximum = true;
          for (int dr = -1; dr <= 1 && maximum; ++dr) {
            for (int dc = -1; dc <= 1; ++dc) {
              const float u = row[static_cast<ptrdiff_t>(dr) * mid.cols + c + dc];
              n.v[1][dr + 1][dc + 1] = u;
              const bool after = dr > 0 || (dr == 0 && dc > 0);
              if ((dr != 0 || dc != 0) && (u > v || (after && u == v))) {
                maximum = false;
                break;
              }
            }
          }
          for (int layer = 0; layer <= 2 && maximum; layer += 2) {
            const ResponseLayer& l = layer == 0 ? below : above;
            for (int dr = -1; dr <= 1 && maximum; ++dr) {
              for (int dc = -1; dc <= 1; ++dc) {
                const float u = l.at(c + dc, r + dr);
                n.v[layer][dr + 1][dc + 1] = u;
                if (u > v || (layer == 2 && u == v)) {
                  maximum = false;
                  break;
                }
              }
            }
          }
          if (!maximum) continue;
          double offset[3], value;
          if (!Interpolate(n, offset, &value)) continue;
          Landmark kp;
          kp.x_px = static_cast<float>((c + offset[0]) * step);
          kp.y_px = static_cast<float>((r + offset[1]) * step);
          kp.scale_px = static_cast<float>(mid.size + offset[2] * (above.size - mid.size));
          kp.strength = static_cast<float>(value);
          kp.angle_deg = -1;
          keypoints.push_back(kp);
          if (laplacian_signs) {
            float dxx, dyy, dxy;
            mid.filter.Derivatives(integral.data() + static_cast<size_t>(r) * step * integral.stride() + c * step, &dxx,
                                   &dyy, &dxy);
            signs.push_back(dxx + dyy >= 0 ? 1 : -1);
          }
        }
      }
    }
  }

  // Strongest first (ties keep scan order); at most max_keypoints.
  std::vector<int> order(keypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&keypoints](int a, int b) { return keypoints[a].strength > keypoints[b].strength; });
  if (options.max_keypoints > 0 && static_cast<int>(order.size()) > options.max_keypoints) {
    order.resize(options.max_keypoints);
  }
  std::vector<Landmark> sorted;
  sorted.reserve(order.size());
  for (const int k : order) sorted.push_back(keypoints[k]);
  if (laplacian_signs) {
    laplacian_signs->clear();
    laplacian_signs->reserve(order.size());
    for (const int k : order) laplacian_signs->push_back(signs[k]);
  }
  return sorted;
}

float SurfOrientationDeg(const IntegralImage& integral, float x_px, float y_px, float scale_px) {
  const float s = ScaleOf(scale_px);
  const int h = std::max(1, cvRound(2 * s));  // wavelet side 4s

  // Weighted responses binned by their angle (1 degree bins), then a sliding 60-degree window.
  constexpr int kBins = 360, kWindow = 60;
  std::array<float, kBins> bin_x{}, bin_y{};
  for (const OrientationSample& p : OrientationPattern()) {
    float dx, dy;
    Haar(integral, cvRound(x_px + static_cast<float>(p.i) * s), cvRound(y_px + static_cast<float>(p.j) * s), h, &dx,
         &dy);
    if (dx == 0 && dy == 0) continue;
    dx *= p.weight;
    dy *= p.weight;
    const int bin = std::min(kBins - 1, static_cast<int>(cv::fastAtan2(dy, dx)));
    bin_x[bin] += dx;
    bin_y[bin] += dy;
  }
  float sum_x = 0, sum_y = 0;
  for (int b = 0; b < kWindow; ++b) sum_x += bin_x[b], sum_y += bin_y[b];
  float best_x = sum_x, best_y = sum_y, best = sum_x * sum_x + sum_y * sum_y;
  for (int start = 1; start < kBins; ++start) {
    const int in = (start + kWindow - 1) % kBins, out = start - 1;
    sum_x += bin_x[in] - bin_x[out];
    sum_y += bin_y[in] - bin_y[out];
    const float length2 = sum_x * sum_x + sum_y * sum_y;
    if (length2 > best) best = length2, best_x = sum_x, best_y = sum_y;
  }
  if (best <= 0) return 0;
  const float angle = std::atan2(best_y, best_x) * kDegPerRad;
  return angle < 0 ? angle + 360.0f : (angle >= 360.0f ? 0.0f : angle);
}

void SurfDescriptor(const IntegralImage& integral, const Landmark& keypoint, float* out) {
  const DescriptorPattern& pattern = DescriptorSamples();
  const float s = ScaleOf(keypoint.scale_px);
  const int h = std::max(1, cvRound(s));  // wavelet side 2s
  const float angle = keypoint.angle_deg < 0 ? 0.0f : keypoint.angle_deg / kDegPerRad;
  const float co = std::cos(angle), si = std::sin(angle);

  std::fill(out, out + kSurfDescriptorSize, 0.0f);
  for (int b = 0; b < 20; ++b) {
    const float v = pattern.offset[b] * s;
    for (int a = 0; a < 20; ++a) {
      const float u = pattern.offset[a] * s;
      // Sample position: (u, v) in the keypoint frame turned by the orientation, to the nearest pixel.
      float dx, dy;
      Haar(integral, cvRound(keypoint.x_px + co * u - si * v), cvRound(keypoint.y_px + si * u + co * v), h, &dx, &dy);
      // Responses in the keypoint frame, weighted.
      const float w = pattern.weight[b * 20 + a];
      const float du = (co * dx + si * dy) * w;
      const float dv = (-si * dx + co * dy) * w;
      float* cell = out + ((b / 5) * 4 + a / 5) * 4;
      cell[0] += du;
      cell[1] += dv;
      cell[2] += std::abs(du);
      cell[3] += std::abs(dv);
    }
  }
  float norm2 = 0;
  for (int k = 0; k < kSurfDescriptorSize; ++k) norm2 += out[k] * out[k];
  if (norm2 > 0) {
    const float inv = 1.0f / std::sqrt(norm2);
    for (int k = 0; k < kSurfDescriptorSize; ++k) out[k] *= inv;
  }
}

cv::Mat DescribeSurf(const IntegralImage& integral, std::vector<Landmark>* keypoints, const SurfOptions& options) {
  options.Validate();
  if (!keypoints) throw std::invalid_argument("surf: DescribeSurf needs a keypoint vector");
  if (keypoints->empty()) return cv::Mat();
  if (integral.empty()) throw std::invalid_argument("surf: DescribeSurf on an empty integral image");
  for (const Landmark& kp : *keypoints) {
    if (!(kp.scale_px > 0)) throw std::invalid_argument("surf: keypoint scale_px must be > 0");
  }
  cv::Mat descriptors(static_cast<int>(keypoints->size()), kSurfDescriptorSize, CV_32F);
  for (size_t k = 0; k < keypoints->size(); ++k) {
    Landmark& kp = (*keypoints)[k];
    kp.angle_deg = options.upright ? -1.0f : SurfOrientationDeg(integral, kp.x_px, kp.y_px, kp.scale_px);
    SurfDescriptor(integral, kp, descriptors.ptr<float>(static_cast<int>(k)));
  }
  return descriptors;
}

cv::Mat DescribeSurf(const cv::Mat& gray, std::vector<Landmark>* keypoints, const SurfOptions& options) {
  return DescribeSurf(IntegralImage(gray), keypoints, options);
}

LandmarkSet DetectSurf(const cv::Mat& gray, const SurfOptions& options, std::vector<int8_t>* laplacian_signs) {
  CheckGray(gray);
  options.Validate();
  const IntegralImage integral(gray);
  LandmarkSet set;
  set.method = LandmarkMethod::kSurf;
  set.width_px = gray.cols;
  set.height_px = gray.rows;
  set.landmarks = FastHessian(integral, options, laplacian_signs);
  set.descriptors = DescribeSurf(integral, &set.landmarks, options);
  return set;
}

}  // namespace snapnav::nav
