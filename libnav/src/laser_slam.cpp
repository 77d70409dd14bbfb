#include "snapnav/nav/laser_slam.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

std::optional<ScanMatcher> ParseScanMatcher(const std::string& name) {
  if (name == "heading") return ScanMatcher::kHeading;
  if (name == "correlative") return ScanMatcher::kCorrelative;
  return std::nullopt;
}

std::vector<Eigen::Vector2d> ScanNormals(const std::vector<Eigen::Vector2d>& points, int neighbours, double max_gap_m) {
  std::vector<Eigen::Vector2d> normals(points.size(), Eigen::Vector2d::Zero());
  const int n = static_cast<int>(points.size());
  for (int i = 0; i < n; ++i) {
    // Neighbours may be farther apart at long range (beams diverge): 5 % of the range.
    const double gap = std::max(max_gap_m, 0.05 * points[i].norm());
    Eigen::Vector2d sum = points[i];
    Eigen::Matrix2d outer = points[i] * points[i].transpose();
    int count = 1;
    // Walk outwards on each side while the neighbours stay close to the point.
    for (const int dir : {-1, 1}) {
      for (int k = 1; k <= neighbours; ++k) {
        const int j = i + dir * k;
        if (j < 0 || j >= n || (points[j] - points[i]).norm() > gap * k) break;
        sum += points[j];
        outer += points[j] * points[j].transpose();
        ++count;
      }
    }
    if (count < 3) continue;
    const Eigen::Vector2d mean = sum / count;
    const Eigen::Matrix2d cov = outer / count - mean * mean.transpose();
    // Closed-form eigen decomposition of the symmetric 2x2 covariance.
    const double a = cov(0, 0), b = cov(0, 1), c = cov(1, 1);
    const double half_trace = 0.5 * (a + c), det = a * c - b * b;
    const double root = std::sqrt(std::max(0.0, half_trace * half_trace - det));
    const double large = half_trace + root, small = half_trace - root;
    if (!(large > 0) || small > 0.1 * large) continue;  // not a line
    // Eigenvector of the small eigenvalue: the normal.
    const Eigen::Vector2d v = std::abs(b) > 1e-15 ? Eigen::Vector2d(b, small - a)
                                                  : (a < c ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1));
    normals[i] = v.normalized();
  }
  return normals;
}

Pose2 EkfPoseUpdate(const Pose2& pose, Eigen::Matrix3d* covariance, const Pose2& z, const Eigen::Matrix3d& r) {
  const Eigen::Matrix3d& p = *covariance;
  const Eigen::Matrix3d k = p * (p + r).inverse();
  const Eigen::Vector3d innovation(z.x_m - pose.x_m, z.y_m - pose.y_m, WrapAngle(z.theta_rad - pose.theta_rad));
  const Eigen::Vector3d dx = k * innovation;
  // Joseph form keeps the covariance symmetric and positive.
  const Eigen::Matrix3d i_k = Eigen::Matrix3d::Identity() - k;
  *covariance = i_k * p * i_k.transpose() + k * r * k.transpose();
  return {pose.x_m + dx.x(), pose.y_m + dx.y(), WrapAngle(pose.theta_rad + dx.z())};
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

// floor(v) as an integer, without the library call (the lookup's hot path).
int64_t FloorToInt(double v) {
  const auto i = static_cast<int64_t>(v);
  return i - (static_cast<double>(i) > v);
}

}  // namespace

PointGridMap::PointGridMap(double resolution_m, double bucket_m, double lookup_radius_m, double lookup_cell_m,
                           double likelihood_sigma_m)
    : resolution_(resolution_m),
      bucket_(bucket_m),
      lookup_radius_(lookup_radius_m),
      lookup_cell_(lookup_cell_m),
      likelihood_sigma_(likelihood_sigma_m),
      node_(lookup_cell_m / kLikelihoodSub),
      inv_lookup_cell_(1.0 / lookup_cell_m) {
  if (!(resolution_m > 0) || !(bucket_m > 0)) throw std::invalid_argument("point map: cell sizes must be > 0");
  if (!(lookup_radius_m >= 0) || !(lookup_cell_m > 0)) {
    throw std::invalid_argument("point map: lookup radius must be >= 0 and its cell > 0");
  }
  if (!(likelihood_sigma_m >= 0)) throw std::invalid_argument("point map: likelihood sigma must be >= 0 (0: none)");
  if (has_likelihood()) {
    // The raster's byte of exp(-x), x = d^2 / (2 sigma^2) in [0, 4.5] (d within 3 sigma), by bins of
    // x: where no rounding boundary (255 exp(-x) = k + 1/2) lies within 1e-9 of a bin, its byte;
    // elsewhere -1 (computed).
    kernel_bytes_.assign(kKernelBins, -1);
    const double width = kKernelMaxX / kKernelBins;
    size_t k = 0;  // boundaries by increasing x: x_k = ln(255 / (k + 1/2)), k from 254 down
    std::vector<double> bounds;
    for (int v = 254; v >= 0; --v) bounds.push_back(std::log(255.0 / (v + 0.5)));
    for (int b = 0; b < kKernelBins; ++b) {
      const double lo = b * width - 1e-9, hi = (b + 1) * width + 1e-9;
      while (k < bounds.size() && bounds[k] < lo) ++k;
      if (k < bounds.size() && bounds[k] <= hi) continue;
      kernel_bytes_[static_cast<size_t>(b)] =
          static_cast<int16_t>(std::lround(255 * std::exp(-(b + 0.5) * width)));
    }
  }
}

bool PointGridMap::Add(const Eigen::Vector2d& p, const Eigen::Vector2d& normal) {
  const uint64_t fine = Key(FloorToInt(p.x() / resolution_), FloorToInt(p.y() / resolution_));
  // (Mostly the cell is taken: one probe of an open-addressing table.)
  const auto index = static_cast<uint32_t>(points_.size());
  if (cells_.FindOrAdd(fine, index) != index) return false;
  buckets_[Key(FloorToInt(p.x() / bucket_), FloorToInt(p.y() / bucket_))].push_back(index);
  if (lookup_radius_ > 0) AddToLookup(p, index);
  if (has_likelihood()) AddToLikelihood(p);
  points_.push_back(p);
  normals_.push_back(normal);
  return true;
}

uint32_t PointGridMap::TileTable::FindOrAdd(uint64_t key, uint32_t value) {
  if (2 * (count + 1) > values.size()) {  // keep it at most half full
    std::vector<uint64_t> old_keys = std::move(keys);
    std::vector<uint32_t> old_values = std::move(values);
    bits = std::max(6, bits + 1);
    keys.assign(size_t{1} << bits, 0);
    values.assign(size_t{1} << bits, kNone);
    count = 0;
    for (size_t i = 0; i < old_values.size(); ++i) {
      if (old_values[i] != kNone) FindOrAdd(old_keys[i], old_values[i]);
    }
  }
  const size_t mask = values.size() - 1;
  size_t i = Slot(key);
  for (; values[i] != kNone; i = (i + 1) & mask) {
    if (keys[i] == key) return values[i];
  }
  keys[i] = key;
  values[i] = value;
  ++count;
  return value;
}

