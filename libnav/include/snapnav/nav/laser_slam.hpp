#pragma once
// 2D laser SLAM with an EKF on the robot pose (thesis 5.3.1).
//
// The state is the robot pose (x, y, theta) with its covariance. Odometry predicts it
// (PredictWithOdometry, motion noise growing with distance and rotation). Each scan's
// points are matched to their nearest map points within match_distance_m; a closed-form
// 2D alignment of the matches, iterated (ICP), gives a pose measurement whose covariance
// comes from the residuals and the match geometry; the EKF update fuses it with the
// prediction; scan points with no map point near them are added to the map at the
// updated pose. The map is a hash grid of cells of map_resolution_m holding one point
// each: nearest-neighbour queries and insertions cost O(1), and the map cannot grow
// faster than the area explored.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// How ICP measures the distance of a scan point to its matched map point.
enum class IcpMetric {
  kPointToPoint,  // thesis 5.3.1: closed-form alignment of the matched pairs (AlignPoints), iterated
  kPointToLine,   // Gauss-Newton on the distance along the surface normal, robust (Cauchy) weights
};
const char* IcpMetricName(IcpMetric m);
std::optional<IcpMetric> ParseIcpMetric(const std::string& name);

// Where ICP starts from.
enum class ScanMatcher {
  kHeading,      // a search of headings around the prediction (its position kept), then ICP
  kCorrelative,  // a correlative search of poses (x, y and heading) around the prediction, then ICP
};
const char* ScanMatcherName(ScanMatcher m);
std::optional<ScanMatcher> ParseScanMatcher(const std::string& name);

// Unit surface normals of scan points from their neighbours in scan order: a line fitted
// (principal axes) through the point and up to `neighbours` points on each side that lie
// within `max_gap_m` of it. Zero where there are too few neighbours or they do not lie on a
// line (a corner, clutter). The gap grows to 5 % of the range for far points.
std::vector<Eigen::Vector2d> ScanNormals(const std::vector<Eigen::Vector2d>& points, int neighbours = 2,
                                         double max_gap_m = 0.3);

// The EKF update with a direct pose measurement z (H = I): K = P (P + R)^-1. The angle
// innovation is wrapped. Returns the updated pose; `covariance` is updated in place.
Pose2 EkfPoseUpdate(const Pose2& pose, Eigen::Matrix3d* covariance, const Pose2& z, const Eigen::Matrix3d& r);

// The rigid transform T minimising sum |T(src_i) - dst_i|^2 (closed form, 2D Kabsch).
// nullopt with fewer than 2 pairs or a degenerate (single-point) source.
std::optional<Pose2> AlignPoints(const std::vector<Eigen::Vector2d>& src, const std::vector<Eigen::Vector2d>& dst);

// Laser ranges to points in the robot frame: beams with NaN, infinite, below range_min or
// at/above range_max (no return) are dropped. `sensor` is the laser's pose on the robot.
std::vector<Eigen::Vector2d> ScanToPoints(const std::vector<float>& ranges_m, double angle_min_rad,
                                          double angle_increment_rad, double range_min_m, double range_max_m,
                                          const Pose2& sensor = {});

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
  static uint64_t Key(int64_t ix, int64_t iy) {
    return (static_cast<uint64_t>(ix) << 32) ^ (static_cast<uint64_t>(iy) & 0xffffffffULL);
  }
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

constexpr double kRadPerDeg = 3.14159265358979323846 / 180;
constexpr double kStaleMinMotionM = 0.05;  // LaserSlamOptions::stale_fraction applies above this motion per scan

