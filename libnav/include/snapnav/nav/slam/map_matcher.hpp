#pragma once
// Scan matching against a point map (laser SLAM's front end, thesis 5.3.1 and beyond): the
// scan's geometry (points, normals), a search of poses around a prediction (headings only, or
// the correlative search of Olson 2009 on the map's likelihood raster), and ICP from the
// search's best maxima. Stateless over a PointGridMap: the filter (LaserSlam) decides what the
// match is worth; loop closure may match against another map with the same code.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/slam/point_grid_map.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180;

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

// Unit surface normals of scan points from their neighbours in scan order: a line fitted
// (principal axes) through the point and up to `neighbours` points on each side that lie
// within `max_gap_m` of it. Zero where there are too few neighbours or they do not lie on a
// line (a corner, clutter). The gap grows to 5 % of the range for far points.
std::vector<Eigen::Vector2d> ScanNormals(const std::vector<Eigen::Vector2d>& points, int neighbours = 2,
                                         double max_gap_m = 0.3);
// The same for two neighbourhoods in one pass (the smaller's are the first steps of the larger's
// walk): *normals from `neighbours`, *more (unless null) from `more_neighbours`.
void ScanNormals(const std::vector<Eigen::Vector2d>& points, int neighbours, int more_neighbours, double max_gap_m,
                 std::vector<Eigen::Vector2d>* normals, std::vector<Eigen::Vector2d>* more);

// The rigid transform T minimising sum |T(src_i) - dst_i|^2 (closed form, 2D Kabsch).
// nullopt with fewer than 2 pairs or a degenerate (single-point) source.
std::optional<Pose2> AlignPoints(const std::vector<Eigen::Vector2d>& src, const std::vector<Eigen::Vector2d>& dst);

// Laser ranges to points in the robot frame: beams with NaN, infinite, below range_min or
// at/above range_max (no return) are dropped. `sensor` is the laser's pose on the robot.
std::vector<Eigen::Vector2d> ScanToPoints(const std::vector<float>& ranges_m, double angle_min_rad,
                                          double angle_increment_rad, double range_min_m, double range_max_m,
                                          const Pose2& sensor = {});

struct MatcherOptions {
  IcpMetric metric = IcpMetric::kPointToPoint;
  double match_distance_m = 0.2;            // a scan point matches a map point closer than this
  double match_distance_start_m = 0.6;      // first iteration's match distance, halved each iteration
                                            // down to match_distance_m (coarse to fine)
  double robust_scale_m = 0.05;             // point-to-line: Cauchy weight 1 / (1 + (r / scale)^2)
  double search_step_rad = 0.5 * kRadPerDeg;  // heading step of the searches
  // The correlative search (matcher = kCorrelative): poses within a window around the prediction,
  // in steps of search_step_rad and of the map's lookup cell, are scored (the sum over the points
  // of exp(-d^2 / (2 search_sigma_m^2)), d the distance to the nearest map point, less
  // search_prior_weight times half the squared Mahalanobis distance from the prediction) and ICP
  // starts from the best. With a lookup grid the map keeps a likelihood raster (PointGridMap)
  // that ranks each heading's shifts; the headings within 25 % of the raster's best score, and
  // their neighbours, have their best 2 shifts scored exactly.
  ScanMatcher matcher = ScanMatcher::kCorrelative;
  // Test only (no config key): the searches visit their candidates in the opposite order, so that
  // equal scores resolve the other way (a robust result does not depend on it).
  bool search_order_reversed = false;
  double search_sigma_m = 0.05;
  // The kernel sum over-counts the evidence (neighbouring points' errors are not independent: a
  // point's effective noise is point_sigma_m, not search_sigma_m): the prior weighs this many
  // kernel points per unit of half its squared Mahalanobis distance, (point_sigma_m /
  // search_sigma_m)^2, and a match's posterior in nats is its score over this weight.
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
  int icp_iterations = 15;
  double icp_convergence_m = 1e-4;          // stop when an iteration moves less than this
  // A matched point's noise along its surface normal, for the match's covariance: point_sigma_m,
  // and point_sigma_rad times its range (the laser's beam spacing and the map's local rotation
  // move far points more), combined as independent; the covariance grows where the residuals say
  // the points are noisier than that.
  double point_sigma_m = 0.03;
  double point_sigma_rad = 0.5 * kRadPerDeg;
  int min_matches = 20;                     // fewer: no measurement this scan (prediction only)
};

