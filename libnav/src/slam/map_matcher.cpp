#include "snapnav/nav/slam/map_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

namespace snapnav::nav {

const char* IcpMetricName(IcpMetric m) {
  return m == IcpMetric::kPointToPoint ? "point_to_point" : "point_to_line";
}

std::optional<IcpMetric> ParseIcpMetric(const std::string& name) {
  if (name == "point_to_point") return IcpMetric::kPointToPoint;
  if (name == "point_to_line") return IcpMetric::kPointToLine;
  return std::nullopt;
}

const char* ScanMatcherName(ScanMatcher m) { return m == ScanMatcher::kHeading ? "heading" : "correlative"; }

namespace {

// Sums of points' offsets from a scan point, and their products (the point itself counted as one
// at the origin).
struct Moments {
  int count = 1;
  double x = 0, y = 0, xx = 0, xy = 0, yy = 0;
  void Add(const Eigen::Vector2d& d) {
    ++count;
    x += d.x();
    y += d.y();
    xx += d.x() * d.x();
    xy += d.x() * d.y();
    yy += d.y() * d.y();
  }
  // Another's offsets (without its point).
  void Merge(const Moments& o) {
    count += o.count - 1;
    x += o.x;
    y += o.y;
    xx += o.xx;
    xy += o.xy;
    yy += o.yy;
  }
  // The unit normal of the line through the points (principal axes); zero with fewer than 3
  // points or where they do not lie on a line.
  Eigen::Vector2d Normal() const {
    if (count < 3) return Eigen::Vector2d::Zero();
    const double mx = x / count, my = y / count;
    const double a = xx / count - mx * mx, b = xy / count - mx * my, c = yy / count - my * my;
    // Closed-form eigen decomposition of the symmetric 2x2 covariance.
    const double half_trace = 0.5 * (a + c), det = a * c - b * b;
    const double root = std::sqrt(std::max(0.0, half_trace * half_trace - det));
    const double large = half_trace + root, small = half_trace - root;
    if (!(large > 0) || small > 0.1 * large) return Eigen::Vector2d::Zero();  // not a line
    // Eigenvector of the small eigenvalue: the normal.
    const Eigen::Vector2d v = std::abs(b) > 1e-15 ? Eigen::Vector2d(b, small - a)
                                                  : (a < c ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1));
    return v.normalized();
  }
};

}  // namespace

void ScanNormals(const std::vector<Eigen::Vector2d>& points, int neighbours, int more_neighbours, double max_gap_m,
                 std::vector<Eigen::Vector2d>* normals, std::vector<Eigen::Vector2d>* more) {
  const int n = static_cast<int>(points.size());
  const int reach = std::max(neighbours, more_neighbours);
  normals->assign(points.size(), Eigen::Vector2d::Zero());
  if (more) more->assign(points.size(), Eigen::Vector2d::Zero());
  for (int i = 0; i < n; ++i) {
    // Neighbours may be farther apart at long range (beams diverge): 5 % of the range.
    const double gap = std::max(max_gap_m, 0.05 * points[i].norm());
    const double gap2 = gap * gap;
    // Walk outwards on each side while the neighbours stay close to the point; the sums of the
    // first `neighbours` steps and of the first `more_neighbours`.
    Moments few, many;
    for (const int dir : {-1, 1}) {
      Moments side_few, side_many;
      for (int k = 1; k <= (more ? reach : neighbours); ++k) {
        const int j = i + dir * k;
        if (j < 0 || j >= n) break;
        const Eigen::Vector2d d = points[j] - points[i];
        if (d.squaredNorm() > gap2 * k * k) break;
        if (k <= neighbours) side_few.Add(d);
        if (k <= more_neighbours) side_many.Add(d);
      }
      few.Merge(side_few);
      many.Merge(side_many);
    }
    (*normals)[static_cast<size_t>(i)] = few.Normal();
    if (more) (*more)[static_cast<size_t>(i)] = many.Normal();
  }
}

std::vector<Eigen::Vector2d> ScanNormals(const std::vector<Eigen::Vector2d>& points, int neighbours, double max_gap_m) {
  std::vector<Eigen::Vector2d> normals;
  ScanNormals(points, neighbours, neighbours, max_gap_m, &normals, nullptr);
  return normals;
}

