#include "snapnav/nav/slam/wall_orientations.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace snapnav::nav {
namespace {

// A normal's direction in [0, pi).
double LineAngle(const Eigen::Vector2d& n) {
  double a = std::atan2(n.y(), n.x());
  if (a < 0) a += M_PI;
  if (a >= M_PI) a -= M_PI;
  return a;
}

// Adds a normal's direction to a histogram of bins of bin_rad over [0, pi): linear interpolation
// between the two nearest bins (circular over pi).
void AddToBins(const Eigen::Vector2d& normal, double weight, double bin_rad, std::vector<double>* bins) {
  const double f = LineAngle(normal) / bin_rad;
  const int n = static_cast<int>(bins->size());
  const int b0 = static_cast<int>(std::floor(f)) % n;
  const double w1 = f - std::floor(f);
  (*bins)[static_cast<size_t>(b0)] += weight * (1 - w1);
  (*bins)[static_cast<size_t>((b0 + 1) % n)] += weight * w1;
}

}  // namespace

WallOrientations::WallOrientations(double bin_rad) : bin_rad_(bin_rad) {
  if (!(bin_rad > 0 && bin_rad <= 0.1)) throw std::invalid_argument("wall orientations: bin must be in (0, 0.1] rad");
  bins_.assign(static_cast<size_t>(std::ceil(M_PI / bin_rad)), 0.0);
}

void WallOrientations::Add(const Eigen::Vector2d& normal, double weight) {
  if (normal.isZero() || !(weight > 0)) return;
  AddToBins(normal, weight, bin_rad_, &bins_);
  total_ += weight;
  smooth_valid_ = false;
}

void WallOrientations::Clear() {
  std::fill(bins_.begin(), bins_.end(), 0.0);
  total_ = 0;
  smooth_valid_ = false;
}

std::optional<WallOrientations::Alignment> WallOrientations::Align(const std::vector<Eigen::Vector2d>& normals,
                                                                   double window_rad, double kernel_rad) const {
  if (total_ <= 0 || !(kernel_rad > 0) || !(window_rad > 0)) return std::nullopt;
  const int n = static_cast<int>(bins_.size());
  // The map's directions spread by the kernel, normalised so that a lone direction peaks at 1 (kept
  // between calls until a normal is added).
  if (!smooth_valid_ || smooth_kernel_rad_ != kernel_rad) {
    const int half = static_cast<int>(std::ceil(3 * kernel_rad / bin_rad_));
    std::vector<double> kernel(static_cast<size_t>(2 * half + 1));
    for (int k = -half; k <= half; ++k) {
      const double d = k * bin_rad_ / kernel_rad;
      kernel[static_cast<size_t>(k + half)] = std::exp(-0.5 * d * d);
    }
    smooth_.assign(static_cast<size_t>(n), 0.0);
    for (int b = 0; b < n; ++b) {
      const double v = bins_[static_cast<size_t>(b)];
      if (v == 0) continue;
      for (int k = -half; k <= half; ++k) {
        int i = b + k;  // circular over pi (half < n)
        if (i < 0) i += n;
        if (i >= n) i -= n;
        smooth_[static_cast<size_t>(i)] += v * kernel[static_cast<size_t>(k + half)];
      }
    }
    const double peak = *std::max_element(smooth_.begin(), smooth_.end());
    if (peak > 0) {
      for (double& v : smooth_) v /= peak;
    }
    smooth_kernel_rad_ = kernel_rad;
    smooth_valid_ = true;
  }
  const std::vector<double>& smooth = smooth_;
  if (!(*std::max_element(smooth.begin(), smooth.end()) > 0)) return std::nullopt;
  // The scan's directions, binned the same way.
  std::vector<double> scan(static_cast<size_t>(n), 0.0);
  double scan_total = 0;
  for (const Eigen::Vector2d& v : normals) {
    if (v.isZero()) continue;
    AddToBins(v, 1, bin_rad_, &scan);
    scan_total += 1;
  }
  if (scan_total <= 0) return std::nullopt;
  std::vector<std::pair<int, double>> occupied;  // the scan's non-empty bins
  for (int b = 0; b < n; ++b) {
    if (scan[static_cast<size_t>(b)] != 0) occupied.emplace_back(b, scan[static_cast<size_t>(b)]);
  }
  const int steps = std::min(static_cast<int>(std::floor(window_rad / bin_rad_)), n / 2);
  // The map's histogram with `steps` bins of its other end on each side: shifts without wrapping.
  std::vector<double> padded(static_cast<size_t>(n + 2 * steps));
  for (int i = 0; i < n + 2 * steps; ++i) padded[static_cast<size_t>(i)] = smooth[static_cast<size_t>((i - steps + n) % n)];
  std::vector<double> score(static_cast<size_t>(2 * steps + 1), 0.0);
  for (int s = -steps; s <= steps; ++s) {
    double c = 0;
    for (const auto& [b, w] : occupied) c += w * padded[static_cast<size_t>(b + s + steps)];
    score[static_cast<size_t>(s + steps)] = c / scan_total;
  }
  const auto best = std::max_element(score.begin(), score.end());
  const int i = static_cast<int>(best - score.begin());
  double mean = 0;
  for (double v : score) mean += v;
  mean /= static_cast<double>(score.size());
  // Sub-bin: the parabola through the best and its neighbours (not at the window's edge).
  double sub = 0;
  if (i > 0 && i + 1 < static_cast<int>(score.size())) {
    const double l = score[static_cast<size_t>(i - 1)], c = score[static_cast<size_t>(i)], r = score[static_cast<size_t>(i + 1)];
    const double den = l - 2 * c + r;
    if (den < 0) sub = std::clamp(0.5 * (l - r) / den, -0.5, 0.5);
  }
  // The best other local maximum, at least 3 kernel widths away: another way the walls could align.
  const int apart = static_cast<int>(std::ceil(3 * kernel_rad / bin_rad_));
  double second = 0;
  for (int k = 1; k + 1 < static_cast<int>(score.size()); ++k) {
    if (std::abs(k - i) < apart) continue;
    const double v = score[static_cast<size_t>(k)];
    if (v >= score[static_cast<size_t>(k - 1)] && v >= score[static_cast<size_t>(k + 1)]) second = std::max(second, v);
  }
  Alignment a;
  a.ambiguity = *best > 0 ? second / *best : 0;
  a.offset_rad = ((i - steps) + sub) * bin_rad_;
  a.score = *best;
  a.contrast = mean > 0 ? *best / mean : 0;
  if (i == 0 || i + 1 == static_cast<int>(score.size())) return std::nullopt;  // no maximum inside the window
  return a;
}

}  // namespace snapnav::nav
