#include "snapnav/nav/trajectory.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace snapnav::nav {

std::vector<std::pair<Pose2, Pose2>> AssociateByTime(const std::vector<StampedPose>& estimate,
                                                     const std::vector<StampedPose>& reference, int64_t max_dt_us) {
  std::vector<std::pair<Pose2, Pose2>> pairs;
  size_t j = 0;
  for (const StampedPose& e : estimate) {
    while (j + 1 < reference.size() && std::llabs(reference[j + 1].utime - e.utime) <= std::llabs(reference[j].utime - e.utime)) ++j;
    if (j < reference.size() && std::llabs(reference[j].utime - e.utime) <= max_dt_us) pairs.emplace_back(e.pose, reference[j].pose);
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

}  // namespace snapnav::nav
