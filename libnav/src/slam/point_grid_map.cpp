#include "snapnav/nav/slam/point_grid_map.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__SSE2__) && defined(__GNUC__) && defined(__x86_64__)
#define SNAPNAV_X86_AVX2 1  // an AVX2 kernel, chosen at run time where the CPU has AVX2
#include <immintrin.h>
#endif

namespace snapnav::nav {

namespace {

// floor(v) as an integer, without the library call (the lookup's hot path).
int64_t FloorToInt(double v) {
  const auto i = static_cast<int64_t>(v);
  return i - (static_cast<double>(i) > v);
}

}  // namespace

namespace {

PointGridMap::Simd BestSimd() {
#if defined(SNAPNAV_X86_AVX2)
  if (__builtin_cpu_supports("avx2")) return PointGridMap::Simd::kAvx2;
#endif
#if defined(__SSE2__)
  return PointGridMap::Simd::kSse2;
#else
  return PointGridMap::Simd::kScalar;
#endif
}

std::atomic<PointGridMap::Simd>& SimdLevel() {
  static std::atomic<PointGridMap::Simd> level{BestSimd()};
  return level;
}

}  // namespace

PointGridMap::Simd PointGridMap::simd() { return SimdLevel().load(); }

PointGridMap::Simd PointGridMap::SetSimd(Simd wanted) {
  const Simd level = std::min(wanted, BestSimd());
  SimdLevel().store(level);
  return level;
}

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
      const int64_t cx0 = std::max(x0, tx * kTile), cx1 = std::min(x1, (tx + 1) * kTile - 1);
      const int64_t cy0 = std::max(y0, ty * kTile), cy1 = std::min(y1, (ty + 1) * kTile - 1);
      for (int64_t cy = cy0; cy <= cy1; ++cy) {
        const double dy = (static_cast<double>(cy) + 0.5) * lookup_cell_ - p.y();
        const double dy2 = dy * dy;
        if (dy2 > reach2) continue;  // every cell of the row is farther
        // The row's cells within reach, |dx| <= sqrt(reach2 - dy2), and one more on each side
        // against rounding (the test below decides).
        const double half = std::sqrt(reach2 - dy2) / lookup_cell_, centre = p.x() / lookup_cell_ - 0.5;
        const int64_t lo = std::max(cx0, static_cast<int64_t>(std::floor(centre - half)) - 1);
        const int64_t hi = std::min(cx1, static_cast<int64_t>(std::floor(centre + half)) + 1);
        const int row = static_cast<int>(cy - ty * kTile) << kTileBits;
        for (int64_t cx = lo; cx <= hi; ++cx) {
          const double d2 = dx2_at[cx] + dy2;
          if (d2 > reach2) continue;
          const int c = row + static_cast<int>(cx - tx * kTile);
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
      const int64_t ox = tx * kNodes, oy = ty * kNodes;  // its first node
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

// A point's place on the raster, moved by the rotation (c, s) and then t: the node (i, j) below
// and left of it, and its bilinear weights (1-fx)(1-fy), fx(1-fy), (1-fx)fy, fx fy as floats, in
// SSE2 (FloorToInt by truncation to 32 bits: points within 50,000 km). The moved point
// (c x - s y + tx, s x + c y + ty) is taken as (c x + (-s) y, c y + s x) + t: the same bits.
class PointWeights {
 public:
  PointWeights(double inv_node, double c, double s, const Eigen::Vector2d& t)
      : inv_(_mm_set1_pd(inv_node)), c_(_mm_set1_pd(c)), s_(_mm_set_pd(s, -s)), t_(_mm_loadu_pd(t.data())) {}
  __m128 operator()(const Eigen::Vector2d& q, int64_t* i, int64_t* j) const {
    const __m128d half = _mm_set1_pd(0.5), one = _mm_set1_pd(1.0);
    const __m128d xy = _mm_loadu_pd(q.data());
    const __m128d p = _mm_add_pd(_mm_add_pd(_mm_mul_pd(xy, c_), _mm_mul_pd(_mm_shuffle_pd(xy, xy, 1), s_)), t_);
    const __m128d uv = _mm_sub_pd(_mm_mul_pd(p, inv_), half);  // (u, v)
    const __m128i truncated = _mm_cvttpd_epi32(uv);
    const __m128d tf = _mm_cvtepi32_pd(truncated);
    const __m128d above = _mm_cmpgt_pd(tf, uv);  // truncated up: the floor is one less
    const __m128d fl = _mm_sub_pd(tf, _mm_and_pd(above, one));
    const int down = _mm_movemask_pd(above);
    *i = _mm_cvtsi128_si32(truncated) - (down & 1);
    *j = _mm_cvtsi128_si32(_mm_shuffle_epi32(truncated, 1)) - (down >> 1);
    const __m128 f = _mm_cvtpd_ps(_mm_sub_pd(uv, fl));
    const __m128 pairs = _mm_unpacklo_ps(_mm_sub_ps(_mm_set1_ps(1.0f), f), f);  // (1-fx, fx, 1-fy, fy)
    return _mm_mul_ps(_mm_movelh_ps(pairs, pairs), _mm_shuffle_ps(pairs, pairs, _MM_SHUFFLE(3, 3, 2, 2)));
  }

 private:
  __m128d inv_, c_, s_, t_;
};

#if defined(SNAPNAV_X86_AVX2)
// AccumulateShiftsStep2 with 8 x-shifts at a time (AVX2, no FMA): acc[(b * groups + g) * 8 + l]
// holds a = 8 g + l. Each shift's sum takes the same float operations in the same order: the same
// bits. Reads 16 nodes per group and row (up to 16 * groups past the block's start).
template <int SHIFTS>
__attribute__((target("avx2"))) inline void AccumulateShiftsStep2Avx2(const uint8_t* base, int row_stride, int shifts,
                                                                      __m256 w00, __m256 w10, __m256 w01, __m256 w11,
                                                                      float* acc) {
  const int count = SHIFTS > 0 ? SHIFTS : shifts;
  const int groups = (count + 7) / 8;
  const __m256i low = _mm256_set1_epi32(0xffff);
  for (int b = 0; b < count; ++b) {
    const uint8_t* row0 = base + 2 * b * row_stride;
    const uint8_t* row1 = row0 + row_stride;
    for (int g = 0; g < groups; ++g) {
      const __m256i v0 = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row0 + 16 * g)));
      const __m256i v1 = _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row1 + 16 * g)));
      const __m256 e0 = _mm256_cvtepi32_ps(_mm256_and_si256(v0, low)),
                   o0 = _mm256_cvtepi32_ps(_mm256_srli_epi32(v0, 16));
      const __m256 e1 = _mm256_cvtepi32_ps(_mm256_and_si256(v1, low)),
                   o1 = _mm256_cvtepi32_ps(_mm256_srli_epi32(v1, 16));
      const __m256 v = _mm256_add_ps(
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w00, e0), _mm256_mul_ps(w10, o0)), _mm256_mul_ps(w01, e1)),
          _mm256_mul_ps(w11, o1));
      float* out = acc + 8 * (b * groups + g);
      _mm256_storeu_ps(out, _mm256_add_ps(_mm256_loadu_ps(out), v));
    }
  }
}

