#include "snapnav/nav/slam/loop_closure.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_set>

#include "snapnav/nav/slam/cell_key.hpp"

namespace snapnav::nav {
namespace {

constexpr int kMaxCells = 4096;  // per side of the grid

}  // namespace

std::vector<Eigen::Vector2d> DecimatePoints(const std::vector<Eigen::Vector2d>& points, double cell_m) {
  std::vector<Eigen::Vector2d> out;
  if (!(cell_m > 0)) return points;
  std::unordered_set<uint64_t> taken;
  taken.reserve(points.size() * 2);
  for (const Eigen::Vector2d& p : points) {
    if (taken.insert(CellKey(p, cell_m)).second) out.push_back(p);
  }
  return out;
}

std::vector<Eigen::Vector2d> DensifyScan(const std::vector<Eigen::Vector2d>& points, double max_gap_m, double step_m) {
  std::vector<Eigen::Vector2d> out;
  if (!(step_m > 0)) return points;
  out.reserve(points.size() * 2);
  for (size_t i = 0; i < points.size(); ++i) {
    out.push_back(points[i]);
    if (i + 1 == points.size()) break;
    const Eigen::Vector2d d = points[i + 1] - points[i];
    const double gap = d.norm();
    if (gap > std::max(max_gap_m, 0.05 * points[i].norm()) || gap <= step_m) continue;
    const int n = static_cast<int>(std::floor(gap / step_m));
    for (int k = 1; k < n; ++k) out.push_back(points[i] + d * (static_cast<double>(k) / n));
  }
  return out;
}

LikelihoodPyramid::LikelihoodPyramid(const std::vector<Eigen::Vector2d>& points,
                                     const CorrelativeSearchOptions& options, double margin_m)
    : cell_(options.cell_m) {
  if (!(options.cell_m > 0) || !(options.sigma_m > 0) || options.levels < 0 || options.levels > 10) {
    throw std::invalid_argument("likelihood pyramid: cell_m and sigma_m must be > 0, levels in [0, 10]");
  }
  Eigen::Vector2d lo(0, 0), hi(0, 0);
  if (!points.empty()) {
    lo = hi = points.front();
    for (const Eigen::Vector2d& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const double reach = 3 * options.sigma_m;
  margin_m = std::max(margin_m, reach) + cell_;
  origin_ = lo - Eigen::Vector2d(margin_m, margin_m);
  width_ = std::min(kMaxCells, static_cast<int>(std::ceil((hi.x() - lo.x() + 2 * margin_m) / cell_)) + 1);
  height_ = std::min(kMaxCells, static_cast<int>(std::ceil((hi.y() - lo.y() + 2 * margin_m) / cell_)) + 1);
  // Every level is stored with pad_ cells before the grid in x and in y: a coarse cell anchored
  // left of (below) the grid still holds the maximum of the part of its block inside it.
  pad_ = (1 << options.levels) - 1;
  stride_ = width_ + pad_;
  const size_t size = static_cast<size_t>(stride_) * static_cast<size_t>(height_ + pad_);
  grids_.assign(static_cast<size_t>(options.levels) + 1, std::vector<uint8_t>());
  std::vector<uint8_t>& g = grids_[0];
  g.assign(size, 0);
  const int r = static_cast<int>(std::ceil(reach / cell_));
  const double inv2s2 = 1.0 / (2 * options.sigma_m * options.sigma_m);
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d q = (p - origin_) / cell_;
    const int cx = static_cast<int>(std::floor(q.x())), cy = static_cast<int>(std::floor(q.y()));
    for (int iy = std::max(0, cy - r); iy <= std::min(height_ - 1, cy + r); ++iy) {
      for (int ix = std::max(0, cx - r); ix <= std::min(width_ - 1, cx + r); ++ix) {
        const double dx = (ix + 0.5 - q.x()) * cell_, dy = (iy + 0.5 - q.y()) * cell_;
        const double d2 = dx * dx + dy * dy;
        if (d2 > reach * reach) continue;
        const auto v = static_cast<uint8_t>(std::lround(255.0 * std::exp(-d2 * inv2s2)));
        uint8_t& cell = g[Index(ix, iy)];
        cell = std::max(cell, v);
      }
    }
  }
  for (int k = 1; k <= options.levels; ++k) {
    const std::vector<uint8_t>& f = grids_[static_cast<size_t>(k) - 1];
    std::vector<uint8_t>& c = grids_[static_cast<size_t>(k)];
    c.assign(size, 0);
    const int h = 1 << (k - 1);
    const auto at = [&](int x, int y) -> uint8_t {
      if (x < -pad_ || y < -pad_ || x >= width_ || y >= height_) return 0;
      return f[Index(x, y)];
    };
    for (int y = -pad_; y < height_; ++y) {
      for (int x = -pad_; x < width_; ++x) {
        c[Index(x, y)] = std::max({at(x, y), at(x + h, y), at(x, y + h), at(x + h, y + h)});
      }
    }
  }
}

double LikelihoodPyramid::Score(const Pose2& pose, const std::vector<Eigen::Vector2d>& points) const {
  if (points.empty()) return 0;
  double sum = 0;
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d q = (pose.Transform(p) - origin_) / cell_ - Eigen::Vector2d(0.5, 0.5);
    const int x0 = static_cast<int>(std::floor(q.x())), y0 = static_cast<int>(std::floor(q.y()));
    const double fx = q.x() - x0, fy = q.y() - y0;
    sum += (1 - fx) * (1 - fy) * At(0, x0, y0) + fx * (1 - fy) * At(0, x0 + 1, y0) + (1 - fx) * fy * At(0, x0, y0 + 1) +
           fx * fy * At(0, x0 + 1, y0 + 1);
  }
  return sum / (255.0 * static_cast<double>(points.size()));
}

namespace {

struct Node {
  int rotation = 0, ix = 0, iy = 0, level = 0;
  double score = 0;  // mean over the points, 0-255 scale
};

class Searcher {
 public:
  Searcher(const LikelihoodPyramid& pyramid, const std::vector<Eigen::Vector2d>& points, const Pose2& around,
           double window_xy_m, double window_rad, const CorrelativeSearchOptions& options)
      : pyramid_(pyramid), options_(options) {
    wxy_ = std::max(0, static_cast<int>(std::ceil(window_xy_m / pyramid.cell_m())));
    wth_ = options.step_rad > 0 ? std::max(0, static_cast<int>(std::ceil(window_rad / options.step_rad))) : 0;
    around_ = around;
    n_ = points.size();
    cells_.resize(static_cast<size_t>(2 * wth_ + 1));
    for (int k = -wth_; k <= wth_; ++k) {
      const Pose2 p{around.x_m, around.y_m, around.theta_rad + k * options.step_rad};
      std::vector<std::pair<int, int>>& c = cells_[static_cast<size_t>(k + wth_)];
      c.reserve(points.size());
      for (const Eigen::Vector2d& q : points) {
        const Eigen::Vector2d g = (p.Transform(q) - pyramid.origin()) / pyramid.cell_m();
        c.emplace_back(static_cast<int>(std::floor(g.x())), static_cast<int>(std::floor(g.y())));
      }
    }
  }