PointGridMap::Tile* PointGridMap::TileAt(int64_t tx, int64_t ty) {
  const uint32_t slot = tile_index_.FindOrAdd(Key(tx, ty), static_cast<uint32_t>(tiles_.size()));
  if (slot == tiles_.size()) {
    tiles_.tiles.push_back(std::make_unique<Tile>());  // (not zeroed)
    Tile& t = *tiles_.tiles.back();
    std::fill(&t.index[0][0], &t.index[0][0] + kTile * kTile * kLookupCandidates, kNone);
    std::fill(&t.d2[0][0], &t.d2[0][0] + kTile * kTile * kLookupCandidates, std::numeric_limits<float>::infinity());
  }
  return &tiles_[slot];
}

PointGridMap::RasterTile* PointGridMap::RasterAt(int64_t tx, int64_t ty) {
  const uint32_t slot = raster_index_.FindOrAdd(Key(tx, ty), static_cast<uint32_t>(rasters_.size()));
  if (slot == rasters_.size()) {
    rasters_.tiles.push_back(std::make_unique<RasterTile>());  // value-initialised: zeros
  }
  return &rasters_[slot];
}

void PointGridMap::AddToLookup(const Eigen::Vector2d& p, uint32_t index) {
  // Every cell whose centre lies within the radius (plus half a cell diagonal, so that a query
  // anywhere in the cell within the radius of p finds a point) may now have p as its nearest.
  const double reach = lookup_radius_ + 0.7072 * lookup_cell_;
  const double reach2 = reach * reach;
  const int64_t x0 = static_cast<int64_t>(std::floor((p.x() - reach) / lookup_cell_));
  const int64_t x1 = static_cast<int64_t>(std::floor((p.x() + reach) / lookup_cell_));
  const int64_t y0 = static_cast<int64_t>(std::floor((p.y() - reach) / lookup_cell_));
  const int64_t y1 = static_cast<int64_t>(std::floor((p.y() + reach) / lookup_cell_));
  // Each column's dx^2 once, for every row (the same arithmetic as per cell).
  thread_local std::vector<double> dx2;
  dx2.resize(static_cast<size_t>(x1 - x0 + 1));
  for (int64_t cx = x0; cx <= x1; ++cx) {
    const double dx = (static_cast<double>(cx) + 0.5) * lookup_cell_ - p.x();
    dx2[static_cast<size_t>(cx - x0)] = dx * dx;
  }
  const double* dx2_at = dx2.data() - x0;  // by cx
  for (int64_t tx = x0 >> kTileBits; tx <= x1 >> kTileBits; ++tx) {
    for (int64_t ty = y0 >> kTileBits; ty <= y1 >> kTileBits; ++ty) {
      Tile* tile = TileAt(tx, ty);
      const int64_t cx0 = std::max(x0, tx << kTileBits), cx1 = std::min(x1, ((tx + 1) << kTileBits) - 1);
      const int64_t cy0 = std::max(y0, ty << kTileBits), cy1 = std::min(y1, ((ty + 1) << kTileBits) - 1);
      for (int64_t cy = cy0; cy <= cy1; ++cy) {
        const double dy = (static_cast<double>(cy) + 0.5) * lookup_cell_ - p.y();
        const double dy2 = dy * dy;
        if (dy2 > reach2) continue;  // every cell of the row is farther
        // The row's cells within reach, |dx| <= sqrt(reach2 - dy2), and one more on each side
        // against rounding (the test below decides).
        const double half = std::sqrt(reach2 - dy2) / lookup_cell_, centre = p.x() / lookup_cell_ - 0.5;
        const int64_t lo = std::max(cx0, static_cast<int64_t>(std::floor(centre - half)) - 1);
        const int64_t hi = std::min(cx1, static_cast<int64_t>(std::floor(centre + half)) + 1);
        const int row = static_cast<int>(cy - (ty << kTileBits)) << kTileBits;
        for (int64_t cx = lo; cx <= hi; ++cx) {
          const double d2 = dx2_at[cx] + dy2;
          if (d2 > reach2) continue;
          const int c = row + static_cast<int>(cx - (tx << kTileBits));
          // Insert into the cell's candidates, nearest first (mostly it is farther than all three).
          float* dist = tile->d2[c];
          const float f = static_cast<float>(d2);
          if (!(f < dist[kLookupCandidates - 1])) continue;
          uint32_t* idx = tile->index[c];
          int k = kLookupCandidates - 1;
          while (k > 0 && f < dist[k - 1]) --k;
          for (int j = kLookupCandidates - 1; j > k; --j) {
            dist[j] = dist[j - 1];
            idx[j] = idx[j - 1];
          }
          dist[k] = static_cast<float>(d2);
          idx[k] = index;
        }
      }
    }
  }
}

void PointGridMap::AddToLikelihood(const Eigen::Vector2d& p) {
  const double reach = 3 * likelihood_sigma_, reach2 = reach * reach;
  const double inv2s2 = 1.0 / (2 * likelihood_sigma_ * likelihood_sigma_);
  // Nodes sit at the centres of cells of node_: node i at (i + 0.5) node_.
  const int64_t x0 = FloorToInt((p.x() - reach) / node_), x1 = FloorToInt((p.x() + reach) / node_);
  const int64_t y0 = FloorToInt((p.y() - reach) / node_), y1 = FloorToInt((p.y() + reach) / node_);
  // The box's bytes (0 beyond reach: a node within it is at least 255 exp(-4.5), 3), computed once.
  const int nx = static_cast<int>(x1 - x0 + 1), ny = static_cast<int>(y1 - y0 + 1);
  thread_local std::vector<uint8_t> bytes;
  bytes.assign(static_cast<size_t>(nx) * ny, 0);
  for (int64_t iy = y0; iy <= y1; ++iy) {
    const double dy = (static_cast<double>(iy) + 0.5) * node_ - p.y();
    uint8_t* out = bytes.data() + (iy - y0) * nx;
    for (int64_t ix = x0; ix <= x1; ++ix) {
      const double dx = (static_cast<double>(ix) + 0.5) * node_ - p.x();
      const double d2 = dx * dx + dy * dy;
      if (d2 > reach2) continue;
      const double x = d2 * inv2s2;
      const int bin = static_cast<int>(x * (kKernelBins / kKernelMaxX));
      const int16_t byte = bin < kKernelBins ? kernel_bytes_[static_cast<size_t>(bin)] : int16_t{-1};
      out[ix - x0] = byte >= 0 ? static_cast<uint8_t>(byte) : static_cast<uint8_t>(std::lround(255 * std::exp(-x)));
    }
  }
  // Into every tile whose nodes or apron (kRasterRow nodes from its origin) meet the box: the same
  // value in each copy of a node.
  for (int64_t tx = (x0 - kRasterApron) >> kNodeBits; tx <= x1 >> kNodeBits; ++tx) {
    for (int64_t ty = (y0 - kRasterApron) >> kNodeBits; ty <= y1 >> kNodeBits; ++ty) {
      RasterTile& raster = *RasterAt(tx, ty);
      const int64_t ox = tx << kNodeBits, oy = ty << kNodeBits;  // its first node
      const int64_t ix0 = std::max(x0, ox), ix1 = std::min(x1, ox + kRasterRow - 1);
      const int64_t iy0 = std::max(y0, oy), iy1 = std::min(y1, oy + kRasterRow - 1);
      for (int64_t iy = iy0; iy <= iy1; ++iy) {
        uint8_t* row = raster.node + static_cast<ptrdiff_t>(iy - oy) * kRasterRow - ox;
        const uint8_t* in = bytes.data() + (iy - y0) * nx - x0;
        for (int64_t ix = ix0; ix <= ix1; ++ix) row[ix] = std::max(row[ix], in[ix]);
      }
    }
  }
}

