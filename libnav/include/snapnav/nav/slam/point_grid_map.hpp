#pragma once
// The point map of laser SLAM: points on hash grids with a nearest-point lookup grid and a
// likelihood raster for correlative scan matching.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "snapnav/nav/slam/cell_key.hpp"

namespace snapnav::nav {

// A point map on hash grids: at most one point per cell of resolution_m (decimation), and
// buckets of bucket_m for exact nearest-neighbour queries (3 x 3 buckets cover a query radius
// up to bucket_m). With lookup_radius_m > 0 it also keeps a nearest-point lookup grid: in tiles
// of 32 x 32 cells of lookup_cell_m, each cell within lookup_radius_m of a stored point holds
// the kLookupCandidates stored points nearest to the cell's centre, updated as points are added;
// a query (LookupIndex) takes the nearest of its cell's candidates: one tile lookup instead of a
// search over buckets.
//
// With likelihood_sigma_m > 0 (and a lookup grid) it also keeps a likelihood raster for
// correlative scan matching (Olson 2009), in tiles of its own: nodes every lookup_cell_m /
// kLikelihoodSub, at the centres of cells of that size, hold exp(-d^2 / (2 sigma^2)), d the
// distance from the node to the nearest stored point (0 beyond 3 sigma), updated as points are
// added; between nodes the likelihood is bilinear. Its memory (about 10.8 KB per 1.6 m x 1.6 m,
// against the lookup tiles' 24 KB) grows with the area explored, not with the scans.
class PointGridMap {
 public:
  PointGridMap(double resolution_m, double bucket_m, double lookup_radius_m = 0, double lookup_cell_m = 0.05,
               double likelihood_sigma_m = 0);
  // Adds p (with its unit surface normal, or zero if unknown) unless its cell is taken;
  // returns whether it was added.
  bool Add(const Eigen::Vector2d& p, const Eigen::Vector2d& normal = Eigen::Vector2d::Zero());
  // The nearest stored point within max_distance_m, if any.
  std::optional<Eigen::Vector2d> Nearest(const Eigen::Vector2d& p, double max_distance_m) const;
  // Its index in points() / normals(), or -1.
  int NearestIndex(const Eigen::Vector2d& p, double max_distance_m) const;
  // Nearly the nearest: the nearest to p of the candidates the lookup grid holds for p's cell, if
  // within max_distance_m of p; -1 otherwise. It is the nearest point unless more than
  // kLookupCandidates points lie nearer to the cell's centre than the nearest point's distance
  // plus half a cell diagonal. Without a lookup grid, or for max_distance_m beyond its radius,
  // it is NearestIndex.
  int LookupIndex(const Eigen::Vector2d& p, double max_distance_m) const;
  // LookupIndex of each of the n points q in out[0..n): the same answers, faster for a scan's
  // points (each one's cell is located and prefetched some points before it is resolved: the
  // memory reads overlap).
  void LookupIndices(const Eigen::Vector2d* q, size_t n, double max_distance_m, int* out) const;
  // Whether a stored point lies within `distance_m` of p (through the lookup grid if there is one).
  bool HasPointWithin(const Eigen::Vector2d& p, double distance_m) const { return LookupIndex(p, distance_m) >= 0; }
  size_t size() const { return points_.size(); }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }
  const std::vector<Eigen::Vector2d>& normals() const { return normals_; }
  double resolution_m() const { return resolution_; }
  double lookup_radius_m() const { return lookup_radius_; }
  double lookup_cell_m() const { return lookup_cell_; }  // cell of the lookup grid (with lookup_radius_m() > 0) [m]
  // Whether there is a likelihood raster (likelihood_sigma_m > 0 and a lookup grid).
  bool has_likelihood() const { return likelihood_sigma_ > 0 && lookup_radius_ > 0; }
  double likelihood_node_m() const { return node_; }  // spacing of the raster's nodes [m]
  // The raster's likelihood at p (bilinear between nodes); 0 without a raster.
  double Likelihood(const Eigen::Vector2d& p) const;
  // For every shift (ia, ib) in [-n, n]^2 of step_nodes raster nodes in x and y: adds to
  // sums[(ia + n) * (2n + 1) + (ib + n)] the sum over `points` of Likelihood(p + shift), each
  // point's interpolation weights computed once for all shifts. Needs a raster.
  void AddShiftedLikelihoods(const std::vector<Eigen::Vector2d>& points, int n, int step_nodes, double* sums) const;
  // The same for the points moved by the rotation (c, s) and then t (each c x - s y + t.x,
  // s x + c y + t.y, as the search rotates them), without a copy of the moved points.
  void AddShiftedLikelihoods(const std::vector<Eigen::Vector2d>& moving, double c, double s, const Eigen::Vector2d& t,
                             int n, int step_nodes, double* sums) const;
  // The instruction sets AddShiftedLikelihoods uses (with each, the same sums bit for bit): the
  // best this CPU has (AVX2 where it has it, SSE2 on every x86-64), unless lowered for all maps by
  // SetSimd, which returns the level in effect (at most the CPU's).
  enum class Simd { kScalar, kSse2, kAvx2 };
  static Simd simd();
  static Simd SetSimd(Simd wanted);

 private:
  static constexpr int kTileBits = 5, kTile = 1 << kTileBits;  // 32 x 32 lookup cells per tile
 public:
  static constexpr int kLookupCandidates = 3;
  static constexpr int kLikelihoodSubBits = 1;
  static constexpr int kLikelihoodSub = 1 << kLikelihoodSubBits;  // raster nodes per lookup cell, in x and in y