  double Score(int rotation, int ix, int iy, int level) {
    ++scored_;
    const std::vector<std::pair<int, int>>& c = cells_[static_cast<size_t>(rotation + wth_)];
    int64_t sum = 0;
    for (const auto& [x, y] : c) sum += pyramid_.At(level, x + ix, y + iy);
    return static_cast<double>(sum) / static_cast<double>(std::max<size_t>(1, n_));
  }

  // Branch and bound: the best leaf scoring above `threshold` (0-255 scale), outside the excluded
  // zone if one is set. Returns whether one was found.
  bool Run(double threshold, Node* best) {
    const int top = pyramid_.levels();
    const int step = 1 << top;
    std::vector<Node> roots;
    for (int k = -wth_; k <= wth_; ++k) {
      for (int ix = -wxy_; ix <= wxy_; ix += step) {
        for (int iy = -wxy_; iy <= wxy_; iy += step) {
          Node n{k, ix, iy, top, 0};
          if (Excluded(n)) continue;
          n.score = Score(k, ix, iy, top);
          if (n.score > threshold) roots.push_back(n);
        }
      }
    }
    std::sort(roots.begin(), roots.end(), [](const Node& a, const Node& b) { return a.score > b.score; });
    best_score_ = threshold;
    found_ = false;
    for (const Node& n : roots) {
      if (n.score <= best_score_) break;
      Descend(n);
    }
    if (found_) *best = best_;
    return found_;
  }