float PointGridMap::Node(int64_t ix, int64_t iy) const {
  const uint32_t tile = raster_index_.Find(Key(ix >> kNodeBits, iy >> kNodeBits));
  if (tile == kNone) return 0.0f;
  return rasters_[tile].node[(iy & (kNodes - 1)) * kRasterRow + (ix & (kNodes - 1))];
}

double PointGridMap::Likelihood(const Eigen::Vector2d& p) const {
  if (!has_likelihood()) return 0.0;
  const double u = p.x() / node_ - 0.5, v = p.y() / node_ - 0.5;
  const int64_t i = FloorToInt(u), j = FloorToInt(v);
  const double fx = u - static_cast<double>(i), fy = v - static_cast<double>(j);
  return ((1 - fy) * ((1 - fx) * Node(i, j) + fx * Node(i + 1, j)) +
          fy * ((1 - fx) * Node(i, j + 1) + fx * Node(i + 1, j + 1))) /
         255.0;
}

namespace {

// Adds to acc[a * shifts + b] the bilinear interpolation, with the weights w.., of the nodes at
// base + a * step + b * step * row_stride (shifts x shifts of them). SHIFTS > 0: known at compile
// time (the loops unrolled); 0: `shifts`.
template <int SHIFTS>
inline void AccumulateShifts(const uint8_t* base, int row_stride, int step, int shifts, float w00, float w10,
                             float w01, float w11, float* acc) {
  const int count = SHIFTS > 0 ? SHIFTS : shifts;
  for (int a = 0; a < count; ++a) {
    const uint8_t* col = base + a * step;
    float* out = acc + a * count;
    for (int b = 0; b < count; ++b) {
      const uint8_t* q = col + b * step * row_stride;
      out[b] += w00 * q[0] + w10 * q[1] + w01 * q[row_stride] + w11 * q[row_stride + 1];
    }
  }
}

#if defined(__SSE2__)
struct Lanes {  // 4 floats (a struct: a vector of __m128 would drop its alignment attribute)
  __m128 v;
};

// The same sums, for shifts of 2 nodes (PointGridMap::kLikelihoodSub), 4 x-shifts a at a time
// (SSE2): acc[b * groups + g] holds a = 4 g .. 4 g + 3 (lanes past `shifts` unused). Each shift's
// sum takes the same float operations in the same order as AccumulateShifts: the same bits. Reads
// up to 6 nodes past the block's last row (the raster tiles and the copied block are padded).
template <int SHIFTS>
inline void AccumulateShiftsStep2(const uint8_t* base, int row_stride, int shifts, __m128 w00, __m128 w10,
                                  __m128 w01, __m128 w11, Lanes* acc) {
  const int count = SHIFTS > 0 ? SHIFTS : shifts;
  const int groups = (count + 3) / 4;
  const __m128i zero = _mm_setzero_si128(), low = _mm_set1_epi32(0xffff);
  for (int b = 0; b < count; ++b) {
    const uint8_t* row0 = base + 2 * b * row_stride;
    const uint8_t* row1 = row0 + row_stride;
    for (int g = 0; g < groups; ++g) {
      // 8 nodes of each row as 16-bit lanes; even nodes (x = 2 a) and odd ones (2 a + 1) as floats.
      const __m128i v0 = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(row0 + 8 * g)), zero);
      const __m128i v1 = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(row1 + 8 * g)), zero);
      const __m128 e0 = _mm_cvtepi32_ps(_mm_and_si128(v0, low)), o0 = _mm_cvtepi32_ps(_mm_srli_epi32(v0, 16));
      const __m128 e1 = _mm_cvtepi32_ps(_mm_and_si128(v1, low)), o1 = _mm_cvtepi32_ps(_mm_srli_epi32(v1, 16));
      const __m128 v = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(w00, e0), _mm_mul_ps(w10, o0)), _mm_mul_ps(w01, e1)),
                                  _mm_mul_ps(w11, o1));
      acc[b * groups + g].v = _mm_add_ps(acc[b * groups + g].v, v);
    }
  }
}

// AccumulateShiftsStep2 with the window's size known at compile time where it is common.
inline void AccumulateShiftsStep2Any(const uint8_t* base, int row_stride, int shifts, __m128 w00, __m128 w10,
                                     __m128 w01, __m128 w11, Lanes* acc) {
  switch (shifts) {
    case 3:
      AccumulateShiftsStep2<3>(base, row_stride, shifts, w00, w10, w01, w11, acc);
      break;
    case 5:
      AccumulateShiftsStep2<5>(base, row_stride, shifts, w00, w10, w01, w11, acc);
      break;
    default:
      AccumulateShiftsStep2<0>(base, row_stride, shifts, w00, w10, w01, w11, acc);
  }
}
#endif

}  // namespace

void PointGridMap::AddShiftedLikelihoods(const std::vector<Eigen::Vector2d>& points, int n, int step_nodes,
                                         double* sums) const {
  AddShiftedLikelihoods(points, 1.0, 0.0, Eigen::Vector2d::Zero(), n, step_nodes, sums);  // (x 1 - y 0 + 0: x)
}

