#include "snapnav/nav/slam/wall_orientations.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace snapnav::nav {

WallOrientations::WallOrientations(double kernel_rad, double bin_rad) : kernel_rad_(kernel_rad) {
  if (!(bin_rad > 0 && bin_rad <= 0.1)) throw std::invalid_argument("wall orientations: bin must be in (0, 0.1] rad");
  if (!(kernel_rad > 0 && kernel_rad <= 0.2)) throw std::invalid_argument("wall orientations: kernel must be in (0, 0.2] rad");
  // A whole number of bins over pi: a direction and the same turned by pi fall in the same bin.
  const int n = static_cast<int>(std::lround(M_PI / bin_rad));
  bin_rad_ = M_PI / n;
  const int half = std::min(static_cast<int>(std::ceil(3 * kernel_rad / bin_rad_)), (n - 1) / 2);
  for (int k = -half; k <= half; ++k) {
    const double d = k * bin_rad_ / kernel_rad;
    kernel_.push_back(std::exp(-0.5 * d * d));
  }
  smooth_.assign(static_cast<size_t>(n), 0.0);
}

double WallOrientations::Direction(const Eigen::Vector2d& normal) {
  if (normal.isZero()) return std::numeric_limits<double>::quiet_NaN();
  double a = std::atan2(normal.y(), normal.x());
  if (a < 0) a += M_PI;
  if (a >= M_PI) a -= M_PI;
  return a;
}

void WallOrientations::AddDirection(double direction_rad, double weight) {
  if (!std::isfinite(direction_rad) || !(weight > 0)) return;
  // Linear interpolation between the two nearest bins (circular over pi), each spread by the kernel.
  const int n = static_cast<int>(smooth_.size());
  const int half = static_cast<int>(kernel_.size() / 2);
  const double f = direction_rad / bin_rad_;
  const double fl = std::floor(f);
  const double w1 = f - fl;
  int b = static_cast<int>(fl) % n;
  if (b < 0) b += n;
  for (const double w : {weight * (1 - w1), weight * w1}) {
    for (int k = -half; k <= half; ++k) {
      int i = b + k;
      if (i < 0) i += n;
      if (i >= n) i -= n;
      smooth_[static_cast<size_t>(i)] += w * kernel_[static_cast<size_t>(k + half)];
    }
    b = (b + 1) % n;
  }
  total_ += weight;
}

void WallOrientations::Clear() {
  std::fill(smooth_.begin(), smooth_.end(), 0.0);
  total_ = 0;
}

std::optional<WallOrientations::Alignment> WallOrientations::Align(const std::vector<Eigen::Vector2d>& normals,
                                                                   double window_rad) const {
  std::vector<double> directions;
  directions.reserve(normals.size());
  for (const Eigen::Vector2d& v : normals) directions.push_back(Direction(v));
  return Align(directions, 0, window_rad);
}

std::optional<WallOrientations::Alignment> WallOrientations::Align(const std::vector<double>& directions,
                                                                   double turn_rad, double window_rad) const {
  if (total_ <= 0 || !(window_rad > 0) || !std::isfinite(turn_rad)) return std::nullopt;
  const int n = static_cast<int>(smooth_.size());
  // The map's directions spread by the kernel, normalised so that a lone direction peaks at 1.
  const double peak = *std::max_element(smooth_.begin(), smooth_.end());
  if (!(peak > 0)) return std::nullopt;
  // The scan's directions, turned and binned as the map's are (without the kernel).
  scan_.assign(static_cast<size_t>(n), 0.0);
  double scan_total = 0;
  const double turn = std::fmod(turn_rad, M_PI) + M_PI;  // in (0, 2 pi)
  for (const double d : directions) {
    if (!std::isfinite(d)) continue;
    const double f = (d + turn) / bin_rad_;
    const double fl = std::floor(f);
    const double w1 = f - fl;
    const int b = static_cast<int>(fl) % n;
    scan_[static_cast<size_t>(b)] += 1 - w1;
    scan_[static_cast<size_t>((b + 1) % n)] += w1;
    scan_total += 1;
  }
  if (scan_total <= 0) return std::nullopt;
  const int steps = std::min(static_cast<int>(std::floor(window_rad / bin_rad_)), n / 2);
  // The map's histogram with `steps` bins of its other end on each side: shifts without wrapping.
  padded_.resize(static_cast<size_t>(n + 2 * steps));
  for (int i = 0; i < n + 2 * steps; ++i) padded_[static_cast<size_t>(i)] = smooth_[static_cast<size_t>((i - steps + n) % n)];
  score_.assign(static_cast<size_t>(2 * steps + 1), 0.0);
  for (int b = 0; b < n; ++b) {
    const double w = scan_[static_cast<size_t>(b)];
    if (w == 0) continue;
    const double* map = padded_.data() + b;  // map[s + steps]: the map at the scan's bin shifted by s
    for (int k = 0; k <= 2 * steps; ++k) score_[static_cast<size_t>(k)] += w * map[k];
  }
  const double norm = 1 / (scan_total * peak);
  for (double& v : score_) v *= norm;
  const std::vector<double>& score = score_;
  const auto best = std::max_element(score.begin(), score.end());
  const int i = static_cast<int>(best - score.begin());
  if (i == 0 || i + 1 == static_cast<int>(score.size())) return std::nullopt;  // no maximum inside the window
  double mean = 0;
  for (double v : score) mean += v;
  mean /= static_cast<double>(score.size());
  // Sub-bin: the parabola through the best and its neighbours.
  double sub = 0;
  {
    const double l = score[static_cast<size_t>(i - 1)], c = score[static_cast<size_t>(i)], r = score[static_cast<size_t>(i + 1)];
    const double den = l - 2 * c + r;
    if (den < 0) sub = std::clamp(0.5 * (l - r) / den, -0.5, 0.5);
  }
  // The best other local maximum, at least 3 kernel widths away: another way the walls could align.
  const int apart = static_cast<int>(std::ceil(3 * kernel_rad_ / bin_rad_));
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
  return a;
}

}  // namespace snapnav::nav