std::optional<Pose2> AlignPoints(const std::vector<Eigen::Vector2d>& src, const std::vector<Eigen::Vector2d>& dst) {
  if (src.size() != dst.size() || src.size() < 2) return std::nullopt;
  Eigen::Vector2d ms = Eigen::Vector2d::Zero(), md = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    ms += src[i];
    md += dst[i];
  }
  ms /= static_cast<double>(src.size());
  md /= static_cast<double>(dst.size());
  double sxx = 0, sxy = 0, spread = 0;  // cross terms of the centred pairs
  for (size_t i = 0; i < src.size(); ++i) {
    const Eigen::Vector2d a = src[i] - ms, b = dst[i] - md;
    sxx += a.x() * b.x() + a.y() * b.y();
    sxy += a.x() * b.y() - a.y() * b.x();
    spread += a.squaredNorm();
  }
  if (spread < 1e-12) return std::nullopt;
  const double theta = std::atan2(sxy, sxx);
  const double c = std::cos(theta), s = std::sin(theta);
  const Eigen::Vector2d t = md - Eigen::Vector2d(c * ms.x() - s * ms.y(), s * ms.x() + c * ms.y());
  return Pose2{t.x(), t.y(), WrapAngle(theta)};
}

std::vector<Eigen::Vector2d> ScanToPoints(const std::vector<float>& ranges_m, double angle_min_rad,
                                          double angle_increment_rad, double range_min_m, double range_max_m,
                                          const Pose2& sensor) {
  std::vector<Eigen::Vector2d> points;
  points.reserve(ranges_m.size());
  // Ranges travel as floats: a max-range reading may arrive a few ULPs below range_max.
  const double no_return = range_max_m - 1e-5 * std::max(1.0, range_max_m);
  for (size_t i = 0; i < ranges_m.size(); ++i) {
    const double r = ranges_m[i];
    if (!std::isfinite(r) || r < range_min_m || r >= no_return) continue;
    const double a = angle_min_rad + angle_increment_rad * static_cast<double>(i);
    points.push_back(sensor.Transform({r * std::cos(a), r * std::sin(a)}));
  }
  return points;
}

namespace {

// The correlative search scores this many of a heading's shifts exactly (the best on the raster).
constexpr size_t kRescoredShifts = 2;
// ... for the headings whose best raster score is within this fraction of the search's best.
constexpr double kRescoreMargin = 0.25;

// A pose as a rotation and translation, its sine and cosine computed once for many points.
struct Rigid {
  explicit Rigid(const Pose2& p) : c(std::cos(p.theta_rad)), s(std::sin(p.theta_rad)), t(p.x_m, p.y_m) {}
  Eigen::Vector2d operator()(const Eigen::Vector2d& v) const { return RotateBy(c, s, v) + t; }
  double c, s;
  Eigen::Vector2d t;
};

// Every stride-th point at `to_map` in *world, and the index of each one's nearest map point
// within max_distance_m (PointGridMap::LookupIndex; -1: none) in *nearest.
void LookupAt(const PointGridMap& map, const Rigid& to_map, const std::vector<Eigen::Vector2d>& points, size_t stride,
              double max_distance_m, std::vector<Eigen::Vector2d>* world, std::vector<int>* nearest) {
  const size_t n = (points.size() + stride - 1) / stride;
  world->resize(n);
  Eigen::Vector2d* out = world->data();
  for (size_t k = 0; k < n; ++k) out[k] = to_map(points[k * stride]);
  nearest->resize(n);
  map.LookupIndices(out, n, max_distance_m, nearest->data());
}

}  // namespace

