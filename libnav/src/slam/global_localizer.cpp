#include "snapnav/nav/slam/global_localizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "snapnav/nav/slam/cell_key.hpp"

namespace snapnav::nav {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Felzenszwalb and Huttenlocher's squared Euclidean distance transform of one row: d[i] = min_j
// (i - j)^2 + f[j]. Cells with nothing marked hold kFar (finite: the parabolas' intersections stay
// exact in double).
constexpr double kFar = 1e10;
void Edt1d(const std::vector<double>& f, int n, std::vector<double>* d, std::vector<int>* v, std::vector<double>* z) {
  int k = 0;
  (*v)[0] = 0;
  (*z)[0] = -std::numeric_limits<double>::infinity();
  (*z)[1] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < n; ++q) {
    double s;
    while (true) {
      const int p = (*v)[k];
      s = ((f[q] + static_cast<double>(q) * q) - (f[p] + static_cast<double>(p) * p)) / (2.0 * (q - p));
      if (s <= (*z)[k] && k > 0) {
        --k;
        continue;
      }
      break;
    }
    ++k;
    (*v)[k] = q;
    (*z)[k] = s;
    (*z)[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while ((*z)[k + 1] < static_cast<double>(q)) ++k;
    const int p = (*v)[k];
    (*d)[q] = static_cast<double>(q - p) * (q - p) + f[p];
  }
}

// Squared distance (in cells^2) of every cell to the nearest marked one.
std::vector<float> SquaredDistances(const std::vector<uint8_t>& marked, int w, int h) {
  std::vector<double> grid(marked.size());
  for (size_t i = 0; i < marked.size(); ++i) grid[i] = marked[i] ? 0.0 : kFar;
  const int n = std::max(w, h);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h; ++y) f[y] = grid[static_cast<size_t>(y) * w + x];
    Edt1d(f, h, &d, &v, &z);
    for (int y = 0; y < h; ++y) grid[static_cast<size_t>(y) * w + x] = d[y];
  }
  std::vector<float> out(marked.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) f[x] = grid[static_cast<size_t>(y) * w + x];
    Edt1d(f, w, &d, &v, &z);
    for (int x = 0; x < w; ++x) out[static_cast<size_t>(y) * w + x] = static_cast<float>(std::min(d[x], kFar));
  }
  return out;
}

}  // namespace

void GlobalSearchOptions::Validate() const {
  if (!(resolution_m >= 0.01 && resolution_m <= 2)) throw std::invalid_argument("global search: resolution_m must be in [0.01, 2] m");
  if (!(heading_step_rad >= 0.1 * kPi / 180 && heading_step_rad <= 30 * kPi / 180))
    throw std::invalid_argument("global search: heading_step must be in [0.1, 30] deg");
  if (!(sigma_m > 0 && sigma_m <= 5)) throw std::invalid_argument("global search: sigma_m must be in (0, 5] m");
  if (depth < 0 || depth > 10) throw std::invalid_argument("global search: depth must be in [0, 10]");
  if (!(max_range_m > 0 && max_range_m <= 200)) throw std::invalid_argument("global search: max_range_m must be in (0, 200] m");
  if (max_points < 10 || max_points > 100000) throw std::invalid_argument("global search: max_points must be in [10, 100000]");
  if (!(free_threshold >= 0 && free_threshold < occupied_threshold && occupied_threshold <= 1))
    throw std::invalid_argument("global search: need 0 <= free_threshold < occupied_threshold <= 1");
  if (!(distinct_m > 0) || !(distinct_rad > 0)) throw std::invalid_argument("global search: distinct_m and distinct_deg must be positive");
  if (!(ambiguity_floor > 0 && ambiguity_floor < 1)) throw std::invalid_argument("global search: ambiguity_floor must be in (0, 1)");
}