struct LaserSlamOptions {
  // Odometry noise Q of the prediction. The heading noise per radian turned is 0.4, not dead
  // reckoning's 0.05: on a real robot turning fast, odometry and laser are out of step (CSAIL:
  // 10-25 deg between a scan and its odometry while turning at 60 deg/s), and the heading search
  // window follows this uncertainty.
  DeadReckoningOptions motion = [] {
    DeadReckoningOptions m;
    m.rotation_noise_rad_per_rad = 0.4;
    return m;
  }();
  double initial_sigma_xy_m = 0.01;         // initial covariance
  double initial_sigma_theta_rad = 0.5 * kRadPerDeg;
  IcpMetric metric = IcpMetric::kPointToPoint;
  double match_distance_m = 0.2;            // a scan point matches a map point closer than this
  double match_distance_start_m = 0.6;      // first iteration's match distance, halved each iteration
                                            // down to match_distance_m (coarse to fine)
  double robust_scale_m = 0.05;             // point-to-line: Cauchy weight 1 / (1 + (r / scale)^2)
  double max_range_m = 0;                   // ignore points farther than this (0: no limit)
  // Heading search before ICP: headings within +-search_sigmas predicted standard deviations
  // (at most search_window_max_rad) in search_step_rad steps are scored against the map and ICP
  // starts from the best. Recovery: when fewer than recovery_fit of the points lie within
  // match_distance_m / 2 of the map after ICP, the whole window (and positions +-
  // match_distance_start_m / 2) is searched and ICP runs again; the better fit wins.
  double search_sigmas = 3.5;
  double search_window_max_rad = 30 * kRadPerDeg;  // 0: no search, no recovery
  double search_step_rad = 0.5 * kRadPerDeg;
  // The correlative search (matcher = kCorrelative): poses within +-search_sigmas predicted
  // standard deviations in heading (at most search_window_max_rad) and position (at most
  // search_window_xy_m), in steps of search_step_rad and of the map's lookup cell, are scored
  // (the sum over the points of exp(-d^2 / (2 search_sigma_m^2)), d the distance to the nearest
  // map point, less search_prior_weight times half the squared Mahalanobis distance from the
  // prediction) and ICP starts from the best. With a lookup grid (lookup_cell_m > 0) the map keeps
  // a likelihood raster (PointGridMap) that ranks each heading's shifts; the headings within 25 % of
  // the raster's best score, and their neighbours, have their best 2 shifts scored exactly.
  ScanMatcher matcher = ScanMatcher::kCorrelative;
  // Test only (no config key): the searches visit their candidates in the opposite order, so that
  // equal scores resolve the other way (a robust result does not depend on it).
  bool search_order_reversed = false;
  double search_window_xy_m = 0.3;
  double search_sigma_m = 0.05;
  double search_prior_weight = 1.0;
  // ICP starts from the best this many local maxima of the search's score over the heading and
  // the result that fits best (the sum over all points of exp(-d^2 / (2 search_sigma_m^2))) is the
  // measurement: the nearest local minimum of ICP is not the best one when two lie close (a fast
  // turn: two minima 1 deg apart, taken by turns as the search grid moves by a quarter step).
  int refine_starts = 3;
  // Pruning the later starts: ICP from the 2nd and later maxima stops after this many iterations
  // when the KernelScore (the fit used to pick the best start) of its estimate is then below
  // refine_prune_fraction of the best result so far; a start that is still worse that late
  // seldom ends better (0: off, every start runs to convergence or icp_iterations).
  int refine_prune_iterations = 0;
  double refine_prune_fraction = 0.8;
  // Fast turns: odometry that lags the laser reports a turn a scan late (CSAIL: 21 deg, then 0.2
  // where the laser saw 15, then 20), so the prediction's heading also gets this std. dev. per
  // radian of the larger of odometry's turn since the last scan and its turn over the interval
  // before; the heading search window follows.
  double turn_noise_rad_per_rad = 1.0;
  // Stale odometry: an interval between two scans with no odometry motion at all is taken as
  // odometry that stopped reporting (CSAIL: the same odometry pose for up to 5 scans while the
  // robot turns, then a jump of 0.5 m and 85 deg). The prediction is then the last scan-to-scan
  // motion, and when odometry moves again, the motion the scans tracked meanwhile is taken out
  // of its increment. (A robot that really stopped: the last motion is small, the scan corrects it.)
  bool stale_odometry = true;
  // ... and so is an interval whose odometry translation is below this fraction of the last
  // scan-to-scan translation (when that was at least kStaleMinMotionM): a moving robot cannot
  // stop within one scan (CSAIL: 0.21 m per scan, then 0.004, 0, 0, then 0.83 m). 0: only
  // intervals with no motion at all.
  double stale_fraction = 0.25;
  // A scan is this much older than its utime (a laser on a slow serial line stamps it when it has
  // arrived: CSAIL's SICK, its odometry pose half a scan interval ahead of the scan). The scan is
  // matched at its utime minus this, odometry interpolated (LaserSlam's timed Predict / Update).
  // 0 (the default): stamped at acquisition, as laser-hokuyo and the simulator do; a latency set
  // for such a laser puts pose() that much odometry ahead of the truth.
  double scan_latency_s = 0;
  double recovery_fit = 0.6;
  // The update should sit where the scan fits: when the updated pose scores (against the map,
  // every point) more than this fraction below the ICP pose, the prediction was off by more than
  // its covariance allowed (odometry jitter along a corridor, where the measurement covariance
  // leaves the axis to the prediction; a late turn): its covariance is widened by the innovation
  // and the update redone. 0: off.
  double update_score_margin = 0.05;
  int icp_iterations = 15;
  double icp_convergence_m = 1e-4;          // stop when an iteration moves less than this
  double point_sigma_m = 0.03;              // noise of one matched point, floor of the residual estimate
  int min_matches = 20;                     // fewer: no measurement this scan (prediction only)
  double map_resolution_m = 0.05;           // grid cell of the map (decimation)
  double add_distance_m = 0.08;             // a scan point is new if no map point is this close
  int scan_step = 1;                        // use every n-th point of a scan
  // Nearest map points through the map's lookup grid of cells of this size (PointGridMap): one
  // table lookup per query, the nearest of the points nearest to the cell's centre. 0: exact
  // search over buckets.
  double lookup_cell_m = 0.05;
  void Validate() const;                    // throws std::invalid_argument
};