void PointGridMap::AddShiftedLikelihoods(const std::vector<Eigen::Vector2d>& moving, double c, double s,
                                         const Eigen::Vector2d& t, int n, int step_nodes, double* sums) const {
  if (!has_likelihood()) throw std::logic_error("point map: no likelihood raster");
  const int shifts = 2 * n + 1;
  // The nodes any shift of a point interpolates between: a block of w x w from (i - n s, j - n s).
  const int w = 2 * n * step_nodes + 2;
  const int64_t mask = kNodes - 1;
  const double inv_node = 1.0 / node_;
  // The raster tile of a tile key (nullptr: none), the last one remembered.
  uint64_t cached_key = 0;
  const uint8_t* cached_nodes = nullptr;
  bool cached = false;
  const auto nodes_of = [&](int64_t tx, int64_t ty) {
    const uint64_t key = Key(tx, ty);
    if (!cached || key != cached_key) {
      cached_key = key;
      const uint32_t tile = raster_index_.Find(key);
      cached_nodes = tile == kNone ? nullptr : rasters_[tile].node;
      cached = true;
    }
    return cached_nodes;
  };
  // The block, where it spans tiles; its rows bw apart, 8 nodes or more longer than the block (for
  // the copies of 8 nodes at a time below).
  const int bw = ((w + 7) & ~7) + 8;
  // (Called for every heading of every scan's search: the buffers are kept, zeroed each call as needed.)
  thread_local std::vector<uint8_t> block;
  const int cells = shifts * shifts;
  thread_local std::vector<float> acc;  // per shift, in units of 1/255
  acc.assign(static_cast<size_t>(cells), 0.0f);
#if defined(__SSE2__)
  const bool simd = step_nodes == 2;
  const int groups = (shifts + 3) / 4;
  thread_local std::vector<Lanes> acc4;
  acc4.assign(simd ? static_cast<size_t>(groups * shifts) : 0, Lanes{_mm_setzero_ps()});
  const int read_x = simd ? std::max(w, 8 * groups) : w;  // nodes of a block row read (SSE2: 8 at a time)
#else
  const int read_x = w;
#endif
  // Whether a block is read in place: it fits in the apron of the tile it starts in.
  const bool in_place = read_x <= kRasterApron && w <= kRasterApron;
  if (!in_place) block.assign(static_cast<size_t>(bw) * w + kRasterPadding, 0);
#if defined(__SSE2__)
  const bool fast = simd && in_place;
  if (fast) {
    // The common case, each point's interpolation set up with SSE2: the same operations as the
    // loop below (FloorToInt by truncation to 32 bits: points within 50,000 km).
    const __m128d inv2 = _mm_set1_pd(inv_node), half2 = _mm_set1_pd(0.5), one2 = _mm_set1_pd(1.0);
    const __m128 one4 = _mm_set1_ps(1.0f);
    const int64_t back = static_cast<int64_t>(n) * step_nodes;
    // The moved point (c x - s y + tx, s x + c y + ty) as (c x + (-s) y, c y + s x) + t: the same bits.
    const __m128d cc = _mm_set1_pd(c), ms = _mm_set_pd(s, -s), tt = _mm_loadu_pd(t.data());
    for (const Eigen::Vector2d& q : moving) {
      const __m128d xy = _mm_loadu_pd(q.data());
      const __m128d p = _mm_add_pd(_mm_add_pd(_mm_mul_pd(xy, cc), _mm_mul_pd(_mm_shuffle_pd(xy, xy, 1), ms)), tt);
      const __m128d uv = _mm_sub_pd(_mm_mul_pd(p, inv2), half2);  // (u, v)
      const __m128i truncated = _mm_cvttpd_epi32(uv);
      const __m128d tf = _mm_cvtepi32_pd(truncated);
      const __m128d above = _mm_cmpgt_pd(tf, uv);  // truncated up: the floor is one less
      const __m128d fl = _mm_sub_pd(tf, _mm_and_pd(above, one2));
      const int down = _mm_movemask_pd(above);
      const int64_t i = _mm_cvtsi128_si32(truncated) - (down & 1);
      const int64_t j = _mm_cvtsi128_si32(_mm_shuffle_epi32(truncated, 1)) - (down >> 1);
      const uint8_t* nodes = nodes_of((i - back) >> kNodeBits, (j - back) >> kNodeBits);
      if (!nodes) continue;  // no map point within reach of any shift
      const uint8_t* base = nodes + ((j - back) & mask) * kRasterRow + ((i - back) & mask);
      // (fx, fy) and the bilinear weights (1-fx)(1-fy), fx(1-fy), (1-fx)fy, fx fy in floats.
      const __m128 f = _mm_cvtpd_ps(_mm_sub_pd(uv, fl));
      const __m128 pairs = _mm_unpacklo_ps(_mm_sub_ps(one4, f), f);  // (1-fx, fx, 1-fy, fy)
      const __m128 weights = _mm_mul_ps(_mm_movelh_ps(pairs, pairs), _mm_shuffle_ps(pairs, pairs, _MM_SHUFFLE(3, 3, 2, 2)));
      const __m128 v00 = _mm_shuffle_ps(weights, weights, 0x00), v10 = _mm_shuffle_ps(weights, weights, 0x55);
      const __m128 v01 = _mm_shuffle_ps(weights, weights, 0xAA), v11 = _mm_shuffle_ps(weights, weights, 0xFF);
      AccumulateShiftsStep2Any(base, kRasterRow, shifts, v00, v10, v01, v11, acc4.data());
    }
  }
#else
  const bool fast = false;
#endif
  for (const Eigen::Vector2d& q : moving) {
    if (fast) break;  // (done above)
    const Eigen::Vector2d p = Eigen::Vector2d(c * q.x() - s * q.y(), s * q.x() + c * q.y()) + t;
    const double u = p.x() * inv_node - 0.5, v = p.y() * inv_node - 0.5;
    const int64_t i = FloorToInt(u), j = FloorToInt(v);
    const float fx = static_cast<float>(u - static_cast<double>(i)), fy = static_cast<float>(v - static_cast<double>(j));
    const int64_t lx = i - static_cast<int64_t>(n) * step_nodes, ly = j - static_cast<int64_t>(n) * step_nodes;
    const int64_t hx = lx + w - 1, hy = ly + w - 1;
    const int64_t tx0 = lx >> kNodeBits, tx1 = hx >> kNodeBits, ty0 = ly >> kNodeBits, ty1 = hy >> kNodeBits;
    const uint8_t* base;  // the block's first node
    int row_stride;     // nodes from one block row to the next
    if (in_place || (tx0 == tx1 && ty0 == ty1)) {
      // The tile the block starts in holds it (with its apron): read it in place.
      const uint8_t* nodes = nodes_of(tx0, ty0);
      if (!nodes) continue;  // no map point within reach of any shift
      base = nodes + (ly & mask) * kRasterRow + (lx & mask);
      row_stride = kRasterRow;
    } else {
      // A block wider than the apron that spans 2 or 4 tiles: copied together, row pieces of each
      // tile (zeros where there is none).
      bool any = false;
      for (int64_t ty = ty0; ty <= ty1; ++ty) {
        const int64_t y0 = std::max(ly, ty << kNodeBits), y1 = std::min(hy, ((ty + 1) << kNodeBits) - 1);
        for (int64_t tx = tx0; tx <= tx1; ++tx) {
          const int64_t x0 = std::max(lx, tx << kNodeBits), x1 = std::min(hx, ((tx + 1) << kNodeBits) - 1);
          const size_t len = static_cast<size_t>(x1 - x0 + 1);
          const uint8_t* nodes = nodes_of(tx, ty);
          any = any || nodes;
          for (int64_t iy = y0; iy <= y1; ++iy) {
            // 8 nodes at a time: a piece may write (and read) up to 7 nodes past its end, into the
            // next piece of the row (copied after it) or the row's slack (and the tile's apron).
            uint8_t* to = block.data() + (iy - ly) * bw + (x0 - lx);
            const uint8_t* from = nodes ? nodes + (iy & mask) * kRasterRow + (x0 & mask) : nullptr;
            for (size_t k = 0; k < len; k += 8) {
              uint64_t eight = 0;
              if (from) std::memcpy(&eight, from + k, 8);
              std::memcpy(to + k, &eight, 8);
            }
          }
        }
      }
      if (!any) continue;
      base = block.data();
      row_stride = bw;
    }
    // Bilinear weights, the same for every shift.
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
#if defined(__SSE2__)
    if (simd) {
      const __m128 v00 = _mm_set1_ps(w00), v10 = _mm_set1_ps(w10), v01 = _mm_set1_ps(w01), v11 = _mm_set1_ps(w11);
      AccumulateShiftsStep2Any(base, row_stride, shifts, v00, v10, v01, v11, acc4.data());
      continue;
    }
#endif
    switch (shifts) {
      case 3:
        AccumulateShifts<3>(base, row_stride, step_nodes, shifts, w00, w10, w01, w11, acc.data());
        break;
      case 5:
        AccumulateShifts<5>(base, row_stride, step_nodes, shifts, w00, w10, w01, w11, acc.data());
        break;
      default:
        AccumulateShifts<0>(base, row_stride, step_nodes, shifts, w00, w10, w01, w11, acc.data());
    }
  }
#if defined(__SSE2__)
  if (simd) {
    for (int b = 0; b < shifts; ++b) {
      for (int g = 0; g < groups; ++g) {
        alignas(16) float lanes[4];
        _mm_store_ps(lanes, acc4[static_cast<size_t>(b * groups + g)].v);
        for (int l = 0; l < 4 && 4 * g + l < shifts; ++l) acc[static_cast<size_t>((4 * g + l) * shifts + b)] = lanes[l];
      }
    }
  }
#endif
  for (int c = 0; c < cells; ++c) sums[c] += acc[static_cast<size_t>(c)] / 255.0;
}