MapMatcher::Icp MapMatcher::Align(const Pose2& start, const std::vector<Eigen::Vector2d>& points,
                                const std::vector<Eigen::Vector2d>& normals, double prune_below) const {
  Icp r;
  r.estimate = start;
  // After refine_prune_iterations iterations: whether this start is pruned (ends, not ok).
  const auto prune = [&](int iterations) {
    if (prune_below <= 0 || iterations != options_.refine_prune_iterations) return false;
    r.pruned = KernelScore(r.estimate, points, 1) < prune_below;
    return r.pruned;
  };
  double distance = options_.match_distance_start_m;
  const auto next_distance = [&] { distance = std::max(options_.match_distance_m, 0.5 * distance); };
  if (options_.metric == IcpMetric::kPointToLine) {
    // Gauss-Newton on sum w_i (n_i . (R p_i + t - q_i))^2, n_i the map point's normal (or the
    // scan point's, rotated, if the map point has none), w_i a Cauchy weight of the residual.
    const double scale2 = options_.robust_scale_m * options_.robust_scale_m;
    std::vector<Eigen::Vector2d> world;  // the points at the estimate
    std::vector<int> nearest;            // their nearest map points
    for (int it = 0; it < options_.icp_iterations; ++it) {
      const double c = std::cos(r.estimate.theta_rad), s = std::sin(r.estimate.theta_rad);
      Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      int matches = 0;
      double residual2 = 0, weight_sum = 0;
      Eigen::Matrix3d info = Eigen::Matrix3d::Zero();  // for the covariance: each point's own noise
      LookupAt(map_, Rigid(r.estimate), points, 1, distance, &world, &nearest);
      for (size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector2d& w = world[i];
        const int j = nearest[i];
        if (j < 0) continue;
        const Eigen::Vector2d scan_normal = RotateBy(c, s, normals[i]);
        Eigen::Vector2d n = map_.normals()[static_cast<size_t>(j)];
        if (n.isZero()) n = scan_normal;
        if (n.isZero()) continue;
        // Surfaces facing differently (more than 45 degrees apart) are not the same surface.
        if (!scan_normal.isZero() && std::abs(scan_normal.dot(n)) < 0.7071) continue;
        const double res = n.dot(w - map_.points()[static_cast<size_t>(j)]);
        const Eigen::Vector2d d_theta(-s * points[i].x() - c * points[i].y(), c * points[i].x() - s * points[i].y());
        const Eigen::Vector3d jac(n.x(), n.y(), n.dot(d_theta));
        const double weight = 1.0 / (1.0 + res * res / scale2);
        h += weight * jac * jac.transpose();
        g += weight * res * jac;
        const double inv_var = weight / PointVariance(points[i]);
        info += inv_var * jac * jac.transpose();
        residual2 += inv_var * res * res;
        weight_sum += weight;
        ++matches;
      }
      ++r.iterations;
      r.matches = matches;
      if (matches < options_.min_matches) break;
      r.info = info;
      r.residual2 = residual2;
      r.weight_sum = weight_sum;
      // A small damping keeps directions the scan cannot see (a corridor's axis) where they were.
      const Eigen::Vector3d step = -(h + 1e-6 * (h.trace() + 1.0) * Eigen::Matrix3d::Identity()).ldlt().solve(g);
      r.estimate = {r.estimate.x_m + step.x(), r.estimate.y_m + step.y(), WrapAngle(r.estimate.theta_rad + step.z())};
      const bool coarse = distance > options_.match_distance_m;
      next_distance();
      if (!coarse && std::hypot(step.x(), step.y()) + std::abs(step.z()) < options_.icp_convergence_m) break;
      if (prune(r.iterations)) break;
    }
  } else {
    // Thesis 5.3.1: nearest map point of every scan point, closed-form alignment, repeated.
    std::vector<Eigen::Vector2d> src, dst;
    std::vector<size_t> index;
    std::vector<Eigen::Vector2d> world;  // the points at the estimate
    std::vector<int> nearest;            // their nearest map points
    for (int it = 0; it < options_.icp_iterations; ++it) {
      LookupAt(map_, Rigid(r.estimate), points, 1, distance, &world, &nearest);
      src.resize(points.size());
      dst.resize(points.size());
      index.resize(points.size());
      size_t m = 0;
      const std::vector<Eigen::Vector2d>& map_points = map_.points();
      for (size_t i = 0; i < points.size(); ++i) {
        const int j = nearest[i];
        if (j < 0) continue;
        src[m] = points[i];
        dst[m] = map_points[static_cast<size_t>(j)];
        index[m] = i;
        ++m;
      }
      src.resize(m);
      dst.resize(m);
      index.resize(m);
      ++r.iterations;
      r.matches = static_cast<int>(src.size());
      if (r.matches < options_.min_matches) break;
      const auto next = AlignPoints(src, dst);
      if (!next) break;
      // Convergence: translation plus rotation (radians count as metres at 1 m range).
      const double step = std::hypot(next->x_m - r.estimate.x_m, next->y_m - r.estimate.y_m) +
                          std::abs(WrapAngle(next->theta_rad - r.estimate.theta_rad));
      r.estimate = *next;
      const bool coarse = distance > options_.match_distance_m;
      next_distance();
      if (!coarse && step < options_.icp_convergence_m) break;
      if (prune(r.iterations)) break;
    }
    if (r.matches >= options_.min_matches) {
      // Information from the point-to-line geometry of the matches: the normal of the scan's
      // surface at each match constrains the pose along it only, so a corridor leaves its axis
      // to the prediction.
      const double c = std::cos(r.estimate.theta_rad), s = std::sin(r.estimate.theta_rad);
      for (size_t k = 0; k < src.size(); ++k) {
        // (Pose2::Transform's arithmetic, its sine and cosine computed once.)
        const Eigen::Vector2d at(r.estimate.x_m + c * src[k].x() - s * src[k].y(),
                                 r.estimate.y_m + s * src[k].x() + c * src[k].y());
        const Eigen::Vector2d n = RotateBy(c, s, normals[index[k]]);
        if (n.isZero()) continue;  // isolated point or corner: no surface
        const Eigen::Vector2d d_theta(-s * src[k].x() - c * src[k].y(), c * src[k].x() - s * src[k].y());
        const Eigen::Vector3d jac(n.x(), n.y(), n.dot(d_theta));
        const double res = n.dot(at - dst[k]), inv_var = 1.0 / PointVariance(src[k]);
        r.info += inv_var * jac * jac.transpose();
        r.residual2 += inv_var * res * res;
        r.weight_sum += 1;
      }
    }
  }
  r.ok = !r.pruned && r.matches >= options_.min_matches && r.weight_sum > 0;
  return r;
}