// Matching a scan (points in the robot frame, with their ScanNormals) against `map`. Holds
// references: the map and the options must outlive it (it is cheap to make one per scan).
class MapMatcher {
 public:
  MapMatcher(const PointGridMap& map, const MatcherOptions& options) : map_(map), options_(options) {}

  struct Icp {
    bool ok = false;
    bool pruned = false;  // ended early: after refine_prune_iterations it scored below the best start
    Pose2 estimate;
    int matches = 0, iterations = 0;
    // The estimate's information from the matches with a surface normal (sum of J^T J / each point's
    // variance, PointVariance), their squared residuals along the normals over those variances, and
    // their weight: the covariance is info^-1 times max(1, residual2 / weight_sum).
    Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
    double residual2 = 0, weight_sum = 0;
    // From RefineBest: KernelScore, Score and Fit of the estimate (every point), if measured.
    bool scored = false;
    double kernel = 0, score = 0, fit = 0;
    // With a prior: the kernel less the prior's weight times half the squared Mahalanobis distance
    // of the estimate from the prior's pose (what RefineBest ranks by); the kernel without one.
    double posterior = 0;
  };
  // A prediction the results are weighed against (RefineBest).
  struct Prior {
    Pose2 pose;
    Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  // the inverse of its covariance
    double weight = 0;  // kernel points per unit of half the squared Mahalanobis distance
    double Penalty(const Pose2& p) const;
  };
  // A search's candidates: the local maxima of its score over the heading, best first.
  struct Candidate {
    Pose2 pose;
    double score = 0;
  };
  // ICP runs of RefineBest.
  struct RefineCounts {
    int starts = 0;  // ICP runs from the search's maxima
    int pruned = 0;  // ... of them ended early as clearly worse (refine_prune_iterations)
  };

  // ICP from `start`. With prune_below > 0: after refine_prune_iterations iterations (if it has not
  // converged by then), a KernelScore of the estimate below prune_below ends it: not ok, pruned.
  Icp Align(const Pose2& start, const std::vector<Eigen::Vector2d>& points,
            const std::vector<Eigen::Vector2d>& normals, double prune_below = 0) const;
  // Sum over every stride-th point of 1 - (d / match_distance)^2, d its distance to the map.
  double Score(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // The local maxima of scores by heading index (a plateau: its first), best first.
  static std::vector<Candidate> Peaks(const std::vector<Candidate>& by_heading);
  // Headings within +-window_rad of `around` (and positions +-shift_m, if > 0).
  std::vector<Candidate> SearchHeading(const Pose2& around, double window_rad, double shift_m,
                                       const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // The correlative search around `around` (covariance `covariance`) within +-window_rad and
  // +-window_xy_m, the prior in the scores: prior_weight kernel points (of every stride-th point)
  // per unit of half the squared Mahalanobis distance (0: none).
  std::vector<Candidate> SearchPoses(const Pose2& around, const Eigen::Matrix3d& covariance, double window_rad,
                                     double window_xy_m, double prior_weight, const std::vector<Eigen::Vector2d>& points,
                                     size_t stride) const;
  // Sum over the points of exp(-d^2 / (2 search_sigma_m^2)), d the distance to the nearest map point.
  double KernelScore(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // ICP from each of the first refine_starts candidates; the result with the best KernelScore, or
  // with `prior` the best posterior (its start in *start; the starts run and pruned added to
  // *counts; with `others`, the other starts' aligned results appended to it, scored: how
  // ambiguous the match is).
  Icp RefineBest(const std::vector<Candidate>& candidates, const std::vector<Eigen::Vector2d>& points,
                 const std::vector<Eigen::Vector2d>& normals, Pose2* start, RefineCounts* counts,
                 std::vector<Icp>* others = nullptr, const Prior* prior = nullptr) const;
  // Fraction of every stride-th point within match_distance_m / 2 of the map at `pose`.
  double Fit(const Pose2& pose, const std::vector<Eigen::Vector2d>& points, size_t stride) const;
  // KernelScore, Score and Fit of every point at icp->estimate into icp's kernel, score and fit:
  // the same figures from one lookup (its nearest points within the largest of their distances;
  // a point's nearest within a smaller one is the same point, or none).
  void ScoreEstimate(const std::vector<Eigen::Vector2d>& points, Icp* icp) const;

  // The variance of a matched point along its surface normal (point_sigma_m, point_sigma_rad) [m^2].
  double PointVariance(const Eigen::Vector2d& point_robot) const;

 private:
  const PointGridMap& map_;
  const MatcherOptions& options_;
};

}  // namespace snapnav::nav