GlobalLocalizer::GlobalLocalizer(const OccupancyCells& map, const GlobalSearchOptions& options) : options_(options) {
  options_.Validate();
  if (!(map.resolution_m > 0) || map.width <= 0 || map.height <= 0 ||
      map.cells.size() != static_cast<size_t>(map.width) * static_cast<size_t>(map.height)) {
    throw std::invalid_argument("global search: the map has a bad size or resolution");
  }
  const double rm = map.resolution_m, rg = options_.resolution_m;
  const int wm = map.width, hm = map.height;
  // The map's walls and free cells.
  std::vector<uint8_t> wall(map.cells.size(), 0);
  int64_t walls = 0, frees = 0;
  for (size_t i = 0; i < map.cells.size(); ++i) {
    const int8_t c = map.cells[i];
    if (c >= 100.0 * options_.occupied_threshold) wall[i] = 1, ++walls;
    else if (c >= 0 && c <= 100.0 * options_.free_threshold) ++frees;
  }
  if (walls == 0 || frees == 0) throw std::invalid_argument("global search: the map has no occupied or no free cell");
  const std::vector<float> d2 = SquaredDistances(wall, wm, hm);

  const int wc = static_cast<int>(std::ceil(wm * rm / rg)), hc = static_cast<int>(std::ceil(hm * rm / rg));
  pad_ = static_cast<int>(std::ceil(options_.max_range_m / rg)) + (1 << options_.depth) + 2;
  width_ = wc + 2 * pad_;
  height_ = hc + 2 * pad_;
  origin_x_ = map.origin_x_m - pad_ * rg;
  origin_y_ = map.origin_y_m - pad_ * rg;
  headings_ = std::max(1, static_cast<int>(std::lround(2 * kPi / options_.heading_step_rad)));
  const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  levels_.assign(static_cast<size_t>(options_.depth) + 1, std::vector<uint8_t>());
  free_.assign(static_cast<size_t>(options_.depth) + 1, std::vector<uint8_t>());
  std::vector<uint8_t>& l0 = levels_[0];
  std::vector<uint8_t> free0(n, 0);
  l0.assign(n, 0);
  // The likelihood at each search cell's centre from the distance of the nearest wall cell.
  const double inv2s2 = 1.0 / (2 * options_.sigma_m * options_.sigma_m);
  for (int y = 0; y < hc; ++y) {
    for (int x = 0; x < wc; ++x) {
      const int fx = std::min(wm - 1, static_cast<int>(((x + 0.5) * rg) / rm));
      const int fy = std::min(hm - 1, static_cast<int>(((y + 0.5) * rg) / rm));
      const double d = std::sqrt(static_cast<double>(d2[static_cast<size_t>(fy) * wm + fx])) * rm;
      const double l = d > 3 * options_.sigma_m ? 0.0 : std::exp(-d * d * inv2s2);
      l0[static_cast<size_t>(y + pad_) * width_ + (x + pad_)] = static_cast<uint8_t>(std::lround(255 * l));
    }
  }
  // A search cell is a candidate when a free map cell lies in it.
  for (int fy = 0; fy < hm; ++fy) {
    for (int fx = 0; fx < wm; ++fx) {
      const int8_t c = map.cells[static_cast<size_t>(fy) * wm + fx];
      if (c < 0 || c > 100.0 * options_.free_threshold) continue;
      const int x = std::min(wc - 1, static_cast<int>(((fx + 0.5) * rm) / rg));
      const int y = std::min(hc - 1, static_cast<int>(((fy + 0.5) * rm) / rg));
      free0[static_cast<size_t>(y + pad_) * width_ + (x + pad_)] = 1;
    }
  }
  for (const uint8_t f : free0) free_cells_ += f;
  free_[0] = std::move(free0);
  // The pyramid: each level the max over 2 x 2 windows of the one below, shifted by its half.
  for (int h = 1; h <= options_.depth; ++h) {
    const int s = 1 << (h - 1);
    const std::vector<uint8_t>& lb = levels_[h - 1];
    const std::vector<uint8_t>& fb = free_[h - 1];
    std::vector<uint8_t> lv(n, 0), fv(n, 0);
    for (int y = 0; y < height_; ++y) {
      for (int x = 0; x < width_; ++x) {
        const size_t i = static_cast<size_t>(y) * width_ + x;
        uint8_t m = lb[i], f = fb[i];
        if (x + s < width_) m = std::max(m, lb[i + s]), f |= fb[i + s];
        if (y + s < height_) {
          m = std::max(m, lb[i + static_cast<size_t>(s) * width_]), f |= fb[i + static_cast<size_t>(s) * width_];
          if (x + s < width_) m = std::max(m, lb[i + static_cast<size_t>(s) * width_ + s]), f |= fb[i + static_cast<size_t>(s) * width_ + s];
        }
        lv[i] = m;
        fv[i] = f;
      }
    }
    levels_[h] = std::move(lv);
    free_[h] = std::move(fv);
  }
}

