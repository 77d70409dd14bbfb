#include "snapnav/nav/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <cstdlib>
#include <stdexcept>

namespace snapnav::nav {

std::optional<size_t> NearestInTime(const std::vector<StampedPose>& reference, int64_t utime, int64_t max_dt_us) {
  const auto it = std::lower_bound(reference.begin(), reference.end(), utime,
                                   [](const StampedPose& p, int64_t t) { return p.utime < t; });
  std::optional<size_t> best;
  int64_t best_dt = max_dt_us;
  for (auto c : {it, it == reference.begin() ? reference.end() : std::prev(it)}) {
    if (c == reference.end()) continue;
    const int64_t dt = std::llabs(c->utime - utime);
    if (dt <= best_dt) {
      best_dt = dt;
      best = static_cast<size_t>(c - reference.begin());
    }
  }
  return best;
}

std::vector<std::pair<Pose2, Pose2>> AssociateByTime(const std::vector<StampedPose>& estimate,
                                                     const std::vector<StampedPose>& reference, int64_t max_dt_us) {
  std::vector<std::pair<Pose2, Pose2>> pairs;
  for (const StampedPose& e : estimate) {
    if (const auto j = NearestInTime(reference, e.utime, max_dt_us)) pairs.emplace_back(e.pose, reference[*j].pose);
  }
  return pairs;
}

Pose2 AlignSE2(const std::vector<std::pair<Pose2, Pose2>>& pairs) {
  if (pairs.size() < 2) throw std::invalid_argument("SE(2) alignment needs at least 2 pose pairs");
  double mex = 0, mey = 0, mrx = 0, mry = 0;
  for (const auto& [e, r] : pairs) {
    mex += e.x_m;
    mey += e.y_m;
    mrx += r.x_m;
    mry += r.y_m;
  }
  const double n = static_cast<double>(pairs.size());
  mex /= n;
  mey /= n;
  mrx /= n;
  mry /= n;
  double sxx = 0, sxy = 0;  // sum of dot and cross products of centred points
  for (const auto& [e, r] : pairs) {
    const double ex = e.x_m - mex, ey = e.y_m - mey, rx = r.x_m - mrx, ry = r.y_m - mry;
    sxx += ex * rx + ey * ry;
    sxy += ex * ry - ey * rx;
  }
  const double theta = std::atan2(sxy, sxx);
  const double c = std::cos(theta), s = std::sin(theta);
  return {mrx - (c * mex - s * mey), mry - (s * mex + c * mey), theta};
}

AteResult ComputeAte(const std::vector<std::pair<Pose2, Pose2>>& pairs, const Pose2& align) {
  AteResult r;
  double sum2 = 0, sum = 0;
  for (const auto& [e, ref] : pairs) {
    const Pose2 a = align.Compose(e);
    const double d = std::hypot(a.x_m - ref.x_m, a.y_m - ref.y_m);
    sum2 += d * d;
    sum += d;
    r.max_m = std::max(r.max_m, d);
    r.final_m = d;
  }
  r.pairs = static_cast<int>(pairs.size());
  if (r.pairs > 0) {
    r.rmse_m = std::sqrt(sum2 / r.pairs);
    r.mean_m = sum / r.pairs;
  }
  return r;
}

RpeResult ComputeRpe(const std::vector<std::pair<Pose2, Pose2>>& pairs, double delta_m) {
  if (!(delta_m > 0) || !std::isfinite(delta_m)) throw std::invalid_argument("RPE needs a positive, finite delta_m");
  RpeResult r;
  r.delta_m = delta_m;
  // Travelled distance of the reference at each pair.
  std::vector<double> travelled(pairs.size(), 0.0);
  for (size_t i = 1; i < pairs.size(); ++i) {
    const Pose2 &a = pairs[i - 1].second, &b = pairs[i].second;
    travelled[i] = travelled[i - 1] + std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
  }
  // A relative tolerance so that e.g. ten 0.1 m steps count as 1 m.
  const double tolerance = 1e-9 * std::max(1.0, delta_m);
  double sum_t2 = 0, sum_t = 0, sum_r2 = 0;
  size_t j = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < pairs.size() && travelled[j] - travelled[i] < delta_m - tolerance) ++j;
    if (j >= pairs.size()) break;  // later i travel even less
    const Pose2 estimate_motion = pairs[i].first.Between(pairs[j].first);
    const Pose2 reference_motion = pairs[i].second.Between(pairs[j].second);
    const Pose2 error = reference_motion.Between(estimate_motion);
    const double t = std::hypot(error.x_m, error.y_m);
    const double rot_deg = std::abs(WrapAngle(error.theta_rad)) * 180.0 / M_PI;
    sum_t2 += t * t;
    sum_t += t;
    sum_r2 += rot_deg * rot_deg;
    r.translation_max_m = std::max(r.translation_max_m, t);
    r.rotation_max_deg = std::max(r.rotation_max_deg, rot_deg);
    ++r.segments;
  }
  if (r.segments > 0) {
    r.translation_rmse_m = std::sqrt(sum_t2 / r.segments);
    r.translation_mean_m = sum_t / r.segments;
    r.rotation_rmse_deg = std::sqrt(sum_r2 / r.segments);
  }
  return r;
}

}  // namespace snapnav::nav