struct LaserSlamUpdate {
  bool measured = false;       // the scan gave a pose measurement
  int points = 0, matches = 0, added = 0, iterations = 0;
  double fit = 0;              // fraction of the points within match_distance_m / 2 of the map after ICP
  int searches = 0;            // 1 if the heading was searched before ICP
  int starts = 0;              // ICP runs from the search's maxima (refine_starts; a recovery's included)
  int pruned = 0;              // ... of them ended early as clearly worse (refine_prune_iterations)
  int recoveries = 0;          // 1 if a poor fit started a wider search
  bool stale_odometry = false; // odometry had not moved since the last scan: predicted from the last motion
  bool widened = false;        // the update scored below the ICP pose: the prediction was widened
  Pose2 measurement;           // the ICP pose
  Eigen::Matrix3d measurement_covariance = Eigen::Matrix3d::Zero();
  Pose2 start;      // the pose ICP started from (the search's best; after a recovery, its)
  Pose2 predicted;  // the prediction the scan was matched from (after the odometry models)
  Eigen::Matrix3d predicted_covariance = Eigen::Matrix3d::Zero();  // its covariance (turn noise included)
};

class LaserSlam {
 public:
  explicit LaserSlam(const LaserSlamOptions& options, const Pose2& start = {});

  // EKF prediction from one odometry increment (robot frame).
  void Predict(const Pose2& odometry_delta);
  // EKF update from one scan (points in the robot frame). The first scan only builds the map.
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot);
  // The same with message times [us]: the increment ends at end_utime (it starts where the last
  // timed one ended), the scan has `utime`. With scan_latency_s > 0 the scan is matched (and
  // mapped) at utime - scan_latency_s: the increments after that time are taken out of the
  // prediction (the one that straddles it in proportion to its duration) and put back after the
  // update, so that pose() stays the pose at the latest odometry. Without times (the calls above)
  // the latency is not applied.
  void Predict(const Pose2& odometry_delta, int64_t end_utime);
  LaserSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime);

  const Pose2& pose() const { return pose_; }
  // The pose of the last scan: where it was matched (its utime minus scan_latency_s), after its
  // update. pose() is that pose carried on by the odometry since.
  const Pose2& scan_pose() const { return scan_pose_; }
  const Eigen::Matrix3d& covariance() const { return covariance_; }
  const PointGridMap& map() const { return map_; }
  int64_t scans() const { return scans_; }

 private:
  struct Icp {
    bool ok = false;
    bool pruned = false;  // ended early: after refine_prune_iterations it scored below the best start
    Pose2 estimate;
    int matches = 0, iterations = 0;
    Eigen::Matrix3d info = Eigen::Matrix3d::Zero();  // unscaled information (sum of J^T J)
    double residual2 = 0, weight_sum = 0;
    // From RefineBest: KernelScore, Score and Fit of the estimate (every point), if measured.
    bool scored = false;
    double kernel = 0, score = 0, fit = 0;
  };
  // ICP from `start`. With prune_below > 0: after refine_prune_iterations iterations (if it has not
  // converged by then), a KernelScore of the estimate below prune_below ends it: not ok, pruned.
  Icp Align(const Pose2& start, const std::vector<Eigen::Vector2d>& points,
            const std::vector<Eigen::Vector2d>& normals, double prune_below = 0) const;
  // Sum over every stride-th point of 1 - (d / match_distance)^2, d its distance to the map.
  double Score(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // A search's candidates: the local maxima of its score over the heading, best first.
  struct Candidate {
    Pose2 pose;
    double score = 0;
  };
  // The local maxima of scores by heading index (a plateau: its first), best first.
  static std::vector<Candidate> Peaks(const std::vector<Candidate>& by_heading);
  // Headings within +-window_rad of `around` (and positions +-shift_m, if > 0).
  std::vector<Candidate> SearchHeading(const Pose2& around, double window_rad, double shift_m,
                                       const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // The correlative search around `around` (covariance `covariance`) within +-window_rad and
  // +-window_xy_m (with `prior`, the prior included in the scores; the recovery after a poor fit
  // searches without it: the prediction was wrong, whatever its covariance says).
  std::vector<Candidate> SearchPoses(const Pose2& around, const Eigen::Matrix3d& covariance, double window_rad,
                                     double window_xy_m, bool prior, const std::vector<Eigen::Vector2d>& points,
                                     size_t stride) const;
  // Sum over the points of exp(-d^2 / (2 search_sigma_m^2)), d the distance to the nearest map point.
  double KernelScore(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // ICP from each of the first refine_starts candidates; the result with the best KernelScore
  // (the starts run and pruned counted in *u).
  Icp RefineBest(const std::vector<Candidate>& candidates, const std::vector<Eigen::Vector2d>& points,
                 const std::vector<Eigen::Vector2d>& normals, Pose2* start, LaserSlamUpdate* u) const;

  // Fraction of every stride-th point within match_distance_m / 2 of the map at `pose`.
  double Fit(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // KernelScore, Score and Fit of every point at icp->estimate into icp's kernel, score and fit:
  // the same figures from one lookup (its nearest points within the largest of their distances;
  // a point's nearest within a smaller one is the same point, or none).
  void ScoreEstimate(const std::vector<Eigen::Vector2d>& points, Icp* icp) const;

  LaserSlamOptions options_;
  Pose2 pose_;
  Eigen::Matrix3d covariance_;
  PointGridMap map_;
  int64_t scans_ = 0;
  LaserSlamUpdate UpdateAtScan(const std::vector<Eigen::Vector2d>& points_robot);
  struct TimedIncrement {
    int64_t start_utime, end_utime;
    Pose2 delta;
  };
  std::deque<TimedIncrement> recent_odometry_;  // timed increments since the last scan's match time
  Pose2 scan_pose_;
  std::optional<int64_t> last_odometry_utime_;  // end of the last timed increment
  Pose2 tail_;                                  // odometry after the last scan's match time (re-applied after it)
  Pose2 odometry_since_scan_;         // odometry's motion since the last scan
  double previous_odometry_turn_rad_ = 0;  // odometry's heading change over the interval before
  std::optional<Pose2> last_scan_pose_;    // the pose after the last scan
  Pose2 last_motion_;                  // the estimate's motion between the last two scans
  std::optional<Pose2> stale_since_;   // the pose at the last scan before odometry went stale
  Pose2 odometry_since_stale_;         // odometry's motion since then

  // ---- For filters built on this one (nav::FusedSlam: a visual pose measurement in the same EKF).
 public:
  // EKF update with a direct pose measurement z of covariance r (EkfPoseUpdate).
  void UpdatePose(const Pose2& z, const Eigen::Matrix3d& r);
  // Replaces the pose and its covariance (relocalisation); the map stays as it is.
  void ResetPose(const Pose2& pose, const Eigen::Matrix3d& covariance);
  // Map protection: with add_points false no scan point joins the map; with min_fit > 0 a scan
  // whose ICP fit (LaserSlamUpdate::fit) is below min_fit adds none either (the first scan, which
  // builds the map, always does). Defaults: true, 0 (every scan maps, as before).
  void SetMapping(bool add_points, double min_fit = 0);
  bool adding_points() const { return add_points_; }

 private:
  bool MayAddPoints(const LaserSlamUpdate& u) const;
  bool add_points_ = true;
  double min_add_fit_ = 0;
};

}  // namespace snapnav::nav