size_t GlobalLocalizer::memory_bytes() const {
  size_t b = 0;
  for (const auto& l : levels_) b += l.size();
  for (const auto& f : free_) b += f.size();
  return b;
}

double GlobalLocalizer::Likelihood(double x_m, double y_m) const {
  const int x = static_cast<int>(std::floor((x_m - origin_x_) / options_.resolution_m));
  const int y = static_cast<int>(std::floor((y_m - origin_y_) / options_.resolution_m));
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return 0;
  return levels_[0][static_cast<size_t>(y) * width_ + x] / 255.0;
}

int GlobalLocalizer::ScoreAt(const std::vector<int>& offsets, int level, int x, int y) const {
  const uint8_t* base = levels_[static_cast<size_t>(level)].data() + static_cast<ptrdiff_t>(y) * width_ + x;
  int s = 0;
  for (const int o : offsets) s += base[o];
  return s;
}

bool GlobalLocalizer::Distinct(const Best& a, int x, int y, int heading) const {
  if (!a.found) return true;
  const double d = std::hypot(static_cast<double>(x - a.x), static_cast<double>(y - a.y)) * options_.resolution_m;
  int dh = std::abs(heading - a.heading) % headings_;
  dh = std::min(dh, headings_ - dh);
  return d > options_.distinct_m || dh * (2 * kPi / headings_) > options_.distinct_rad;
}

Pose2 GlobalLocalizer::PoseOf(int x, int y, int heading) const {
  return {origin_x_ + (x + 0.5) * options_.resolution_m, origin_y_ + (y + 0.5) * options_.resolution_m,
          WrapAngle(heading * (2 * kPi / headings_))};
}

