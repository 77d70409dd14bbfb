#include "snapnav/nav/homing/mirror_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "snapnav/nav/homing/image_mask.hpp"

namespace snapnav::nav {
namespace {

constexpr int kSectors = 180;  // 2 degree sectors for the coverage

struct EdgePoint {
  float x, y;    // pixel position (sub-pixel after refinement)
  float ux, uy;  // unit gradient direction
};

struct Edges {
  std::vector<EdgePoint> points;
  cv::Mat magnitude;  // CV_32F gradient magnitude of the blurred image
};

cv::Mat ToGray(const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U) throw std::invalid_argument("mirror calibration: need an 8-bit image");
  if (image.channels() == 1) return image;
  cv::Mat gray;
  cv::cvtColor(image, gray, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

double Percentile(const cv::Mat& values, double q) {
  std::vector<float> v;
  v.reserve(values.total() / 4 + 1);
  // A sample is enough for a threshold (every 4th pixel of every 2nd row).
  for (int y = 0; y < values.rows; y += 2) {
    const float* p = values.ptr<float>(y);
    for (int x = 0; x < values.cols; x += 4) v.push_back(p[x]);
  }
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// Canny edges with the gradient directions; thresholds from the image's own gradient distribution
// (no fixed grey levels: a dark or a bright housing, a dim or a bright scene).
Edges FindEdges(const cv::Mat& gray, double blur_sigma) {
  cv::Mat blurred;
  if (blur_sigma > 0)
    cv::GaussianBlur(gray, blurred, {0, 0}, blur_sigma);
  else
    blurred = gray;
  cv::Mat dx, dy;
  cv::Sobel(blurred, dx, CV_16S, 1, 0, 3, 1, 0, cv::BORDER_REPLICATE);
  cv::Sobel(blurred, dy, CV_16S, 0, 1, 3, 1, 0, cv::BORDER_REPLICATE);
  cv::Mat fx, fy;
  dx.convertTo(fx, CV_32F);
  dy.convertTo(fy, CV_32F);
  Edges e;
  cv::magnitude(fx, fy, e.magnitude);
  const double high = std::max(24.0, Percentile(e.magnitude, 0.85));
  cv::Mat canny;
  cv::Canny(dx, dy, canny, high / 2.5, high, true);
  for (int y = 1; y < gray.rows - 1; ++y) {
    const uint8_t* c = canny.ptr<uint8_t>(y);
    const float* gx = fx.ptr<float>(y);
    const float* gy = fy.ptr<float>(y);
    for (int x = 1; x < gray.cols - 1; ++x) {
      if (!c[x]) continue;
      const float m = std::hypot(gx[x], gy[x]);
      if (m <= 0) continue;
      e.points.push_back({static_cast<float>(x), static_cast<float>(y), gx[x] / m, gy[x] / m});
    }
  }
  return e;
}

float Bilinear(const cv::Mat& m, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= m.cols || y0 + 1 >= m.rows) return 0.f;
  const double fx = x - x0, fy = y - y0;
  const float* r0 = m.ptr<float>(y0);
  const float* r1 = m.ptr<float>(y0 + 1);
  return static_cast<float>((r0[x0] * (1 - fx) + r0[x0 + 1] * fx) * (1 - fy) +
                            (r1[x0] * (1 - fx) + r1[x0 + 1] * fx) * fy);
}

// Mean gradient magnitude over an annulus [r0, r1] about (cx, cy), inside the image.
double AnnulusTexture(const cv::Mat& magnitude, double cx, double cy, double r0, double r1) {
  double sum = 0;
  int n = 0;
  const int steps = 360;
  for (double r = std::max(0.0, r0); r <= r1; r += 1.0) {
    for (int k = 0; k < steps; ++k) {
      const double a = 2 * M_PI * k / steps;
      const double x = cx + r * std::cos(a), y = cy + r * std::sin(a);
      if (x < 1 || y < 1 || x >= magnitude.cols - 2 || y >= magnitude.rows - 2) continue;
      sum += Bilinear(magnitude, x, y);
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
}

// How much the grey level varies along circles about (cx, cy) between r0 and r1 (the median
// over the radii of the 90th minus the 10th percentile along each circle, on a blurred CV_32F
// image): a flat band (the camera's reflection, whatever its noise) varies little, the scene much.
// Along circles only: a radial change (vignetting, the blur of a nearby edge) does not count.
double AnnulusSpread(const cv::Mat& blurred, double cx, double cy, double r0, double r1) {
  std::vector<float> spreads, v;
  for (double r = std::max(1.0, r0); r <= r1; r += 1.0) {
    v.clear();
    for (int k = 0; k < 720; ++k) {
      const double a = 2 * M_PI * k / 720;
      const double x = cx + r * std::cos(a), y = cy + r * std::sin(a);
      if (x < 1 || y < 1 || x >= blurred.cols - 2 || y >= blurred.rows - 2) continue;
      v.push_back(Bilinear(blurred, x, y));
    }
    if (v.size() < 36) continue;
    const size_t lo = v.size() / 10, hi = v.size() - 1 - v.size() / 10;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(lo), v.end());
    const float p10 = v[lo];
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(hi), v.end());
    spreads.push_back(v[hi] - p10);
  }
  if (spreads.empty()) return 0;
  std::nth_element(spreads.begin(), spreads.begin() + static_cast<std::ptrdiff_t>(spreads.size() / 2), spreads.end());
  return spreads[spreads.size() / 2];
}

// Share of the circle's 2-degree sectors that lie inside the image.
std::vector<bool> VisibleSectors(double cx, double cy, double r, cv::Size size) {
  std::vector<bool> visible(kSectors);
  for (int k = 0; k < kSectors; ++k) {
    const double a = 2 * M_PI * (k + 0.5) / kSectors;
    const double x = cx + r * std::cos(a), y = cy + r * std::sin(a);
    visible[k] = x >= 0 && y >= 0 && x <= size.width - 1 && y <= size.height - 1;
  }
  return visible;
}

// Edge points a sector of a circle of radius r must hold to count as seen: a third of its arc
// length (a circle's edge has about one point per pixel of arc; a few crossings of straight
// edges, as a grid's, do not fill a sector).
int PointsPerSector(double r) { return std::max(1, static_cast<int>(std::lround(0.33 * 2 * M_PI * r / kSectors))); }

int SectorOf(double dx, double dy) {
  double a = std::atan2(dy, dx);
  if (a < 0) a += 2 * M_PI;
  return std::min(kSectors - 1, static_cast<int>(a / (2 * M_PI) * kSectors));
}

bool Radial(const EdgePoint& p, double cx, double cy, double cos_min, double* d) {
  const double dx = p.x - cx, dy = p.y - cy;
  *d = std::hypot(dx, dy);
  if (*d < 1e-9) return false;
  return std::abs((dx * p.ux + dy * p.uy) / *d) >= cos_min;
}

// Gauss-Newton on the geometric distance | |p - c| - r |.
void FitCircle(const std::vector<EdgePoint>& pts, double* cx, double* cy, double* r) {
  if (pts.size() < 3) return;
  for (int it = 0; it < 10; ++it) {
    double jtj[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, jtr[3] = {0, 0, 0};
    for (const auto& p : pts) {
      const double dx = p.x - *cx, dy = p.y - *cy, d = std::hypot(dx, dy);
      if (d < 1e-9) continue;
      const double res = d - *r;
      const double j[3] = {-dx / d, -dy / d, -1.0};
      for (int a = 0; a < 3; ++a) {
        jtr[a] += j[a] * res;
        for (int b = 0; b < 3; ++b) jtj[a][b] += j[a] * j[b];
      }
    }
    cv::Matx33d A(jtj[0][0], jtj[0][1], jtj[0][2], jtj[1][0], jtj[1][1], jtj[1][2], jtj[2][0], jtj[2][1], jtj[2][2]);
    cv::Vec3d b(-jtr[0], -jtr[1], -jtr[2]), step;
    if (!cv::solve(A, b, step, cv::DECOMP_CHOLESKY)) break;
    *cx += step[0];
    *cy += step[1];
    *r += step[2];
    if (std::abs(step[0]) + std::abs(step[1]) + std::abs(step[2]) < 1e-4) break;
  }
}

// Moves each edge point along its radial direction to the peak of the gradient magnitude
// (parabola through three samples): sub-pixel edges.
EdgePoint Subpixel(const EdgePoint& p, double cx, double cy, const cv::Mat& magnitude) {
  const double dx = p.x - cx, dy = p.y - cy, d = std::hypot(dx, dy);
  if (d < 1e-9) return p;
  const double ux = dx / d, uy = dy / d;
  const double m0 = Bilinear(magnitude, p.x - ux, p.y - uy), m1 = Bilinear(magnitude, p.x, p.y),
               m2 = Bilinear(magnitude, p.x + ux, p.y + uy);
  const double denom = m0 - 2 * m1 + m2;
  if (!(denom < 0)) return p;
  const double t = std::clamp(0.5 * (m0 - m2) / denom, -0.75, 0.75);
  EdgePoint q = p;
  q.x = static_cast<float>(p.x + t * ux);
  q.y = static_cast<float>(p.y + t * uy);
  return q;
}

// Refines a circle on the edge points that are radial about it and close to it, shrinking the
// tolerance; fills the fit's statistics. `fixed_centre`: only the radius moves.
CircleFit RefineCircle(const std::vector<EdgePoint>& points, const cv::Mat& magnitude, cv::Size size, double cx,
                       double cy, double r, double start_tolerance, double radial_cos) {
  std::vector<double> tolerances{start_tolerance, std::max(3.0, start_tolerance / 2), 2.0, 1.5};
  std::vector<EdgePoint> inliers;
  double rms = 0;
  for (size_t k = 0; k < tolerances.size() + 2; ++k) {
    const double tol = k < tolerances.size() ? tolerances[k] : std::max(1.0, 2.5 * rms);
    inliers.clear();
    for (const auto& p : points) {
      double d;
      if (!Radial(p, cx, cy, radial_cos, &d) || std::abs(d - r) > tol + 1.0) continue;
      const EdgePoint q = Subpixel(p, cx, cy, magnitude);
      const double dq = std::hypot(q.x - cx, q.y - cy);
      if (std::abs(dq - r) <= tol) inliers.push_back(q);
    }
    if (inliers.size() < 8) break;
    FitCircle(inliers, &cx, &cy, &r);
    double s = 0;
    for (const auto& p : inliers) {
      const double e = std::hypot(p.x - cx, p.y - cy) - r;
      s += e * e;
    }
    rms = std::sqrt(s / inliers.size());
  }
  CircleFit f;
  f.center_x_px = cx;
  f.center_y_px = cy;
  f.radius_px = r;
  // Final statistics with the final tolerance.
  const double tol = std::max(1.0, 2.5 * rms);
  int near = 0;
  std::vector<int> hit(kSectors, 0);
  double s = 0;
  int n = 0;
  for (const auto& p : points) {
    const double d0 = std::hypot(p.x - cx, p.y - cy);
    if (std::abs(d0 - r) > 4 * tol + 1) continue;
    ++near;
    double d;
    if (!Radial(p, cx, cy, radial_cos, &d)) continue;
    const EdgePoint q = Subpixel(p, cx, cy, magnitude);
    const double e = std::hypot(q.x - cx, q.y - cy) - r;
    if (std::abs(e) > tol) continue;
    s += e * e;
    ++n;
    ++hit[SectorOf(q.x - cx, q.y - cy)];
  }
  const auto visible = VisibleSectors(cx, cy, r, size);
  const int need = PointsPerSector(r);
  int vis = 0, cov = 0;
  for (int k = 0; k < kSectors; ++k) {
    vis += visible[k];
    cov += visible[k] && hit[k] >= need;
  }
  f.inliers = n;
  f.rms_px = n > 0 ? std::sqrt(s / n) : 0;
  f.inlier_fraction = near > 0 ? static_cast<double>(n) / near : 0;
  f.coverage = vis > 0 ? static_cast<double>(cov) / vis : 0;
  return f;
}

struct Candidate {
  double cx, cy, r;
  int support = 0;
  double coverage = 0;
  double texture_ratio = 0;
};

std::string Fixed(double v, int digits = 1) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

// The coverage of the circles about (cx, cy) of radii r0 + b * bin, b = 0 .. n - 1: the share of the
// 2-degree sectors holding enough edge points (PointsPerSector) within +-1.5 px of the circle whose
// gradient is radial; edge points between r_min and r_max only; of the sectors inside an image of
// `size` when one is given, of all of them otherwise. The 3 bins at each end stay 0.
std::vector<double> ConcentricCoverage(const std::vector<EdgePoint>& points, double cx, double cy, double r0, int n,
                                       double bin, double r_min, double r_max, double radial_cos,
                                       cv::Size size = {}) {
  std::vector<std::vector<uint16_t>> sec(static_cast<size_t>(std::max(0, n)), std::vector<uint16_t>(kSectors, 0));
  for (const auto& p : points) {
    double d;
    if (!Radial(p, cx, cy, radial_cos, &d) || d < r_min || d > r_max) continue;
    const long b = std::lround((d - r0) / bin);
    if (b >= 0 && b < n) ++sec[static_cast<size_t>(b)][SectorOf(p.x - cx, p.y - cy)];
  }
  std::vector<double> coverage(static_cast<size_t>(std::max(0, n)), 0.0);
  for (int b = 3; b + 3 < n; ++b) {
    const double r = r0 + b * bin;
    const int need = PointsPerSector(r);
    std::vector<bool> visible(kSectors, true);
    if (!size.empty()) visible = VisibleSectors(cx, cy, r, size);
    int vis = 0, cov = 0;
    for (int k = 0; k < kSectors; ++k) {
      int count = 0;
      for (int j = -3; j <= 3; ++j) count += sec[static_cast<size_t>(b + j)][k];  // +-1.5 px
      vis += visible[k];
      cov += visible[k] && count >= need;
    }
    coverage[static_cast<size_t>(b)] = vis > 0 ? static_cast<double>(cov) / vis : 0.0;
  }
  return coverage;
}

// 4b. A mirror held in a ring: the strongest circle may be the ring's outer edge, with a flat band
// (the ring, no scene in it) between it and the mirror's own edge. The mirror shows the scene right up
// to its edge; where the band just inside `rim` is flat against the scene's own variation (along
// circles, at 0.75-0.9 of the radius), the mirror's edge is the outermost concentric edge circle
// within holder_max_frac of the radius inside it that has a varied scene inside and only a flat band
// between it and `rim`. nullopt: `rim` is the mirror's edge (or no such circle).
std::optional<CircleFit> MirrorEdgeInsideHolder(const Edges& fe, const cv::Mat& smooth, cv::Size size,
                                                const CircleFit& rim, const MirrorSearchOptions& o) {
  const double R0 = rim.radius_px, cx = rim.center_x_px, cy = rim.center_y_px;
  const double band = std::max(4.0, 0.03 * R0);
  const double noise = 4.0;  // grey levels of spread that any band shows (noise, JPEG)
  const double outside = AnnulusSpread(smooth, cx, cy, R0 + 2.5, R0 + 2.5 + band);
  const double inside = AnnulusSpread(smooth, cx, cy, R0 - 2.5 - band, R0 - 2.5);
  const double scene_ref = AnnulusSpread(smooth, cx, cy, 0.75 * R0, 0.9 * R0);
  const auto flat = [&](double spread) { return spread + noise < 0.3 * (scene_ref + noise); };
  if (!flat(inside)) return std::nullopt;
  // The coverage of the concentric circles inside (0.5 px bins), as for the camera's reflection.
  const double bin_r = 0.5, lo = (1 - o.holder_max_frac) * R0, hi = R0 - 3;
  const int nb = std::max(0, static_cast<int>((hi - lo) / bin_r) + 1);
  const std::vector<double> coverage =
      ConcentricCoverage(fe.points, cx, cy, lo, nb, bin_r, lo, hi + 1.5, o.radial_cos, size);
  for (int b = nb - 4; b >= 3; --b) {  // the outermost first
    const double c = coverage[static_cast<size_t>(b)];
    if (c < o.min_rim_coverage || c < coverage[static_cast<size_t>(b - 1)] || c < coverage[static_cast<size_t>(b + 1)])
      continue;
    const double r = lo + b * bin_r;
    const double ring = r + 5 < R0 - 2.5 ? AnnulusSpread(smooth, cx, cy, r + 2.5, R0 - 2.5) : outside;
    const double scene = AnnulusSpread(smooth, cx, cy, r - 2.5 - band, r - 2.5);
    if (!(flat(ring) && scene + noise >= 2 * (ring + noise) && scene + noise >= 0.5 * (scene_ref + noise))) continue;
    const CircleFit f = RefineCircle(fe.points, fe.magnitude, size, cx, cy, r, 3.0, o.radial_cos);
    if (f.inliers < 12 || f.coverage < o.min_rim_coverage || std::hypot(f.center_x_px - cx, f.center_y_px - cy) > 0.02 * R0 ||
        f.radius_px >= R0)
      continue;
    return f;
  }
  return std::nullopt;
}

// 4c. A camera tilted against the mirror's axis sees the rim as an ellipse, which the [mirror] model
// (a circle) cannot hold. The ellipse (cv::fitEllipseAMS, refitted on its inliers) of the edge points
// near `rim`, where it has axes at least ellipse_min_ratio apart and explains at least 1.2 times as
// many of them as the circle. Only reported: fitted to the parts of the rim that are seen, its centre
// lies worse than the circle's.
std::optional<cv::RotatedRect> RimEllipse(const Edges& fe, const CircleFit& rim, const MirrorSearchOptions& o) {
  const double R0 = rim.radius_px, cx = rim.center_x_px, cy = rim.center_y_px;
  const double band = std::max(4.0, 0.04 * R0);
  std::vector<cv::Point2f> near;
  for (const auto& p : fe.points) {
    double d;
    if (!Radial(p, cx, cy, o.radial_cos, &d) || std::abs(d - R0) > band) continue;
    const EdgePoint q = Subpixel(p, cx, cy, fe.magnitude);
    near.emplace_back(q.x, q.y);
  }
  // A point's distance from an ellipse (from its normalised radius, in pixels).
  const auto off = [](const cv::RotatedRect& e, const cv::Point2f& p) {
    const double a = 0.5 * e.size.width, b = 0.5 * e.size.height, t = e.angle * M_PI / 180;
    const double dx = p.x - e.center.x, dy = p.y - e.center.y;
    const double u = std::cos(t) * dx + std::sin(t) * dy, v = -std::sin(t) * dx + std::cos(t) * dy;
    const double rho = std::hypot(u / a, v / b), r = std::hypot(u, v);
    return rho > 1e-9 ? std::abs(r - r / rho) : r;
  };
  std::vector<cv::Point2f> inliers = near;
  std::optional<cv::RotatedRect> ellipse;
  for (int it = 0; it < 4 && inliers.size() >= 20; ++it) {
    const cv::RotatedRect e = cv::fitEllipseAMS(inliers);
    if (!(e.size.width > 0 && e.size.height > 0)) break;
    ellipse = e;
    const double tol = it == 0 ? 4.0 : 2.0;
    inliers.clear();
    for (const auto& p : near) {
      if (off(e, p) <= tol) inliers.push_back(p);
    }
  }
  if (!ellipse || inliers.size() < 20) return std::nullopt;
  const double a = 0.5 * std::max(ellipse->size.width, ellipse->size.height),
               b = 0.5 * std::min(ellipse->size.width, ellipse->size.height);
  int circle_inliers = 0;
  for (const auto& p : near) circle_inliers += std::abs(std::hypot(p.x - cx, p.y - cy) - R0) <= 2.0;
  if (a / b < o.ellipse_min_ratio || static_cast<double>(inliers.size()) < 1.2 * circle_inliers ||
      std::abs(0.5 * (a + b) - R0) >= 0.05 * R0)
    return std::nullopt;
  return ellipse;
}

}  // namespace

void MirrorSearchOptions::Validate() const {
  if (!(min_radius_frac > 0 && max_radius_frac > min_radius_frac && max_radius_frac <= 1.5)) {
    throw std::invalid_argument("mirror search: need 0 < min_radius_frac < max_radius_frac <= 1.5");
  }
  if (search_max_side_px < 128) throw std::invalid_argument("mirror search: search_max_side_px must be >= 128");
  if (!(blur_sigma_px >= 0) || !(radial_cos > 0 && radial_cos < 1)) {
    throw std::invalid_argument("mirror search: need blur_sigma_px >= 0 and 0 < radial_cos < 1");
  }
  if (max_edge_points < 100 || centre_candidates < 1)
    throw std::invalid_argument("mirror search: too few edge points or candidates");
  if (!(inner_min_frac > 0 && inner_max_frac > inner_min_frac && inner_max_frac < 1)) {
    throw std::invalid_argument("mirror search: need 0 < inner_min_frac < inner_max_frac < 1");
  }
  if (!(inner_default_frac >= 0 && inner_default_frac < 1))
    throw std::invalid_argument("mirror search: inner_default_frac in [0, 1)");
  if (!(ellipse_min_ratio >= 1)) throw std::invalid_argument("mirror search: ellipse_min_ratio >= 1 (1: off)");
  if (!(holder_max_frac >= 0 && holder_max_frac < 0.5))
    throw std::invalid_argument("mirror search: holder_max_frac in [0, 0.5)");
}

std::optional<MirrorCalibration> CalibrateMirror(const cv::Mat& image, const MirrorProfile& profile,
                                                 const MirrorSearchOptions& o, std::string* why_not) {
  o.Validate();
  profile.Validate();
  auto fail = [&](const std::string& why) -> std::optional<MirrorCalibration> {
    if (why_not) *why_not = why;
    return std::nullopt;
  };
  if (image.empty()) return fail("the image is empty");
  if (image.cols < 32 || image.rows < 32)
    return fail("the image is too small (" + std::to_string(image.cols) + "x" + std::to_string(image.rows) + ")");
  const cv::Mat gray = ToGray(image);

  // 1. The search, on the image scaled down.
  const double scale = std::min(1.0, static_cast<double>(o.search_max_side_px) / std::max(gray.cols, gray.rows));
  cv::Mat small;
  if (scale < 1.0)
    cv::resize(gray, small, cv::Size(), scale, scale, cv::INTER_AREA);
  else
    small = gray;
  Edges se = FindEdges(small, std::max(0.8, o.blur_sigma_px * scale));
  if (se.points.size() < 50)
    return fail("no edges in the image (" + std::to_string(se.points.size()) + " edge points): is it blank?");
  std::mt19937_64 rng(1);
  if (static_cast<int>(se.points.size()) > o.max_edge_points) {
    std::shuffle(se.points.begin(), se.points.end(), rng);
    se.points.resize(static_cast<size_t>(o.max_edge_points));
  }
  const double side = std::min(small.cols, small.rows);
  const double rmin = o.min_radius_frac * side, rmax = o.max_radius_frac * side;
  // Hough accumulator of centres (2 px bins): each edge point votes along its gradient line.
  const int bin = 2;
  const int aw = small.cols / bin + 1, ah = small.rows / bin + 1;
  cv::Mat acc(ah, aw, CV_32F, cv::Scalar(0));
  // The camera's reflection and the rim share the centre: votes from smaller radii count too.
  const double vote_min = std::max(4.0, o.inner_min_frac * rmin);
  for (const auto& p : se.points) {
    for (int sign = -1; sign <= 1; sign += 2) {
      int last = -1;
      for (double t = vote_min; t <= rmax; t += 1.0) {
        const int ax = static_cast<int>((p.x + sign * t * p.ux) / bin),
                  ay = static_cast<int>((p.y + sign * t * p.uy) / bin);
        if (ax < 0 || ay < 0 || ax >= aw || ay >= ah) break;
        const int idx = ay * aw + ax;
        if (idx == last) continue;
        acc.at<float>(ay, ax) += 1.f;
        last = idx;
      }
    }
  }
  cv::GaussianBlur(acc, acc, {0, 0}, 1.0);
  std::vector<cv::Point> peaks;
  cv::Mat work = acc.clone();
  for (int k = 0; k < o.centre_candidates; ++k) {
    double mx;
    cv::Point at;
    cv::minMaxLoc(work, nullptr, &mx, nullptr, &at);
    if (mx <= 0) break;
    peaks.push_back(at);
    cv::circle(work, at, std::max(3, static_cast<int>(0.05 * side / bin)), cv::Scalar(0), cv::FILLED);
  }
  // 2. Radius candidates about each centre.
  std::vector<Candidate> candidates;
  const int nbins = static_cast<int>(rmax) + 3;
  for (const cv::Point& pk : peaks) {
    // The peak's centre, refined by the accumulator's weighted mean around it.
    double sx = 0, sy = 0, sw = 0;
    for (int y = std::max(0, pk.y - 2); y <= std::min(ah - 1, pk.y + 2); ++y) {
      for (int x = std::max(0, pk.x - 2); x <= std::min(aw - 1, pk.x + 2); ++x) {
        const double w = acc.at<float>(y, x);
        sx += w * (x + 0.5) * bin;
        sy += w * (y + 0.5) * bin;
        sw += w;
      }
    }
    const double cx = sw > 0 ? sx / sw : (pk.x + 0.5) * bin, cy = sw > 0 ? sy / sw : (pk.y + 0.5) * bin;
    std::vector<int> count(static_cast<size_t>(nbins), 0);
    std::vector<std::vector<uint16_t>> sectors(static_cast<size_t>(nbins), std::vector<uint16_t>(kSectors, 0));
    for (const auto& p : se.points) {
      double d;
      if (!Radial(p, cx, cy, o.radial_cos, &d)) continue;
      const int b = static_cast<int>(std::lround(d));
      if (b < 0 || b >= nbins) continue;
      ++count[b];
      ++sectors[b][SectorOf(p.x - cx, p.y - cy)];
    }
    for (int b = static_cast<int>(std::ceil(rmin)); b < nbins - 2 && b <= rmax; ++b) {
      const int s = count[b - 1] + count[b] + count[b + 1];
      const int prev = count[b - 2] + count[b - 1] + count[b], next = count[b] + count[b + 1] + count[b + 2];
      if (s < 12 || s < prev || s < next) continue;  // local maxima of the (3-bin) support
      const auto visible = VisibleSectors(cx, cy, b, small.size());
      const int need = PointsPerSector(b);
      int vis = 0, cov = 0;
      for (int k = 0; k < kSectors; ++k) {
        vis += visible[k];
        cov += visible[k] && sectors[b - 1][k] + sectors[b][k] + sectors[b + 1][k] >= need;
      }
      if (vis < kSectors / 4) continue;  // less than a quarter of the circle inside the image
      Candidate c{cx, cy, static_cast<double>(b), s, static_cast<double>(cov) / vis, 0};
      const double band = std::max(3.0, 0.03 * b);
      const double in = AnnulusTexture(se.magnitude, cx, cy, b - 3 * band, b - band);
      const double out = AnnulusTexture(se.magnitude, cx, cy, b + band, b + 3 * band);
      c.texture_ratio = in / std::max(1e-6, out);
      candidates.push_back(c);
    }
  }
  if (candidates.empty())
    return fail("no circle found: no edge circle of radius " + Fixed(rmin / scale, 0) + ".." + Fixed(rmax / scale, 0) +
                " px");
  // 3. The rim: the best-supported circle that covers enough of its circumference, textured inside.
  const Candidate* best = nullptr;
  const Candidate* best_any = nullptr;
  // Without the texture's support (the inside no more varied than the outside) a circle must be
  // seen over half of its circumference at least.
  const double untextured_coverage = std::max(0.5, o.min_rim_coverage);
  for (const auto& c : candidates) {
    if (c.coverage < o.min_rim_coverage) continue;
    if (c.coverage >= untextured_coverage && (!best_any || c.support > best_any->support)) best_any = &c;
    if (c.texture_ratio > 1.0 && (!best || c.support > best->support)) best = &c;
  }
  MirrorCalibration cal;
  if (!best) {
    if (!best_any) {
      double cov = 0;
      for (const auto& c : candidates) cov = std::max(cov, c.coverage);
      return fail("no circle found: the best edge circle covers " + Fixed(100 * cov, 0) +
                  " % of its circumference (at least " + Fixed(100 * o.min_rim_coverage, 0) + " % needed, " +
                  Fixed(100 * untextured_coverage, 0) + " % when its inside is not more textured than its outside)");
    }
    best = best_any;
    cal.warnings.push_back("the rim found is not more textured inside than outside: check the overlay");
  }
  // 4. Refinement at full size.
  Edges fe = scale < 1.0 ? FindEdges(gray, o.blur_sigma_px) : std::move(se);
  const double cx0 = best->cx / scale, cy0 = best->cy / scale, r0 = best->r / scale;
  cal.rim = RefineCircle(fe.points, fe.magnitude, gray.size(), cx0, cy0, r0, std::max(4.0, 3.0 / scale), o.radial_cos);
  const CircleFit& rim = cal.rim;
  if (rim.inliers < 12 || !(rim.radius_px > 0))
    return fail("no circle found: the rim's refinement kept " + std::to_string(rim.inliers) + " edge points");
  if (rim.coverage < o.min_rim_coverage) {
    return fail("no circle found: the refined rim covers " + Fixed(100 * rim.coverage, 0) +
                " % of its circumference (at least " + Fixed(100 * o.min_rim_coverage, 0) + " % needed)");
  }
  // The grey levels, smoothed, for how much they vary along circles (AnnulusSpread).
  cv::Mat smooth;
  const double smooth_radius = rim.radius_px;
  gray.convertTo(smooth, CV_32F);
  cv::GaussianBlur(smooth, smooth, {0, 0}, std::max(2.0, 0.008 * smooth_radius));
  // 4b. A mirror held in a ring (below).
  if (o.holder_max_frac > 0) {
    const double R0 = rim.radius_px;
    if (const auto edge = MirrorEdgeInsideHolder(fe, smooth, gray.size(), rim, o)) {
      cal.warnings.push_back("the strongest circle (radius " + Fixed(R0, 1) + " px) has a flat ring of " +
                             Fixed(R0 - edge->radius_px, 1) +
                             " px inside it (the mirror's holder?): the rim is the mirror's edge inside that ring; "
                             "check the overlay");
      cal.holder = cal.rim;
      cal.rim = *edge;
    }
  }
  // 4c. A tilted camera (below): reported; the circle stays.
  if (o.ellipse_min_ratio > 1) {
    if (const auto e = RimEllipse(fe, rim, o)) {
      const double a = 0.5 * std::max(e->size.width, e->size.height), b = 0.5 * std::min(e->size.width, e->size.height);
      cal.warnings.push_back("the rim is an ellipse (axes " + Fixed(2 * a, 1) + " and " + Fixed(2 * b, 1) +
                             " px): the camera looks at the mirror tilted by about " +
                             Fixed(std::acos(b / a) * 180 / M_PI, 0) +
                             " deg; the [mirror] model is a circle: align the camera with the mirror's axis for an "
                             "exact unwrap");
    }
  }
  // 5. The camera's reflection: the concentric circle seen in the most directions.
  const double R = rim.radius_px;
  const double bin_in = 0.5;
  const int nin = static_cast<int>(o.inner_max_frac * R / bin_in) + 4;
  const std::vector<double> coverage = ConcentricCoverage(fe.points, rim.center_x_px, rim.center_y_px, 0, nin, bin_in,
                                                          o.inner_min_frac * R, o.inner_max_frac * R, o.radial_cos);
  // Candidates: the peaks of the coverage seen in enough directions. The reflection's edge has
  // the flat reflection inside and the scene outside: the largest ratio of the grey-level spread
  // outside to inside. A lens barrel's ring is flat on both sides, a circle of the scene (a room's
  // floor line seen from its centre) varied on both. When no candidate has a clearly flat inside
  // (a plain floor around the reflection), the outermost well-seen circle.
  if (R != smooth_radius) {
    gray.convertTo(smooth, CV_32F);
    cv::GaussianBlur(smooth, smooth, {0, 0}, std::max(2.0, 0.008 * R));
  }
  struct InnerCandidate {
    int bin;
    double coverage, ratio;
  };
  std::vector<InnerCandidate> inner_candidates;
  double max_coverage = 0;
  for (int b = 4; b < nin - 4; ++b) {
    if (coverage[b] < o.inner_min_coverage || coverage[b] < coverage[b - 1] || coverage[b] < coverage[b + 1]) continue;
    if (coverage[b] == coverage[b - 1]) continue;  // a plateau counts once, at its inner end
    const double r = b * bin_in;
    const double band = std::max(4.0, 0.06 * r);
    const double in = AnnulusSpread(smooth, rim.center_x_px, rim.center_y_px, r - 2.5 - band, r - 2.5);
    const double out = AnnulusSpread(smooth, rim.center_x_px, rim.center_y_px, r + 2.5, r + 2.5 + band);
    inner_candidates.push_back({b, coverage[b], (out + 4.0) / (in + 4.0)});  // + noise-level grey levels
    max_coverage = std::max(max_coverage, coverage[b]);
  }
  int best_bin = -1;
  double best_ratio = 0, best_score = 0;
  for (const auto& c : inner_candidates) {
    // Flat inside, varied outside, and seen all round (a partial circle of the scene may be varied
    // outside too, not all round).
    const double score = c.ratio * c.coverage * c.coverage;
    if (score > best_score) {
      best_score = score;
      best_ratio = c.ratio;
      best_bin = c.bin;
    }
  }
  bool ambiguous = false;
  if (best_ratio < 2.0) {
    best_bin = -1;
    for (const auto& c : inner_candidates) {
      if (c.coverage >= 0.95 * max_coverage) best_bin = c.bin;  // the outermost of the best seen
    }
    ambiguous = best_bin >= 0 && inner_candidates.size() > 1;
  }
  double inner_radius = o.inner_default_frac * R;
  if (best_bin >= 0) {
    CircleFit in = RefineCircle(fe.points, fe.magnitude, gray.size(), rim.center_x_px, rim.center_y_px,
                                best_bin * bin_in, 3.0, o.radial_cos);
    const double offset = std::hypot(in.center_x_px - rim.center_x_px, in.center_y_px - rim.center_y_px);
    if (in.inliers >= 12 && in.radius_px > 0 && offset < 0.2 * R) {
      cal.inner = in;
      inner_radius = std::min(0.95 * R, in.radius_px + offset + o.inner_margin_px);
    }
  }
  if (cal.inner && ambiguous) {
    cal.warnings.push_back(
        "the edge of the camera's reflection is ambiguous (no flat disc inside a varied scene): "
        "check the inner circle on the overlay");
  }
  if (!cal.inner) {
    cal.warnings.push_back("no reflection of the camera found inside the rim: inner radius set to " +
                           Fixed(100 * o.inner_default_frac, 0) + " % of the rim radius");
  }
  cal.mirror = MirrorWithRadii(rim.center_x_px, rim.center_y_px, inner_radius, R, profile);
  if (rim.rms_px > o.warn_rms_px) {
    cal.warnings.push_back("poor rim fit: residual " + Fixed(rim.rms_px, 2) + " px RMS (more than " +
                           Fixed(o.warn_rms_px, 2) + ")");
  }
  if (rim.inlier_fraction < o.warn_inlier_fraction) {
    cal.warnings.push_back("poor rim fit: only " + Fixed(100 * rim.inlier_fraction, 0) +
                           " % of the edge points near the rim fit it");
  }
  if (rim.coverage < o.warn_coverage) {
    cal.warnings.push_back("the rim is seen over " + Fixed(100 * rim.coverage, 0) + " % of its circumference only");
  }
  const auto visible = VisibleSectors(rim.center_x_px, rim.center_y_px, R, gray.size());
  if (std::count(visible.begin(), visible.end(), false) > 0) {
    cal.warnings.push_back("the rim runs outside the image: the mirror is cut by the image's border");
  }
  return cal;
}

void OcclusionOptions::Validate() const {
  if (!(blur_sigma_px >= 0) || !(max_std_grey >= 0) || min_area_px < 0 || grow_px < 0) {
    throw std::invalid_argument("self-occlusion mask: options must not be negative");
  }
}

cv::Mat SelfOcclusionMask(const std::vector<cv::Mat>& frames, const MirrorModel& mirror, const OcclusionOptions& o,
                          OcclusionStats* stats) {
  o.Validate();
  if (frames.size() < 3)
    throw std::invalid_argument("self-occlusion mask: need at least 3 frames (got " + std::to_string(frames.size()) +
                                ")");
  const cv::Size size = frames.front().size();
  std::vector<cv::Mat> grey;
  grey.reserve(frames.size());
  cv::Mat mean(size, CV_32F, cv::Scalar(0));
  for (const auto& frame : frames) {
    if (frame.size() != size) throw std::invalid_argument("self-occlusion mask: the frames differ in size");
    cv::Mat g = ToGray(frame), f;
    if (o.blur_sigma_px > 0) cv::GaussianBlur(g, g, {0, 0}, o.blur_sigma_px);
    g.convertTo(f, CV_32F);
    mean += f;
    grey.push_back(f);
  }
  const double n = static_cast<double>(frames.size());
  mean /= n;
  // The ring (a little inside its edges), the housing just outside the rim and the camera's reflection.
  cv::Mat ring(size, CV_8U, cv::Scalar(0)), reference(size, CV_8U, cv::Scalar(0));
  const double R = mirror.outer_radius_px, r = mirror.inner_radius_px;
  for (int y = 0; y < size.height; ++y) {
    uint8_t* rp = ring.ptr<uint8_t>(y);
    uint8_t* hp = reference.ptr<uint8_t>(y);
    for (int x = 0; x < size.width; ++x) {
      const double d = std::hypot(x - mirror.center_x_px, y - mirror.center_y_px);
      if (d >= r + 2 && d <= R - 2) rp[x] = 255;
      if ((d >= R + 4 && d <= 1.12 * R + 4) || (d <= r - 4 && d >= 0.5 * r)) hp[x] = 255;
    }
  }
  // A camera's auto-exposure scales every pixel of a frame, the robot's parts too: each frame is
  // divided by its gain against the mean frame (the median ratio over the ring) first.
  std::vector<double> gains;
  std::vector<float> ratios;
  for (const cv::Mat& f : grey) {
    ratios.clear();
    for (int y = 0; y < size.height; y += 3) {
      const uint8_t* rp = ring.ptr<uint8_t>(y);
      const float* fp = f.ptr<float>(y);
      const float* mp = mean.ptr<float>(y);
      for (int x = 0; x < size.width; x += 3) {
        if (rp[x] && mp[x] > 10.f) ratios.push_back(fp[x] / mp[x]);
      }
    }
    double gain = 1.0;
    if (!ratios.empty()) {
      std::nth_element(ratios.begin(), ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2), ratios.end());
      gain = std::clamp(static_cast<double>(ratios[ratios.size() / 2]), 0.1, 10.0);
    }
    gains.push_back(gain);
  }
  const double mean_gain = std::accumulate(gains.begin(), gains.end(), 0.0) / n;
  cv::Mat sum(size, CV_64F, cv::Scalar(0)), sum2(size, CV_64F, cv::Scalar(0)), f;
  for (size_t k = 0; k < grey.size(); ++k) {
    grey[k].convertTo(f, CV_64F, mean_gain / gains[k]);
    sum += f;
    sum2 += f.mul(f);
  }
  cv::Mat mean64 = sum / n;
  cv::Mat var = sum2 / n - mean64.mul(mean64);
  cv::Mat sd;
  cv::max(var, 0.0, var);
  cv::sqrt(var, sd);
  sd.convertTo(sd, CV_32F);
  auto median_of = [&](const cv::Mat& where) {
    std::vector<float> v;
    for (int y = 0; y < size.height; ++y) {
      const uint8_t* w = where.ptr<uint8_t>(y);
      const float* s = sd.ptr<float>(y);
      for (int x = 0; x < size.width; ++x) {
        if (w[x]) v.push_back(s[x]);
      }
    }
    if (v.empty()) return -1.0;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return static_cast<double>(v[v.size() / 2]);
  };
  double noise = median_of(reference);
  const double scene = median_of(ring);
  if (noise < 0) noise = 1.0;
  // 3 x the sensor noise, at least a fifth of how much the scene changes (a JPEG camera's blocks
  // and ringing move a part's pixels with the scene beside it, while the flat housing the noise
  // is measured on stays smooth), but well below the scene's changes.
  const double threshold =
      o.max_std_grey > 0 ? o.max_std_grey : std::min(std::max({1.5, 3.0 * noise, 0.2 * scene}), std::max(1.5, 0.3 * scene));
  cv::Mat still = (sd < threshold) & ring;
  cv::morphologyEx(still, still, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  const int ring_area = std::max(1, cv::countNonZero(ring));
  const int min_area = o.min_area_px > 0 ? o.min_area_px : std::max(8, static_cast<int>(0.0005 * ring_area));
  cv::Mat labels, comp_stats, centroids;
  const int n_labels = cv::connectedComponentsWithStats(still, labels, comp_stats, centroids, 8, CV_32S);
  // A part of the robot is seen over a limited range of bearings; a still region all round the
  // centre is the scene (a plain floor) or the dead zone's edge, which the inner radius handles.
  std::vector<std::vector<bool>> bearings(static_cast<size_t>(n_labels), std::vector<bool>(72, false));
  for (int y = 0; y < size.height; ++y) {
    const int* lp = labels.ptr<int>(y);
    for (int x = 0; x < size.width; ++x) {
      if (lp[x] <= 0) continue;
      double a = std::atan2(y - mirror.center_y_px, x - mirror.center_x_px);
      if (a < 0) a += 2 * M_PI;
      bearings[static_cast<size_t>(lp[x])][std::min(71, static_cast<int>(a / (2 * M_PI) * 72))] = true;
    }
  }
  cv::Mat parts(size, CV_8U, cv::Scalar(0));
  int all_round = 0;
  for (int l = 1; l < n_labels; ++l) {
    if (comp_stats.at<int>(l, cv::CC_STAT_AREA) < min_area) continue;
    const auto& b = bearings[static_cast<size_t>(l)];
    if (std::count(b.begin(), b.end(), true) > 36) {
      ++all_round;
      continue;
    }
    parts.setTo(255, labels == l);
  }
  if (o.grow_px > 0) {
    cv::dilate(parts, parts, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * o.grow_px + 1, 2 * o.grow_px + 1}));
  }
  cv::Mat usable = parts == 0;
  if (stats) {
    stats->frames = static_cast<int>(frames.size());
    stats->threshold_grey = threshold;
    stats->noise_grey = noise;
    stats->scene_median_std = scene;
    stats->masked_fraction = static_cast<double>(cv::countNonZero(parts & ring)) / ring_area;
    stats->still_rings = all_round;
  }
  return usable;
}

cv::Mat DrawCalibrationOverlay(const cv::Mat& image, const MirrorModel& m, const cv::Mat& mask,
                               const std::optional<CircleFit>& holder) {
  cv::Mat out;
  if (image.channels() == 1)
    cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  else
    out = image.clone();
  if (!mask.empty() && mask.size() == out.size()) {
    cv::Mat red(out.size(), CV_8UC3, cv::Scalar(0, 0, 255)), tinted;
    cv::addWeighted(out, 0.45, red, 0.55, 0, tinted);
    tinted.copyTo(out, mask == 0);
  }
  const int thick = std::max(1, static_cast<int>(std::lround(std::max(out.cols, out.rows) / 500.0)));
  const int shift = 4;  // sub-pixel drawing
  const cv::Point c(static_cast<int>(std::lround(m.center_x_px * (1 << shift))),
                    static_cast<int>(std::lround(m.center_y_px * (1 << shift))));
  cv::circle(out, c, static_cast<int>(std::lround(m.outer_radius_px * (1 << shift))), cv::Scalar(0, 255, 0), thick,
             cv::LINE_AA, shift);
  cv::circle(out, c, static_cast<int>(std::lround(m.inner_radius_px * (1 << shift))), cv::Scalar(0, 255, 255), thick,
             cv::LINE_AA, shift);
  if (holder) {
    cv::circle(out,
               cv::Point(static_cast<int>(std::lround(holder->center_x_px * (1 << shift))),
                         static_cast<int>(std::lround(holder->center_y_px * (1 << shift)))),
               static_cast<int>(std::lround(holder->radius_px * (1 << shift))), cv::Scalar(0, 140, 255), thick,
               cv::LINE_AA, shift);
  }
  const int arm = 8 * thick << shift;
  cv::line(out, c - cv::Point(arm, 0), c + cv::Point(arm, 0), cv::Scalar(0, 255, 0), thick, cv::LINE_AA, shift);
  cv::line(out, c - cv::Point(0, arm), c + cv::Point(0, arm), cv::Scalar(0, 255, 0), thick, cv::LINE_AA, shift);
  return out;
}

}  // namespace snapnav::nav