double MapMatcher::Prior::Penalty(const Pose2& p) const {
  const Eigen::Vector3d d(p.x_m - pose.x_m, p.y_m - pose.y_m, WrapAngle(p.theta_rad - pose.theta_rad));
  return weight * 0.5 * d.dot(information * d);
}

double MapMatcher::PointVariance(const Eigen::Vector2d& point_robot) const {
  const double angular = options_.point_sigma_rad * point_robot.norm();
  return options_.point_sigma_m * options_.point_sigma_m + angular * angular;
}

double MapMatcher::Score(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const {
  const double tau = options_.match_distance_m, tau2 = tau * tau;
  double score = 0;
  std::vector<Eigen::Vector2d> world;
  std::vector<int> nearest;
  LookupAt(map_, Rigid(pose), points, stride, tau, &world, &nearest);
  for (size_t i = 0; i < world.size(); ++i) {
    const int j = nearest[i];
    if (j >= 0) score += 1.0 - (map_.points()[static_cast<size_t>(j)] - world[i]).squaredNorm() / tau2;
  }
  return score;
}

std::vector<MapMatcher::Candidate> MapMatcher::Peaks(const std::vector<Candidate>& by_heading) {
  std::vector<Candidate> peaks;
  const size_t n = by_heading.size();
  for (size_t i = 0; i < n; ++i) {
    const double s = by_heading[i].score;
    if ((i > 0 && by_heading[i - 1].score >= s) || (i + 1 < n && by_heading[i + 1].score > s)) continue;
    peaks.push_back(by_heading[i]);
  }
  std::stable_sort(peaks.begin(), peaks.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  return peaks;
}

std::vector<MapMatcher::Candidate> MapMatcher::SearchHeading(const Pose2& around, double window_rad, double shift_m,
                                                           const std::vector<Eigen::Vector2d>& points,
                                                           size_t stride) const {
  const double step = options_.search_step_rad;
  const int n = static_cast<int>(std::ceil(window_rad / step));
  const int m = shift_m > 0 ? 1 : 0;
  const int sign = options_.search_order_reversed ? -1 : 1;
  // Per heading (from -n to n), the best of its positions; on a tie the first one stays.
  std::vector<Candidate> by_heading;
  for (int ik = -n; ik <= n; ++ik) {
    const int k = sign * ik;
    Candidate best{around, -1};
    for (int ix = -m; ix <= m; ++ix) {
      for (int iy = -m; iy <= m; ++iy) {
        const int dx = sign * ix, dy = sign * iy;
        const Pose2 candidate{around.x_m + dx * shift_m, around.y_m + dy * shift_m, WrapAngle(around.theta_rad + k * step)};
        const double score = Score(candidate, points, stride);
        if (score > best.score) best = {candidate, score};
      }
    }
    by_heading.push_back(best);
  }
  if (sign < 0) std::reverse(by_heading.begin(), by_heading.end());
  return Peaks(by_heading);
}

std::vector<MapMatcher::Candidate> MapMatcher::SearchPoses(const Pose2& around, const Eigen::Matrix3d& covariance,
                                                         double window_rad, double window_xy_m, double prior_weight,
                                                         const std::vector<Eigen::Vector2d>& points,
                                                         size_t stride) const {
  const double cell = map_.lookup_radius_m() > 0 ? map_.lookup_cell_m() : map_.resolution_m();
  const double step = options_.search_step_rad;
  const int nt = static_cast<int>(std::floor(window_rad / step + 1e-9));
  const int nxy = static_cast<int>(std::floor(window_xy_m / cell + 1e-9));
  const double sigma = options_.search_sigma_m, reach = 3 * sigma, inv2s2 = 1.0 / (2 * sigma * sigma);
  const Eigen::Matrix3d info = (covariance + Eigen::Vector3d(1e-8, 1e-8, 1e-8).asDiagonal().toDenseMatrix()).inverse();
  const double prior = 0.5 * prior_weight;
  std::vector<Eigen::Vector2d> rotated, subset;  // the search's points, rotated to a heading; as they are
  rotated.reserve(points.size() / stride + 1);
  subset.reserve(points.size() / stride + 1);
  for (size_t i = 0; i < points.size(); i += stride) subset.push_back(points[i]);
  const int sign = options_.search_order_reversed ? -1 : 1;
  // With the map's likelihood raster (its nodes a lookup cell / kLikelihoodSub apart, the shifts
  // a whole cell), a point's score at every shift comes from one block of the raster.
  const bool raster = map_.has_likelihood();
  std::vector<double> sums(raster ? static_cast<size_t>(2 * nxy + 1) * (2 * nxy + 1) : 0);
  struct Ranked {
    Eigen::Vector2d shift;
    double total;
    size_t order;  // visiting order
  };
  std::vector<Ranked> ranked;
  std::vector<Candidate> by_heading(static_cast<size_t>(2 * nt + 1));
  // Per heading with the raster: its shifts to score exactly (the best kRescoredShifts on the raster).
  // (kRescoredShifts slots per heading, `rescore_count` of them used.)
  std::vector<Ranked> to_rescore(raster ? by_heading.size() * kRescoredShifts : 0);
  std::vector<size_t> rescore_count(raster ? by_heading.size() : 0, 0);
  const auto rotate_to = [&](double dt) {
    const double c = std::cos(around.theta_rad + dt), sn = std::sin(around.theta_rad + dt);
    rotated.clear();
    for (size_t i = 0; i < points.size(); i += stride) {
      rotated.push_back(RotateBy(c, sn, points[i]) + Eigen::Vector2d(around.x_m, around.y_m));
    }
  };
  std::vector<Eigen::Vector2d> shifted;  // the rotated points, shifted
  std::vector<int> nearest;              // their nearest map points
  // A shift's score: the sum of the points' kernels (the rotated points), less the prior.
  const auto exact = [&](const Eigen::Vector2d& shift) {
    double score = 0;
    shifted.clear();
    for (const Eigen::Vector2d& q0 : rotated) shifted.push_back(q0 + shift);
    nearest.resize(shifted.size());
    map_.LookupIndices(shifted.data(), shifted.size(), reach, nearest.data());
    for (size_t i = 0; i < shifted.size(); ++i) {
      const int j = nearest[i];
      if (j >= 0) score += std::exp(-(map_.points()[static_cast<size_t>(j)] - shifted[i]).squaredNorm() * inv2s2);
    }
    return score;
  };
  const auto penalty = [&](const Eigen::Vector2d& shift, double dt) {
    const Eigen::Vector3d d(shift.x(), shift.y(), dt);
    return prior * d.dot(info * d);
  };
  const auto pose_at = [&](const Eigen::Vector2d& shift, double dt) {
    return Pose2{around.x_m + shift.x(), around.y_m + shift.y(), WrapAngle(around.theta_rad + dt)};
  };
  for (int ik = -nt; ik <= nt; ++ik) {
    const double dt = sign * ik * step;
    if (!raster) rotate_to(dt);  // (the raster moves the points itself)
    Candidate& best = by_heading[static_cast<size_t>(ik + nt)];
    best = {around, -std::numeric_limits<double>::infinity()};
    if (raster) {
      // The raster ranks the shifts; its best is the heading's candidate unless it is scored exactly below.
      std::fill(sums.begin(), sums.end(), 0.0);
      map_.AddShiftedLikelihoods(subset, std::cos(around.theta_rad + dt), std::sin(around.theta_rad + dt),
                                 Eigen::Vector2d(around.x_m, around.y_m), nxy, PointGridMap::kLikelihoodSub, sums.data());
      ranked.clear();
      for (int ia = -nxy; ia <= nxy; ++ia) {
        for (int ib = -nxy; ib <= nxy; ++ib) {
          const Eigen::Vector2d shift(sign * ia * cell, sign * ib * cell);
          const double score =
              sums[static_cast<size_t>(sign * ia + nxy) * (2 * nxy + 1) + static_cast<size_t>(sign * ib + nxy)];
          ranked.push_back({shift, score - penalty(shift, dt), ranked.size()});
        }
      }
      const size_t keep = std::min(ranked.size(), kRescoredShifts);
      std::partial_sort(ranked.begin(), ranked.begin() + static_cast<ptrdiff_t>(keep), ranked.end(),
                        [&](const Ranked& x, const Ranked& y) {
                          return x.total > y.total || (x.total == y.total && x.order < y.order);
                        });
      best = {pose_at(ranked[0].shift, dt), ranked[0].total};
      std::copy(ranked.begin(), ranked.begin() + static_cast<ptrdiff_t>(keep),
                to_rescore.begin() + static_cast<ptrdiff_t>(static_cast<size_t>(ik + nt) * kRescoredShifts));
      rescore_count[static_cast<size_t>(ik + nt)] = keep;
    } else {
      for (int ia = -nxy; ia <= nxy; ++ia) {
        for (int ib = -nxy; ib <= nxy; ++ib) {
          const Eigen::Vector2d shift(sign * ia * cell, sign * ib * cell);
          const double total = exact(shift) - penalty(shift, dt);
          if (total > best.score) best = {pose_at(shift, dt), total};  // on a tie the first one stays
        }
      }
    }
  }
  if (raster) {
    // The headings that may hold the search's best maxima: within kRescoreMargin of the raster's
    // best, and their neighbours (whether a heading is a maximum depends on them). Their shifts
    // are scored exactly; the others keep their raster score, far below.
    double top = -std::numeric_limits<double>::infinity();
    for (const Candidate& c : by_heading) top = std::max(top, c.score);
    const double cut = top - kRescoreMargin * std::max(1.0, std::abs(top));
    const int n = static_cast<int>(by_heading.size());
    std::vector<bool> rescore(by_heading.size(), false);
    for (int h = 0; h < n; ++h) {
      if (by_heading[static_cast<size_t>(h)].score < cut) continue;
      for (int k = std::max(0, h - 1); k <= std::min(n - 1, h + 1); ++k) rescore[static_cast<size_t>(k)] = true;
    }
    for (int h = 0; h < n; ++h) {
      if (!rescore[static_cast<size_t>(h)]) continue;
      const double dt = sign * (h - nt) * step;
      rotate_to(dt);
      Candidate best{around, -std::numeric_limits<double>::infinity()};
      for (size_t k = 0; k < rescore_count[static_cast<size_t>(h)]; ++k) {
        const Ranked& r = to_rescore[static_cast<size_t>(h) * kRescoredShifts + k];
        const double total = exact(r.shift) - penalty(r.shift, dt);
        if (total > best.score) best = {pose_at(r.shift, dt), total};
      }
      by_heading[static_cast<size_t>(h)] = best;
    }
  }
  if (sign < 0) std::reverse(by_heading.begin(), by_heading.end());
  return Peaks(by_heading);
}

double MapMatcher::KernelScore(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const {
  const double sigma = options_.search_sigma_m, reach = 3 * sigma, inv2s2 = 1.0 / (2 * sigma * sigma);
  double score = 0;
  std::vector<Eigen::Vector2d> world;
  std::vector<int> nearest;
  LookupAt(map_, Rigid(pose), points, stride, reach, &world, &nearest);
  for (size_t i = 0; i < world.size(); ++i) {
    const int j = nearest[i];
    if (j >= 0) score += std::exp(-(map_.points()[static_cast<size_t>(j)] - world[i]).squaredNorm() * inv2s2);
  }
  return score;
}

MapMatcher::Icp MapMatcher::RefineBest(const std::vector<Candidate>& candidates,
                                     const std::vector<Eigen::Vector2d>& points,
                                     const std::vector<Eigen::Vector2d>& normals, Pose2* start,
                                     RefineCounts* counts, std::vector<Icp>* others, const Prior* prior) const {
  Icp best;
  double best_score = -std::numeric_limits<double>::infinity();
  std::vector<Icp> results;  // every aligned start's result (with `others`)
  const size_t n = std::min(candidates.size(), static_cast<size_t>(std::max(1, options_.refine_starts)));
  for (size_t k = 0; k < n; ++k) {
    // A later start may be pruned once it is clearly worse than the best so far.
    const double prune_below =
        options_.refine_prune_iterations > 0 && best.ok && best.kernel > 0 ? options_.refine_prune_fraction * best.kernel
                                                                           : 0.0;
    Icp icp = Align(candidates[k].pose, points, normals, prune_below);
    ++counts->starts;
    counts->pruned += icp.pruned;
    if (!icp.ok) continue;
    ScoreEstimate(points, &icp);
    icp.posterior = icp.kernel - (prior ? prior->Penalty(icp.estimate) : 0.0);
    const double score = n > 1 ? icp.posterior : 0.0;
    if (others) results.push_back(icp);
    if (score > best_score) {
      best_score = score;
      best = icp;
      *start = candidates[k].pose;
    }
  }
  if (best_score == -std::numeric_limits<double>::infinity()) {  // none aligned: the first, as it is
    *start = candidates.empty() ? *start : candidates.front().pose;
    best = Align(*start, points, normals);
  }
  if (others) {
    // The results other than the best (the first of equal scores is the best, as above).
    bool skipped = false;
    for (Icp& r : results) {
      if (!skipped && r.posterior == best.posterior && r.estimate.x_m == best.estimate.x_m &&
          r.estimate.y_m == best.estimate.y_m && r.estimate.theta_rad == best.estimate.theta_rad) {
        skipped = true;
        continue;
      }
      others->push_back(std::move(r));
    }
  }
  return best;
}

void MapMatcher::ScoreEstimate(const std::vector<Eigen::Vector2d>& points, Icp* icp) const {
  const double sigma = options_.search_sigma_m, reach = 3 * sigma, inv2s2 = 1.0 / (2 * sigma * sigma);
  const double tau = options_.match_distance_m, half = 0.5 * options_.match_distance_m;
  const double limit = std::max({reach, tau, half});
  icp->scored = true;
  if (!(limit <= map_.lookup_radius_m())) {  // (the limits would take different lookups)
    icp->kernel = KernelScore(icp->estimate, points, 1);
    icp->score = Score(icp->estimate, points, 1);
    icp->fit = Fit(icp->estimate, points, 1);
    return;
  }
  // The distance tests as the lookups make them: d <= limit^2.
  const double reach2 = reach * reach, tau2 = tau * tau, half2 = half * half;
  std::vector<Eigen::Vector2d> world;
  std::vector<int> nearest;
  LookupAt(map_, Rigid(icp->estimate), points, 1, limit, &world, &nearest);
  double kernel = 0, score = 0;
  size_t near = 0;
  for (size_t i = 0; i < world.size(); ++i) {
    const int j = nearest[i];
    if (j < 0) continue;
    const double d = (map_.points()[static_cast<size_t>(j)] - world[i]).squaredNorm();
    if (d <= reach2) kernel += std::exp(-d * inv2s2);
    if (d <= tau2) score += 1.0 - d / tau2;
    if (d <= half2) ++near;
  }
  icp->kernel = kernel;
  icp->score = score;
  icp->fit = world.empty() ? 0.0 : static_cast<double>(near) / static_cast<double>(world.size());
}

double MapMatcher::Fit(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const {
  std::vector<Eigen::Vector2d> world;
  std::vector<int> nearest;
  LookupAt(map_, Rigid(pose), points, stride, 0.5 * options_.match_distance_m, &world, &nearest);
  const size_t total = world.size();
  const size_t near = static_cast<size_t>(std::count_if(nearest.begin(), nearest.end(), [](int j) { return j >= 0; }));
  return total > 0 ? static_cast<double>(near) / static_cast<double>(total) : 0.0;
}

}  // namespace snapnav::nav