GlobalSearchResult GlobalLocalizer::Search(const std::vector<Eigen::Vector2d>& points_robot) const {
  GlobalSearchResult result;
  const double rg = options_.resolution_m;
  // A voxel filter at the search resolution, then every k-th of what is left.
  std::vector<Eigen::Vector2d> points;
  {
    std::unordered_set<uint64_t> seen;
    const double r2 = options_.max_range_m * options_.max_range_m;
    for (const Eigen::Vector2d& p : points_robot) {
      if (!p.allFinite() || p.squaredNorm() > r2) continue;
      if (seen.insert(CellKey(p, rg)).second) points.push_back(p);
    }
    if (static_cast<int>(points.size()) > options_.max_points) {
      std::vector<Eigen::Vector2d> thinned;
      const double step = static_cast<double>(points.size()) / options_.max_points;
      for (int i = 0; i < options_.max_points; ++i) thinned.push_back(points[static_cast<size_t>(i * step)]);
      points.swap(thinned);
    }
  }
  result.points = static_cast<int>(points.size());
  if (points.size() < 3) return result;

  // Each heading's points as offsets into the grids.
  std::vector<std::vector<int>> offsets(static_cast<size_t>(headings_));
  for (int k = 0; k < headings_; ++k) {
    const double th = k * (2 * kPi / headings_), c = std::cos(th), s = std::sin(th);
    auto& o = offsets[static_cast<size_t>(k)];
    o.reserve(points.size());
    for (const Eigen::Vector2d& p : points) {
      const int dx = static_cast<int>(std::lround((c * p.x() - s * p.y()) / rg));
      const int dy = static_cast<int>(std::lround((s * p.x() + c * p.y()) / rg));
      o.push_back(dy * width_ + dx);
    }
  }

  const int depth = options_.depth;
  const int top = 1 << depth;
  std::vector<Node> roots;
  for (int k = 0; k < headings_; ++k) {
    for (int y = pad_; y < height_ - pad_; y += top) {
      for (int x = pad_; x < width_ - pad_; x += top) {
        if (!free_[static_cast<size_t>(depth)][static_cast<size_t>(y) * width_ + x]) continue;
        roots.push_back({x, y, k, depth, ScoreAt(offsets[static_cast<size_t>(k)], depth, x, y)});
        ++result.nodes;
      }
    }
  }
  const auto by_score = [](const Node& a, const Node& b) { return a.score > b.score; };
  std::sort(roots.begin(), roots.end(), by_score);

  Best best, second;
  const auto threshold = [&]() {
    int t = 0;
    if (best.found) t = static_cast<int>(options_.ambiguity_floor * best.score);
    if (second.found) t = std::max(t, second.score);
    return t;
  };
  const auto leaf = [&](const Node& n) {
    ++result.leaves;
    if (!best.found || n.score > best.score) {
      if (best.found && Distinct(best, n.x, n.y, n.heading) && (!second.found || best.score > second.score)) second = best;
      best = {true, n.x, n.y, n.heading, n.score};
      if (second.found && !Distinct(best, second.x, second.y, second.heading)) second.found = false;
    } else if (Distinct(best, n.x, n.y, n.heading) && (!second.found || n.score > second.score)) {
      second = {true, n.x, n.y, n.heading, n.score};
    }
  };
  // Depth first, the better children first (a good leaf early prunes the most).
  struct Frame {
    std::vector<Node> nodes;
    size_t next = 0;
  };
  std::vector<Frame> stack;
  stack.push_back({std::move(roots), 0});
  while (!stack.empty()) {
    Frame& f = stack.back();
    if (f.next >= f.nodes.size()) {
      stack.pop_back();
      continue;
    }
    const Node n = f.nodes[f.next++];
    if (n.score <= threshold()) {
      stack.pop_back();  // sorted: the rest of this frame scores no better
      continue;
    }
    if (n.level == 0) {
      leaf(n);
      continue;
    }
    const int level = n.level - 1, s = 1 << level;
    Frame child;
    child.nodes.reserve(4);
    for (int dy = 0; dy <= s; dy += s) {
      for (int dx = 0; dx <= s; dx += s) {
        const int x = n.x + dx, y = n.y + dy;
        if (x >= width_ - pad_ || y >= height_ - pad_) continue;
        if (!free_[static_cast<size_t>(level)][static_cast<size_t>(y) * width_ + x]) continue;
        child.nodes.push_back({x, y, n.heading, level, ScoreAt(offsets[static_cast<size_t>(n.heading)], level, x, y)});
        ++result.nodes;
      }
    }
    std::sort(child.nodes.begin(), child.nodes.end(), by_score);
    if (!child.nodes.empty()) stack.push_back(std::move(child));
  }
  if (!best.found) return result;
  const double norm = 255.0 * static_cast<double>(points.size());
  result.found = true;
  result.best = PoseOf(best.x, best.y, best.heading);
  result.score = best.score / norm;
  if (second.found) {
    result.has_second = true;
    result.second = PoseOf(second.x, second.y, second.heading);
    result.second_score = second.score / norm;
    result.ambiguity = best.score > 0 ? static_cast<double>(second.score) / best.score : 0;
  }
  return result;
}

}  // namespace snapnav::nav