// Every point's block (nodes_of(tile x, tile y): a raster tile's nodes or nullptr) accumulated with
// AccumulateShiftsStep2Avx2 into acc (8 * groups * shifts floats, zeroed).
template <class NodesOf>
__attribute__((target("avx2"))) void AccumulatePointsAvx2(const std::vector<Eigen::Vector2d>& moving,
                                                          const PointWeights& weights_of, int64_t back, int shifts,
                                                          int node_bits, int raster_row, NodesOf& nodes_of,
                                                          float* acc) {
  const int64_t mask = (int64_t{1} << node_bits) - 1;
  for (const Eigen::Vector2d& q : moving) {
    int64_t i = 0, j = 0;
    const __m128 weights = weights_of(q, &i, &j);
    const uint8_t* nodes = nodes_of((i - back) >> node_bits, (j - back) >> node_bits);
    if (!nodes) continue;  // no map point within reach of any shift
    const uint8_t* base = nodes + ((j - back) & mask) * raster_row + ((i - back) & mask);
    const __m256 w00 = _mm256_broadcastss_ps(weights);
    const __m256 w10 = _mm256_broadcastss_ps(_mm_shuffle_ps(weights, weights, 0x55));
    const __m256 w01 = _mm256_broadcastss_ps(_mm_shuffle_ps(weights, weights, 0xAA));
    const __m256 w11 = _mm256_broadcastss_ps(_mm_shuffle_ps(weights, weights, 0xFF));
    switch (shifts) {
      case 5:
        AccumulateShiftsStep2Avx2<5>(base, raster_row, shifts, w00, w10, w01, w11, acc);
        break;
      case 13:
        AccumulateShiftsStep2Avx2<13>(base, raster_row, shifts, w00, w10, w01, w11, acc);
        break;
      default:
        AccumulateShiftsStep2Avx2<0>(base, raster_row, shifts, w00, w10, w01, w11, acc);
    }
  }
}
#endif
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
  const Simd level = SimdLevel().load(std::memory_order_relaxed);
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
  const bool simd = step_nodes == 2 && level != Simd::kScalar;
  const int groups = (shifts + 3) / 4;
  thread_local std::vector<Lanes> acc4;
  const int read_x = simd ? std::max(w, 8 * groups) : w;  // nodes of a block row read (SSE2: 8 at a time)