void PointGridMap::LookupIndices(const Eigen::Vector2d* q, size_t n, double max_distance_m, int* out) const {
  if (!(max_distance_m <= lookup_radius_)) {
    for (size_t i = 0; i < n; ++i) out[i] = NearestIndex(q[i], max_distance_m);
    return;
  }
  // Each point's cell candidates (nullptr: no tile) are located, and prefetched, kAhead points
  // before they are resolved (the memory reads overlap); the tile of the last point remembered.
  constexpr size_t kAhead = 8;
  const uint32_t* ahead[kAhead];
  uint64_t cached_key = 0;
  const Tile* cached_tile = nullptr;
  bool cached = false;
  const auto locate = [&](const Eigen::Vector2d& p) -> const uint32_t* {
    const int64_t cx = FloorToInt(p.x() * inv_lookup_cell_);
    const int64_t cy = FloorToInt(p.y() * inv_lookup_cell_);
    const uint64_t key = Key(cx >> kTileBits, cy >> kTileBits);
    if (!cached || key != cached_key) {
      cached_key = key;
      const uint32_t tile = tile_index_.Find(key);
      cached_tile = tile == kNone ? nullptr : &tiles_[tile];
      cached = true;
    }
    if (!cached_tile) return nullptr;
    const uint32_t* cell = cached_tile->index[((cy & (kTile - 1)) << kTileBits) | (cx & (kTile - 1))];
    __builtin_prefetch(cell);
    return cell;
  };
  for (size_t i = 0; i < std::min(n, kAhead); ++i) ahead[i] = locate(q[i]);
  // The nearest of each cell's candidates, as LookupIndex takes it.
  const double limit = max_distance_m * max_distance_m;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t* candidates = ahead[i % kAhead];
    if (i + kAhead < n) ahead[i % kAhead] = locate(q[i + kAhead]);
    int found = -1;
    if (candidates) {
      double best = limit;
      for (int k = 0; k < kLookupCandidates && candidates[k] != kNone; ++k) {
        const double d = (points_[candidates[k]] - q[i]).squaredNorm();
        if (d <= best) {
          best = d;
          found = static_cast<int>(candidates[k]);
        }
      }
    }
    out[i] = found;
  }
}

int PointGridMap::NearestIndex(const Eigen::Vector2d& p, double max_distance_m) const {
  const int64_t bx = static_cast<int64_t>(std::floor(p.x() / bucket_));
  const int64_t by = static_cast<int64_t>(std::floor(p.y() / bucket_));
  const int64_t reach = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(max_distance_m / bucket_)));
  double best = max_distance_m * max_distance_m;
  int found = -1;
  for (int64_t dx = -reach; dx <= reach; ++dx) {
    for (int64_t dy = -reach; dy <= reach; ++dy) {
      const auto it = buckets_.find(Key(bx + dx, by + dy));
      if (it == buckets_.end()) continue;
      for (const uint32_t i : it->second) {
        const double d = (points_[i] - p).squaredNorm();
        if (d < best) {
          best = d;
          found = static_cast<int>(i);
        }
      }
    }
  }
  return found;
}

std::optional<Eigen::Vector2d> PointGridMap::Nearest(const Eigen::Vector2d& p, double max_distance_m) const {
  const int i = NearestIndex(p, max_distance_m);
  if (i < 0) return std::nullopt;
  return points_[static_cast<size_t>(i)];
}