  void Exclude(const Node& around, int cells, int rotations) {
    exclude_ = true;
    ex_ = around;
    ex_cells_ = cells;
    ex_rotations_ = rotations;
  }

  Pose2 PoseOf(const Node& n) const {
    return {around_.x_m + n.ix * pyramid_.cell_m(), around_.y_m + n.iy * pyramid_.cell_m(),
            WrapAngle(around_.theta_rad + n.rotation * options_.step_rad)};
  }
  int64_t scored() const { return scored_; }

 private:
  // The node's whole block lies within the excluded zone (a leaf: the leaf does).
  bool Excluded(const Node& n) const {
    if (!exclude_) return false;
    if (std::abs(n.rotation - ex_.rotation) > ex_rotations_) return false;
    const int size = (1 << n.level) - 1;
    const int x0 = n.ix, x1 = std::min(n.ix + size, wxy_), y0 = n.iy, y1 = std::min(n.iy + size, wxy_);
    return x0 >= ex_.ix - ex_cells_ && x1 <= ex_.ix + ex_cells_ && y0 >= ex_.iy - ex_cells_ && y1 <= ex_.iy + ex_cells_;
  }

  void Descend(const Node& n) {
    if (n.level == 0) {
      if (n.score > best_score_) {
        best_score_ = n.score;
        best_ = n;
        found_ = true;
      }
      return;
    }
    const int h = 1 << (n.level - 1);
    Node children[4];
    int count = 0;
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        Node c{n.rotation, n.ix + a * h, n.iy + b * h, n.level - 1, 0};
        if (c.ix > wxy_ || c.iy > wxy_) continue;
        if (Excluded(c)) continue;
        c.score = Score(c.rotation, c.ix, c.iy, c.level);
        if (c.score > best_score_) children[count++] = c;
      }
    }
    for (int i = 1; i < count; ++i) {  // (insertion sort, best first)
      for (int j = i; j > 0 && children[j].score > children[j - 1].score; --j) std::swap(children[j], children[j - 1]);
    }
    for (int i = 0; i < count; ++i) {
      if (children[i].score <= best_score_) break;
      Descend(children[i]);
    }
  }

  const LikelihoodPyramid& pyramid_;
  const CorrelativeSearchOptions& options_;
  Pose2 around_;
  int wxy_ = 0, wth_ = 0;
  size_t n_ = 0;
  std::vector<std::vector<std::pair<int, int>>> cells_;  // per rotation: each point's cell at offset 0
  int64_t scored_ = 0;
  double best_score_ = 0;
  bool found_ = false;
  Node best_;
  bool exclude_ = false;
  Node ex_;
  int ex_cells_ = 0, ex_rotations_ = 0;
};

}  // namespace

CorrelativeSearchResult BranchAndBoundSearch(const LikelihoodPyramid& pyramid, const std::vector<Eigen::Vector2d>& points,
                                             const Pose2& around, double window_xy_m, double window_rad,
                                             double min_score, const CorrelativeSearchOptions& options) {
  CorrelativeSearchResult r;
  if (points.empty()) return r;
  Searcher s(pyramid, points, around, window_xy_m, window_rad, options);
  Node best;
  if (s.Run(std::max(0.0, min_score * 255.0 - 1e-9), &best)) {
    r.found = true;
    r.pose = s.PoseOf(best);
    r.score = best.score / 255.0;
    const int cells = std::max(1, static_cast<int>(std::ceil(options.exclusion_m / pyramid.cell_m())));
    const int rotations =
        options.step_rad > 0 ? std::max(1, static_cast<int>(std::ceil(options.exclusion_rad / options.step_rad))) : 0;
    s.Exclude(best, cells, rotations);
    Node second;
    if (s.Run(options.ambiguity_floor * best.score, &second)) {
      r.second_found = true;
      r.second = s.PoseOf(second);
      r.second_score = second.score / 255.0;
    }
  }
  r.scored = s.scored();
  return r;
}

}  // namespace snapnav::nav