#else
  const int read_x = w;
#endif
  // Whether a block is read in place: it fits in the apron of the tile it starts in.
  const bool in_place = read_x <= kRasterApron && w <= kRasterApron;
  if (!in_place) block.assign(static_cast<size_t>(bw) * w + kRasterPadding, 0);
#if defined(__SSE2__)
  const bool fast = simd && in_place;
  const int64_t back = static_cast<int64_t>(n) * step_nodes;
  const PointWeights weights_of(inv_node, c, s, t);
#if defined(SNAPNAV_X86_AVX2)
  // AVX2 where the CPU has it (8 x-shifts at a time): the same sums, bit for bit.
  const int groups8 = (shifts + 7) / 8;
  const bool avx2 = fast && level == Simd::kAvx2 && 16 * groups8 <= kRasterApron;
#else
  const bool avx2 = false;
#endif
  acc4.assign(simd && !avx2 ? static_cast<size_t>(groups * shifts) : 0, Lanes{_mm_setzero_ps()});
#if defined(SNAPNAV_X86_AVX2)
  if (avx2) {
    thread_local std::vector<float> acc8;
    acc8.assign(static_cast<size_t>(8 * groups8 * shifts), 0.0f);
    AccumulatePointsAvx2(moving, weights_of, back, shifts, kNodeBits, kRasterRow, nodes_of, acc8.data());
    for (int b = 0; b < shifts; ++b) {
      for (int g = 0; g < groups8; ++g) {
        const float* lanes = acc8.data() + 8 * static_cast<size_t>(b * groups8 + g);
        for (int l = 0; l < 8 && 8 * g + l < shifts; ++l) acc[static_cast<size_t>((8 * g + l) * shifts + b)] = lanes[l];
      }
    }
  }
#endif
  if (fast && !avx2) {
    // The common case, each point's interpolation set up with SSE2: the same operations as the
    // loop below.
    for (const Eigen::Vector2d& q : moving) {
      int64_t i = 0, j = 0;
      const __m128 weights = weights_of(q, &i, &j);
      const uint8_t* nodes = nodes_of((i - back) >> kNodeBits, (j - back) >> kNodeBits);
      if (!nodes) continue;  // no map point within reach of any shift
      const uint8_t* base = nodes + ((j - back) & mask) * kRasterRow + ((i - back) & mask);
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
        const int64_t y0 = std::max(ly, ty * kNodes), y1 = std::min(hy, (ty + 1) * kNodes - 1);
        for (int64_t tx = tx0; tx <= tx1; ++tx) {
          const int64_t x0 = std::max(lx, tx * kNodes), x1 = std::min(hx, (tx + 1) * kNodes - 1);
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
  if (simd && !avx2) {
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

}  // namespace snapnav::nav