void LaserSlamOptions::Validate() const {
  motion.Validate();
  if (!(initial_sigma_xy_m >= 0) || !(initial_sigma_theta_rad >= 0)) throw std::invalid_argument("laser slam: initial sigmas must be >= 0");
  if (!(match_distance_m > 0)) throw std::invalid_argument("laser slam: match_distance_m must be > 0");
  if (!(match_distance_start_m >= match_distance_m)) {
    throw std::invalid_argument("laser slam: match_distance_start_m must be >= match_distance_m");
  }
  if (!(robust_scale_m > 0)) throw std::invalid_argument("laser slam: robust_scale_m must be > 0");
  if (!(max_range_m >= 0)) throw std::invalid_argument("laser slam: max_range_m must be >= 0 (0: no limit)");
  if (!(recovery_fit >= 0 && recovery_fit <= 1)) throw std::invalid_argument("laser slam: recovery_fit must be in [0, 1]");
  if (!(search_sigmas >= 0) || !(search_window_max_rad >= 0) || !(search_step_rad > 0)) {
    throw std::invalid_argument("laser slam: search_sigmas and search_window_max must be >= 0, search_step > 0");
  }
  if (icp_iterations < 1) throw std::invalid_argument("laser slam: icp_iterations must be >= 1");
  if (!(point_sigma_m > 0)) throw std::invalid_argument("laser slam: point_sigma_m must be > 0");
  if (min_matches < 3) throw std::invalid_argument("laser slam: min_matches must be >= 3");
  if (!(map_resolution_m > 0) || !(add_distance_m > 0)) throw std::invalid_argument("laser slam: map sizes must be > 0");
  if (scan_step < 1) throw std::invalid_argument("laser slam: scan_step must be >= 1");
  if (!(update_score_margin >= 0 && update_score_margin < 1)) {
    throw std::invalid_argument("laser slam: update_score_margin must be in [0, 1)");
  }
  if (!(turn_noise_rad_per_rad >= 0)) throw std::invalid_argument("laser slam: turn_noise_rad_per_rad must be >= 0");
  if (!(lookup_cell_m >= 0)) throw std::invalid_argument("laser slam: lookup_cell_m must be >= 0 (0: exact search)");
  if (!(search_window_xy_m >= 0)) throw std::invalid_argument("laser slam: search_window_xy_m must be >= 0");
  if (!(search_sigma_m > 0) || !(3 * search_sigma_m <= std::max(match_distance_start_m, add_distance_m))) {
    throw std::invalid_argument("laser slam: search_sigma_m must be > 0 and at most match_distance_start_m / 3");
  }
  if (!(scan_latency_s >= 0 && scan_latency_s <= 10))
    throw std::invalid_argument("laser slam: scan_latency_s must be in [0, 10]");
  if (!(stale_fraction >= 0 && stale_fraction <= 1))
    throw std::invalid_argument("laser slam: stale_fraction must be in [0, 1]");
  if (refine_starts < 1) throw std::invalid_argument("laser slam: refine_starts must be >= 1");
  if (refine_prune_iterations < 0) throw std::invalid_argument("laser slam: refine_prune_iterations must be >= 0");
  if (!(refine_prune_fraction > 0 && refine_prune_fraction <= 1)) {
    throw std::invalid_argument("laser slam: refine_prune_fraction must be in (0, 1]");
  }
  if (!(search_prior_weight >= 0)) throw std::invalid_argument("laser slam: search_prior_weight must be >= 0");
}

LaserSlam::LaserSlam(const LaserSlamOptions& options, const Pose2& start)
    : options_(options),
      pose_(start),
      map_(options.map_resolution_m, std::max(0.25, options.match_distance_m),
           options.lookup_cell_m > 0 ? std::max(options.match_distance_start_m, options.add_distance_m) : 0,
           options.lookup_cell_m > 0 ? options.lookup_cell_m : 1.0,
           options.matcher == ScanMatcher::kCorrelative && options.lookup_cell_m > 0 ? options.search_sigma_m : 0) {
  options_.Validate();
  covariance_ = Eigen::Vector3d(options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_xy_m * options.initial_sigma_xy_m,
                                options.initial_sigma_theta_rad * options.initial_sigma_theta_rad)
                    .asDiagonal();
}

void LaserSlam::Predict(const Pose2& odometry_delta) {
  PredictWithOdometry(options_.motion, odometry_delta, &pose_, &covariance_);
  odometry_since_scan_ = odometry_since_scan_.Compose(odometry_delta);
}

namespace {

// The correlative search scores this many of a heading's shifts exactly (the best on the raster).
constexpr size_t kRescoredShifts = 2;
// ... for the headings whose best raster score is within this fraction of the search's best.
constexpr double kRescoreMargin = 0.25;

Eigen::Vector2d Rotate(double c, double s, const Eigen::Vector2d& v) { return {c * v.x() - s * v.y(), s * v.x() + c * v.y()}; }

// A pose as a rotation and translation, its sine and cosine computed once for many points.
struct Rigid {
  explicit Rigid(const Pose2& p) : c(std::cos(p.theta_rad)), s(std::sin(p.theta_rad)), t(p.x_m, p.y_m) {}
  Eigen::Vector2d operator()(const Eigen::Vector2d& v) const { return Rotate(c, s, v) + t; }
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

LaserSlam::Icp LaserSlam::Align(const Pose2& start, const std::vector<Eigen::Vector2d>& points,
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
      LookupAt(map_, Rigid(r.estimate), points, 1, distance, &world, &nearest);
      for (size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector2d& w = world[i];
        const int j = nearest[i];
        if (j < 0) continue;
        const Eigen::Vector2d scan_normal = Rotate(c, s, normals[i]);
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
        residual2 += weight * res * res;
        weight_sum += weight;
        ++matches;
      }
      ++r.iterations;
      r.matches = matches;
      if (matches < options_.min_matches) break;
      r.info = h;
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
        r.residual2 += (at - dst[k]).squaredNorm() / 2.0;
        r.weight_sum += 1;
        const Eigen::Vector2d n = Rotate(c, s, normals[index[k]]);
        const Eigen::Vector2d d_theta(-s * src[k].x() - c * src[k].y(), c * src[k].x() - s * src[k].y());
        if (n.isZero()) continue;  // isolated point or corner: no surface
        const Eigen::Vector3d jac(n.x(), n.y(), n.dot(d_theta));
        r.info += jac * jac.transpose();
      }
    }
  }
  r.ok = !r.pruned && r.matches >= options_.min_matches && r.weight_sum > 0;
  return r;
}