 private:
  static constexpr int kNodeBits = kTileBits + kLikelihoodSubBits, kNodes = 1 << kNodeBits;
  struct Tile {
    Tile() {}  // (not zeroed: TileAt fills it)
    // Per cell, the nearest points to its centre, nearest first; kNone where fewer lie within the radius.
    uint32_t index[kTile * kTile][kLookupCandidates];
    float d2[kTile * kTile][kLookupCandidates];  // their squared distances from the cell centre [m^2]
  };
  // The likelihood raster's nodes in a tile of kNodes x kNodes, row by row (y), in units of 1/255
  // (a byte each: the raster of the area a scan covers stays in the cache), and an apron: the
  // first kRasterApron nodes of the tiles after it in x, in y and in both, copies kept as points
  // are added. A search's block of nodes (AddShiftedLikelihoods) that starts in a tile then lies
  // in it, read in place, when it is at most kRasterApron nodes wide.
  static constexpr int kRasterApron = 40;  // shifts of up to +-8 cells (0.4 m of 0.05 m cells)
  static constexpr int kRasterRow = kNodes + kRasterApron;
  struct RasterTile {
    uint8_t node[kRasterRow * kRasterRow];
    uint8_t padding[8];  // AddShiftedLikelihoods reads up to 7 nodes past a copied row piece
  };
  static constexpr size_t kRasterPadding = 8;
  static constexpr uint32_t kNone = 0xffffffffu;
  static uint64_t Key(int64_t ix, int64_t iy) { return CellKey(ix, iy); }
  // Tile key -> index in tiles_: open addressing with linear probing in a power-of-two table
  // (the lookup's hot path: a multiply and, mostly, one probe).
  struct TileTable {
    std::vector<uint64_t> keys;
    std::vector<uint32_t> values;  // kNone: empty slot
    size_t count = 0;
    int bits = 0;
    size_t Slot(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ULL) >> (64 - bits)); }
    uint32_t Find(uint64_t key) const;                 // kNone if absent
    uint32_t FindOrAdd(uint64_t key, uint32_t value);  // the stored value (`value` if it was absent)
  };
  void AddToLookup(const Eigen::Vector2d& p, uint32_t index);
  void AddToLikelihood(const Eigen::Vector2d& p);
  Tile* TileAt(int64_t tx, int64_t ty);  // created (empty) if absent
  RasterTile* RasterAt(int64_t tx, int64_t ty);  // created (zeros) if absent
  float Node(int64_t ix, int64_t iy) const;  // a raster node (0 where there is no tile)
  double resolution_, bucket_, lookup_radius_, lookup_cell_, likelihood_sigma_, node_, inv_lookup_cell_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets_;  // bucket -> indices in points_
  TileTable cells_;                                              // fine cell -> index in points_
  TileTable tile_index_;                                         // lookup tile -> index in tiles_
  // Tiles, each allocated once (growing the store never moves them; one load to reach one); a
  // copy of the map copies them.
  template <typename T>
  struct TileStore {
    std::vector<std::unique_ptr<T>> tiles;
    TileStore() = default;
    TileStore(const TileStore& other) { *this = other; }
    TileStore& operator=(const TileStore& other) {
      if (this == &other) return *this;
      tiles.clear();
      for (const auto& t : other.tiles) tiles.push_back(std::make_unique<T>(*t));
      return *this;
    }
    TileStore(TileStore&&) noexcept = default;
    TileStore& operator=(TileStore&&) noexcept = default;
    size_t size() const { return tiles.size(); }
    T& operator[](size_t i) const { return *tiles[i]; }
  };
  TileStore<Tile> tiles_;
  TileTable raster_index_;          // raster tile -> index in rasters_
  TileStore<RasterTile> rasters_;  // with a likelihood raster: the tiles of kNodes x kNodes nodes
                                   // with a node, or an apron node, within reach of a point
  // The raster's byte by bins of d^2 / (2 sigma^2) (-1: a rounding boundary in the bin, computed).
  static constexpr int kKernelBins = 4096;
  static constexpr double kKernelMaxX = 4.5;
  std::vector<int16_t> kernel_bytes_;
  std::vector<Eigen::Vector2d> points_, normals_;
};

// The lookup's hot path, inline.
inline uint32_t PointGridMap::TileTable::Find(uint64_t key) const {
  if (count == 0) return kNone;
  const size_t mask = values.size() - 1;
  for (size_t i = Slot(key);; i = (i + 1) & mask) {
    if (values[i] == kNone) return kNone;
    if (keys[i] == key) return values[i];
  }
}

inline int PointGridMap::LookupIndex(const Eigen::Vector2d& p, double max_distance_m) const {
  if (!(max_distance_m <= lookup_radius_)) return NearestIndex(p, max_distance_m);
  // floor() without the library call.
  const auto floor_to_int = [](double v) {
    const auto i = static_cast<int64_t>(v);
    return i - (static_cast<double>(i) > v);
  };
  const int64_t cx = floor_to_int(p.x() * inv_lookup_cell_);
  const int64_t cy = floor_to_int(p.y() * inv_lookup_cell_);
  const uint32_t tile = tile_index_.Find(Key(cx >> kTileBits, cy >> kTileBits));
  if (tile == kNone) return -1;
  const uint32_t* candidates = tiles_[tile].index[((cy & (kTile - 1)) << kTileBits) | (cx & (kTile - 1))];
  double best = max_distance_m * max_distance_m;
  int found = -1;
  for (int k = 0; k < kLookupCandidates && candidates[k] != kNone; ++k) {
    const double d = (points_[candidates[k]] - p).squaredNorm();
    if (d <= best) {
      best = d;
      found = static_cast<int>(candidates[k]);
    }
  }
  return found;
}

}  // namespace snapnav::nav