double LaserSlam::Score(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const {
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

std::vector<LaserSlam::Candidate> LaserSlam::Peaks(const std::vector<Candidate>& by_heading) {
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

std::vector<LaserSlam::Candidate> LaserSlam::SearchHeading(const Pose2& around, double window_rad, double shift_m,
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

std::vector<LaserSlam::Candidate> LaserSlam::SearchPoses(const Pose2& around, const Eigen::Matrix3d& covariance,
                                                         double window_rad, double window_xy_m, bool prior_on,
                                                         const std::vector<Eigen::Vector2d>& points,
                                                         size_t stride) const {
  const double cell = options_.lookup_cell_m > 0 ? options_.lookup_cell_m : options_.map_resolution_m;
  const double step = options_.search_step_rad;
  const int nt = static_cast<int>(std::floor(window_rad / step + 1e-9));
  const int nxy = static_cast<int>(std::floor(window_xy_m / cell + 1e-9));
  const double sigma = options_.search_sigma_m, reach = 3 * sigma, inv2s2 = 1.0 / (2 * sigma * sigma);
  const Eigen::Matrix3d info = (covariance + Eigen::Vector3d(1e-8, 1e-8, 1e-8).asDiagonal().toDenseMatrix()).inverse();
  const double prior = prior_on ? 0.5 * options_.search_prior_weight : 0.0;
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
      rotated.push_back(Rotate(c, sn, points[i]) + Eigen::Vector2d(around.x_m, around.y_m));
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

double LaserSlam::KernelScore(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const {
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

LaserSlam::Icp LaserSlam::RefineBest(const std::vector<Candidate>& candidates,
                                     const std::vector<Eigen::Vector2d>& points,
                                     const std::vector<Eigen::Vector2d>& normals, Pose2* start,
                                     LaserSlamUpdate* u) const {
  Icp best;
  double best_score = -1;
  const size_t n = std::min(candidates.size(), static_cast<size_t>(std::max(1, options_.refine_starts)));
  for (size_t k = 0; k < n; ++k) {
    // A later start may be pruned once it is clearly worse than the best so far.
    const double prune_below =
        options_.refine_prune_iterations > 0 && best_score > 0 ? options_.refine_prune_fraction * best_score : 0.0;
    Icp icp = Align(candidates[k].pose, points, normals, prune_below);
    ++u->starts;
    u->pruned += icp.pruned;
    if (!icp.ok) continue;
    ScoreEstimate(points, &icp);
    const double score = n > 1 ? icp.kernel : 0.0;
    if (score > best_score) {
      best_score = score;
      best = icp;
      *start = candidates[k].pose;
    }
  }
  if (best_score < 0) {  // none aligned: the first, as it is
    *start = candidates.empty() ? *start : candidates.front().pose;
    best = Align(*start, points, normals);
  }
  return best;
}

void LaserSlam::ScoreEstimate(const std::vector<Eigen::Vector2d>& points, Icp* icp) const {
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

double LaserSlam::Fit(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const {
  std::vector<Eigen::Vector2d> world;
  std::vector<int> nearest;
  LookupAt(map_, Rigid(pose), points, stride, 0.5 * options_.match_distance_m, &world, &nearest);
  const size_t total = world.size();
  const size_t near = static_cast<size_t>(std::count_if(nearest.begin(), nearest.end(), [](int j) { return j >= 0; }));
  return total > 0 ? static_cast<double>(near) / static_cast<double>(total) : 0.0;
}

void LaserSlam::Predict(const Pose2& odometry_delta, int64_t end_utime) {
  Predict(odometry_delta);
  const int64_t start = last_odometry_utime_ ? std::min(*last_odometry_utime_, end_utime) : end_utime;
  recent_odometry_.push_back({start, end_utime, odometry_delta});
  last_odometry_utime_ = end_utime;
}

LaserSlamUpdate LaserSlam::Update(const std::vector<Eigen::Vector2d>& points_robot) {
  // Untimed: matched at the latest odometry; the timed increments so far are past.
  recent_odometry_.clear();
  odometry_since_scan_ = tail_.Compose(odometry_since_scan_);
  tail_ = {};
  const LaserSlamUpdate u = UpdateAtScan(points_robot);
  scan_pose_ = pose_;
  return u;
}

LaserSlamUpdate LaserSlam::Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime) {
  // The odometry after the match time: the later part of each increment that ends after it.
  const int64_t at = utime - static_cast<int64_t>(std::llround(options_.scan_latency_s * 1e6));
  Pose2 tail;
  for (const TimedIncrement& inc : recent_odometry_) {
    if (inc.end_utime <= at) continue;
    if (inc.start_utime >= at || inc.end_utime <= inc.start_utime) {
      tail = tail.Compose(inc.delta);
      continue;
    }
    const double before =
        static_cast<double>(at - inc.start_utime) / static_cast<double>(inc.end_utime - inc.start_utime);
    const Pose2 first{before * inc.delta.x_m, before * inc.delta.y_m, before * inc.delta.theta_rad};
    tail = tail.Compose(first.Inverse().Compose(inc.delta));
  }
  recent_odometry_.clear();
  // The motion between the two match times, and the pose at this one.
  odometry_since_scan_ = tail_.Compose(odometry_since_scan_).Compose(tail.Inverse());
  pose_ = pose_.Compose(tail.Inverse());
  tail_ = tail;
  const LaserSlamUpdate u = UpdateAtScan(points_robot);
  scan_pose_ = pose_;
  pose_ = pose_.Compose(tail_);
  return u;
}

LaserSlamUpdate LaserSlam::UpdateAtScan(const std::vector<Eigen::Vector2d>& all_points) {
  LaserSlamUpdate u;
  std::vector<Eigen::Vector2d> points;
  points.reserve(all_points.size() / static_cast<size_t>(options_.scan_step) + 1);
  const double max_range2 = options_.max_range_m > 0 ? options_.max_range_m * options_.max_range_m
                                                     : std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < all_points.size(); i += static_cast<size_t>(options_.scan_step)) {
    if (all_points[i].squaredNorm() <= max_range2) points.push_back(all_points[i]);
  }
  const std::vector<Eigen::Vector2d> normals = ScanNormals(points);
  u.points = static_cast<int>(points.size());
  ++scans_;
  if (options_.stale_odometry && last_scan_pose_) {
    // (Increments between two equal odometry poses are zero up to rounding.)
    const double moved = std::hypot(odometry_since_scan_.x_m, odometry_since_scan_.y_m);
    const double last_moved = std::hypot(last_motion_.x_m, last_motion_.y_m);
    const bool frozen = moved <= 1e-6 && std::abs(odometry_since_scan_.theta_rad) <= 1e-6;
    // A robot moving at last_moved per scan cannot stop within one scan interval: odometry whose
    // translation falls below stale_fraction of it lags (CSAIL: 0.21 m, then 0.004, 0, 0, then 0.83).
    const bool lagging =
        options_.stale_fraction > 0 && last_moved >= kStaleMinMotionM && moved < options_.stale_fraction * last_moved;
    if (frozen || lagging) {
      // Stale (or the robot stopped: then the last motion is small, or the scan corrects it).
      if (!stale_since_) {
        stale_since_ = *last_scan_pose_;
        odometry_since_stale_ = {};
      }
      odometry_since_stale_ = odometry_since_stale_.Compose(odometry_since_scan_);
      // The prediction is the last motion instead of odometry's (from the pose after the last
      // scan, as a filter built on this one may have moved it since); its covariance also covers
      // what odometry said (the robot may have stopped).
      pose_ = pose_.Compose(odometry_since_scan_.Inverse());
      const double c = std::cos(pose_.theta_rad), sn = std::sin(pose_.theta_rad);
      PredictWithOdometry(options_.motion, last_motion_, &pose_, &covariance_);
      const Eigen::Vector2d off =
          Rotate(c, sn, {last_motion_.x_m - odometry_since_scan_.x_m, last_motion_.y_m - odometry_since_scan_.y_m});
      const double off_theta = WrapAngle(last_motion_.theta_rad - odometry_since_scan_.theta_rad);
      covariance_.topLeftCorner<2, 2>() += off * off.transpose();
      covariance_(2, 2) += off_theta * off_theta;
      u.stale_odometry = true;
    } else if (stale_since_) {
      // Odometry's increments over the stale interval and this one hold the whole motion since.
      // Take out what the scans tracked meanwhile.
      odometry_since_stale_ = odometry_since_stale_.Compose(odometry_since_scan_);
      const Pose2 tracked = stale_since_->Between(*last_scan_pose_);
      pose_ = pose_.Compose(odometry_since_scan_.Inverse()).Compose(tracked.Inverse().Compose(odometry_since_stale_));
      stale_since_.reset();
    }
  }
  if (map_.size() > 0 && !points.empty()) {
    // Heading search: the prediction's heading may be off by more than ICP can pull in (a fast
    // turn, odometry late against the laser). Headings within search_sigmas standard deviations
    // of the prediction are scored on a subset of the points, and ICP starts from the best.
    const size_t stride = std::max<size_t>(1, points.size() / 90);
    const double step = options_.search_step_rad;
    Pose2 start = pose_;
    const double turn = std::max(std::abs(odometry_since_scan_.theta_rad), std::abs(previous_odometry_turn_rad_));
    covariance_(2, 2) += std::pow(options_.turn_noise_rad_per_rad * turn, 2);
    u.predicted = pose_;
    u.predicted_covariance = covariance_;
    const double window = std::min(options_.search_window_max_rad, options_.search_sigmas * std::sqrt(covariance_(2, 2)));
    const bool correlative = options_.matcher == ScanMatcher::kCorrelative;
    const double sigma_xy = std::sqrt(std::max(covariance_(0, 0), covariance_(1, 1)));
    std::vector<Candidate> candidates;
    if (correlative && options_.search_window_max_rad >= step) {
      const double window_xy = std::min(options_.search_window_xy_m, options_.search_sigmas * sigma_xy);
      candidates = SearchPoses(pose_, covariance_, window, window_xy, true, points, stride);
      ++u.searches;
    } else if (window >= step) {
      candidates = SearchHeading(pose_, window, 0.0, points, stride);
      ++u.searches;
    }
    if (candidates.empty()) candidates.push_back({pose_, 0});
    Icp icp = RefineBest(candidates, points, normals, &start, &u);
    u.start = start;
    u.fit = !icp.ok ? 0.0 : icp.scored ? icp.fit : Fit(icp.estimate, points, 1);
    if (u.fit < options_.recovery_fit && options_.search_window_max_rad >= step) {
      // Poor fit: search the whole window, and positions around the prediction, then align again.
      const std::vector<Candidate> again_candidates =
          correlative ? SearchPoses(pose_, covariance_, options_.search_window_max_rad, options_.search_window_xy_m,
                                    false, points, stride)
                      : SearchHeading(pose_, options_.search_window_max_rad, options_.match_distance_start_m / 2,
                                      points, stride);
      Pose2 again_start = pose_;
      const Icp again = RefineBest(again_candidates, points, normals, &again_start, &u);
      const double again_fit = !again.ok ? 0.0 : again.scored ? again.fit : Fit(again.estimate, points, 1);
      ++u.recoveries;
      if (again_fit > u.fit) {
        icp = again;
        u.start = again_start;
        u.fit = again_fit;
        // The prediction was off by this much, whatever its covariance said: widen it so the
        // update does not pull the pose back towards it.
        const Eigen::Vector3d off(icp.estimate.x_m - pose_.x_m, icp.estimate.y_m - pose_.y_m,
                                  WrapAngle(icp.estimate.theta_rad - pose_.theta_rad));
        covariance_ += off.cwiseProduct(off).asDiagonal();
      }
    }
    u.iterations = icp.iterations;
    u.matches = icp.matches;
    if (icp.ok) {
      const double sigma2 = std::max(options_.point_sigma_m * options_.point_sigma_m, icp.residual2 / icp.weight_sum);
      Eigen::Matrix3d info = icp.info / sigma2;
      info += Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();  // unobservable directions: huge R, not singular
      u.measured = true;
      u.measurement = icp.estimate;
      u.measurement_covariance = info.inverse();
      const Pose2 predicted = pose_;
      const Eigen::Matrix3d predicted_covariance = covariance_;
      pose_ = EkfPoseUpdate(pose_, &covariance_, icp.estimate, u.measurement_covariance);
      if (options_.update_score_margin > 0) {
        // The update should sit where the scan fits: if it scores clearly below the ICP pose
        // against the map, the prediction was off by more than its covariance allowed (odometry
        // jitter along a corridor, a late turn); widen it by the innovation and update again.
        const double at_icp = icp.scored ? icp.score : Score(icp.estimate, points, 1);
        const double at_update = Score(pose_, points, 1);
        if (at_update < (1 - options_.update_score_margin) * at_icp) {
          const Eigen::Vector3d off(icp.estimate.x_m - predicted.x_m, icp.estimate.y_m - predicted.y_m,
                                    WrapAngle(icp.estimate.theta_rad - predicted.theta_rad));
          covariance_ = predicted_covariance;
          covariance_ += off.cwiseProduct(off).asDiagonal();
          pose_ = EkfPoseUpdate(predicted, &covariance_, icp.estimate, u.measurement_covariance);
          u.widened = true;
        }
      }
    }
  }
  previous_odometry_turn_rad_ = odometry_since_scan_.theta_rad;
  odometry_since_scan_ = {};
  if (last_scan_pose_) last_motion_ = last_scan_pose_->Between(pose_);
  last_scan_pose_ = pose_;
  if (!MayAddPoints(u)) return u;
  // Points with no map point near them join the map at the updated pose, with their normals.
  const Rigid to_map(pose_);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d w = to_map(points[i]);
    if (map_.size() > 0 && map_.HasPointWithin(w, options_.add_distance_m)) continue;
    if (map_.Add(w, Rotate(to_map.c, to_map.s, normals[i]))) ++u.added;
  }
  return u;
}

// ---- For filters built on this one (nav::FusedSlam).

void LaserSlam::UpdatePose(const Pose2& z, const Eigen::Matrix3d& r) {
  if (!std::isfinite(z.x_m) || !std::isfinite(z.y_m) || !std::isfinite(z.theta_rad) || !r.allFinite()) {
    throw std::invalid_argument("laser slam: pose measurement or its covariance is not finite");
  }
  pose_ = EkfPoseUpdate(pose_, &covariance_, z, r);
}

void LaserSlam::ResetPose(const Pose2& pose, const Eigen::Matrix3d& covariance) {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad) ||
      !covariance.allFinite()) {
    throw std::invalid_argument("laser slam: reset pose or covariance is not finite");
  }
  const Pose2 old = pose_;
  pose_ = {pose.x_m, pose.y_m, WrapAngle(pose.theta_rad)};
  covariance_ = 0.5 * (covariance + covariance.transpose());
  // The jump is no motion: the poses the odometry models keep move with it (else the next scan
  // takes the jump for the last scan-to-scan motion, and odometry below stale_fraction of it for
  // stale, and predicts the jump again at every scan).
  const auto carry = [&](const Pose2& p) { return pose_.Compose(old.Between(p)); };
  if (last_scan_pose_) last_scan_pose_ = carry(*last_scan_pose_);
  if (stale_since_) stale_since_ = carry(*stale_since_);
  scan_pose_ = carry(scan_pose_);
}

void LaserSlam::SetMapping(bool add_points, double min_fit) {
  if (!(min_fit >= 0 && min_fit <= 1)) throw std::invalid_argument("laser slam: mapping min_fit must be in [0, 1]");
  add_points_ = add_points;
  min_add_fit_ = min_fit;
}

bool LaserSlam::MayAddPoints(const LaserSlamUpdate& u) const {
  if (!add_points_) return false;
  return map_.size() == 0 || u.fit >= min_add_fit_;
}

}  // namespace snapnav::nav
