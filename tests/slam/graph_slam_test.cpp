// The graph back end of laser SLAM (issue 22): the pose graph on MRPT's optimizer with its
// switched-off closures, the branch-and-bound loop matcher, and GraphSlam on ray-cast worlds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "snapnav/nav/slam/graph_slam.hpp"
#include "snapnav/nav/slam/loop_closure.hpp"
#include "snapnav/nav/slam/pose_graph.hpp"

namespace snapnav::nav {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

// ---- A world of wall segments and a laser that ray-casts it.

struct Segment {
  Eigen::Vector2d a, b;
};

void AddBox(std::vector<Segment>* w, double x0, double y0, double x1, double y1) {
  w->push_back({{x0, y0}, {x1, y0}});
  w->push_back({{x1, y0}, {x1, y1}});
  w->push_back({{x1, y1}, {x0, y1}});
  w->push_back({{x0, y1}, {x0, y0}});
}

// Points in the robot frame: 541 beams over 270 degrees, 12 m range, 1 cm range noise.
std::vector<Eigen::Vector2d> Scan(const std::vector<Segment>& world, const Pose2& pose, std::mt19937* rng) {
  std::normal_distribution<double> noise(0, 0.01);
  std::vector<Eigen::Vector2d> points;
  const int beams = 541;
  const double fov = 270 * kDeg, max_range = 12;
  const Eigen::Vector2d o(pose.x_m, pose.y_m);
  for (int i = 0; i < beams; ++i) {
    const double a = -fov / 2 + fov * i / (beams - 1);
    const Eigen::Vector2d d(std::cos(pose.theta_rad + a), std::sin(pose.theta_rad + a));
    double best = max_range;
    for (const Segment& s : world) {
      const Eigen::Vector2d e = s.b - s.a;
      const double den = d.x() * e.y() - d.y() * e.x();
      if (std::abs(den) < 1e-12) continue;
      const Eigen::Vector2d w = s.a - o;
      const double t = (w.x() * e.y() - w.y() * e.x()) / den;
      const double u = (w.x() * d.y() - w.y() * d.x()) / den;
      if (t > 0.05 && u >= 0 && u <= 1 && t < best) best = t;
    }
    if (best >= max_range) continue;
    const double r = best + noise(*rng);
    points.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return points;
}

// A square corridor loop, 2 m wide, around the square path (0, 0) - (10, 0) - (10, 10) - (0, 10),
// with boxes in its walls every few metres (irregularly, so that no two places look alike).
std::vector<Segment> LoopWorld() {
  std::vector<Segment> w;
  AddBox(&w, -1, -1, 11, 11);  // outer wall
  AddBox(&w, 1, 1, 9, 9);      // inner block
  const double boxes[][4] = {{2.0, -1.0, 2.6, -0.6}, {5.5, -1.0, 5.8, -0.5}, {8.1, 0.6, 8.5, 1.0},
                             {10.6, 2.4, 11.0, 3.1}, {9.0, 5.0, 9.5, 5.3},   {10.5, 7.7, 11.0, 8.0},
                             {7.0, 10.6, 7.6, 11.0}, {4.2, 9.0, 4.5, 9.6},   {1.5, 10.5, 1.9, 11.0},
                             {-1.0, 7.1, -0.5, 7.5}, {0.6, 4.0, 1.0, 4.7},   {-1.0, 1.6, -0.6, 2.2}};
  for (const auto& b : boxes) AddBox(&w, b[0], b[1], b[2], b[3]);
  return w;
}

// The true poses of `laps` laps of the square path, 0.1 m steps, turning 10 degrees a step at corners.
std::vector<Pose2> SquarePath(int laps) {
  std::vector<Pose2> path;
  Pose2 p{0, 0, 0};
  path.push_back(p);
  for (int lap = 0; lap < laps; ++lap) {
    for (int side = 0; side < 4; ++side) {
      for (int i = 0; i < 100; ++i) {
        p = p.Compose({0.1, 0, 0});
        path.push_back(p);
      }
      for (int i = 0; i < 9; ++i) {
        p = p.Compose({0, 0, 10 * kDeg});
        path.push_back(p);
      }
    }
  }
  return path;
}

// Odometry of a drifting robot: 1 % too long, its heading 0.25 deg per metre off, and noise.
std::vector<Pose2> DriftingOdometry(const std::vector<Pose2>& path, std::mt19937* rng) {
  std::normal_distribution<double> n(0, 1);
  std::vector<Pose2> deltas;
  for (size_t i = 1; i < path.size(); ++i) {
    const Pose2 d = path[i - 1].Between(path[i]);
    const double dist = std::hypot(d.x_m, d.y_m);
    deltas.push_back({1.01 * d.x_m + 0.002 * n(*rng), d.y_m + 0.002 * n(*rng),
                      d.theta_rad + 0.25 * kDeg * dist + 0.1 * kDeg * n(*rng)});
  }
  return deltas;
}

struct RunResult {
  std::vector<Pose2> optimized, live, dead_reckoning;
  int64_t candidates = 0, accepted = 0, rejected = 0, corrections = 0;
  std::vector<LoopClosure> closures;
  std::vector<int64_t> keyframe_scans;
  std::vector<size_t> corrected_scans;  // indices of the scans whose update applied an optimization
  std::vector<size_t> job_scans;        // ... and after whose update a job was running (loop_async)
};

RunResult RunGraphSlam(const std::vector<Segment>& world, const std::vector<Pose2>& path,
                       const std::vector<Pose2>& odometry, const LaserSlamOptions& front, const GraphSlamOptions& options) {
  std::mt19937 rng(7);
  GraphSlam slam(front, options, path.front());
  RunResult r;
  std::vector<std::pair<int, Pose2>> anchors;
  Pose2 dr = path.front();
  for (size_t i = 0; i < path.size(); ++i) {
    if (i > 0) {
      slam.Predict(odometry[i - 1]);
      dr = dr.Compose(odometry[i - 1]);
    }
    const GraphSlamUpdate u = slam.Update(Scan(world, path[i], &rng));
    if (u.corrected) r.corrected_scans.push_back(i);
    if (slam.job_running()) r.job_scans.push_back(i);
    anchors.push_back({u.anchor_keyframe, u.anchor_relative});
    r.live.push_back(slam.scan_pose());
    r.dead_reckoning.push_back(dr);
  }
  slam.Flush();
  for (const auto& [k, rel] : anchors) r.optimized.push_back(slam.OptimizedPose(k, rel));
  r.candidates = slam.loop_candidates();
  r.accepted = slam.loop_accepted();
  r.rejected = slam.loop_rejected();
  r.corrections = slam.corrections();
  r.closures = slam.closures();
  for (int k = 0; k < slam.keyframes(); ++k) r.keyframe_scans.push_back(slam.keyframe_scan(k));
  return r;
}

// Counts of the closures' outcomes, for failure messages.
std::string Outcomes(const std::vector<LoopClosure>& closures) {
  std::map<std::string, int> n;
  for (const LoopClosure& c : closures) ++n[LoopOutcomeName(c.outcome)];
  std::string s;
  for (const auto& [k, v] : n) s += k + " " + std::to_string(v) + "; ";
  return s;
}

double Rmse(const std::vector<Pose2>& estimate, const std::vector<Pose2>& truth) {
  double sum = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    sum += std::pow(estimate[i].x_m - truth[i].x_m, 2) + std::pow(estimate[i].y_m - truth[i].y_m, 2);
  }
  return std::sqrt(sum / static_cast<double>(truth.size()));
}

// A closure is wrong when the pose it gives the new keyframe (from the old one's true pose) is more
// than 0.3 m or 3 degrees off the truth.
bool ClosureIsRight(const LoopClosure& c, const std::vector<Pose2>& truth) {
  const Pose2& from = truth[static_cast<size_t>(c.from_scan - 1)];
  const Pose2& to = truth[static_cast<size_t>(c.to_scan - 1)];
  const Pose2 claimed = from.Compose(c.relative);
  return std::hypot(claimed.x_m - to.x_m, claimed.y_m - to.y_m) < 0.3 &&
         std::abs(WrapAngle(claimed.theta_rad - to.theta_rad)) < 3 * kDeg;
}

// ---- The pose graph.

// A square of 4 x 10 nodes 1 m apart, odometry with a heading bias; closures from the last side's
// nodes to the first's.
struct SquareGraph {
  PoseGraph graph;
  std::vector<Pose2> truth;
};

SquareGraph DriftingSquare() {
  SquareGraph s;
  Pose2 t{0, 0, 0}, est = t;
  s.truth.push_back(t);
  s.graph.AddNode(est);
  const Eigen::Matrix3d odo_info = Eigen::Vector3d(1 / (0.02 * 0.02), 1 / (0.02 * 0.02), 1 / std::pow(1 * kDeg, 2)).asDiagonal();
  for (int i = 1; i <= 40; ++i) {
    const Pose2 step{1, 0, i % 10 == 0 ? kPi / 2 : 0};
    t = t.Compose(step);
    s.truth.push_back(t);
    const Pose2 measured{step.x_m * 1.01, 0.005, step.theta_rad + 1.5 * kDeg};  // drifting odometry
    est = est.Compose(measured);
    const int id = s.graph.AddNode(est);
    s.graph.AddEdge(id - 1, id, measured, odo_info, PoseGraphEdgeKind::kOdometry);
  }
  return s;
}

void AddTrueClosure(SquareGraph* s, int from, int to, const Pose2& error = {}) {
  const Pose2 rel = s->truth[static_cast<size_t>(from)].Between(s->truth[static_cast<size_t>(to)]).Compose(error);
  const Eigen::Matrix3d info = Eigen::Vector3d(1 / (0.05 * 0.05), 1 / (0.05 * 0.05), 1 / std::pow(1 * kDeg, 2)).asDiagonal();
  s->graph.AddEdge(from, to, rel, info, PoseGraphEdgeKind::kLoopClosure);
}

double GraphError(const SquareGraph& s) {
  return Rmse(s.graph.poses(), s.truth);
}

TEST(PoseGraph, ClosuresOfASquareLoopTakeOutTheDrift) {
  SquareGraph s = DriftingSquare();
  const double before = GraphError(s);
  EXPECT_GT(before, 2.0) << "the odometry drifts";
  AddTrueClosure(&s, 0, 40);
  AddTrueClosure(&s, 1, 39);
  AddTrueClosure(&s, 2, 38);
  const PoseGraphOptimizeResult r = s.graph.Optimize({});
  EXPECT_EQ(r.optimizations, 1);
  EXPECT_TRUE(r.switched_off.empty());
  EXPECT_LT(r.chi2_after, r.chi2_before);
  const double after = GraphError(s);
  EXPECT_LT(after, 0.25) << "before " << before;
  EXPECT_EQ(s.graph.pose(0).x_m, 0.0) << "the root is fixed";
  // Edges' errors follow MRPT's convention: zero where the poses agree with the mean.
  EXPECT_NEAR(s.graph.EdgeError(0).norm(), s.graph.EdgeError(0).norm(), 0);
}

TEST(PoseGraph, AWrongClosureIsSwitchedOffAndTheMapIsAsWithoutIt) {
  SquareGraph good = DriftingSquare();
  for (int k = 0; k < 4; ++k) AddTrueClosure(&good, k, 40 - k);
  good.graph.Optimize({});
  const double good_error = GraphError(good);

  SquareGraph s = DriftingSquare();
  for (int k = 0; k < 4; ++k) AddTrueClosure(&s, k, 40 - k);
  AddTrueClosure(&s, 5, 33, {2.0, -1.0, 10 * kDeg});  // a wrong closure: 2 m off
  const int wrong = static_cast<int>(s.graph.edges().size()) - 1;
  const PoseGraphOptimizeResult r = s.graph.Optimize({});
  ASSERT_EQ(r.switched_off.size(), 1u);
  EXPECT_EQ(r.switched_off[0], wrong);
  EXPECT_FALSE(s.graph.edges()[static_cast<size_t>(wrong)].enabled);
  EXPECT_EQ(r.optimizations, 2);
  EXPECT_NEAR(GraphError(s), good_error, 1e-3);
  for (size_t i = 0; i < s.graph.edges().size(); ++i) {
    if (s.graph.edges()[i].kind == PoseGraphEdgeKind::kLoopClosure && s.graph.edges()[i].enabled) {
      EXPECT_LT(s.graph.EdgeChi2(static_cast<int>(i)), 16.27);
    }
  }
  // Without the switch the wrong closure bends the map.
  SquareGraph bent = DriftingSquare();
  for (int k = 0; k < 4; ++k) AddTrueClosure(&bent, k, 40 - k);
  AddTrueClosure(&bent, 5, 33, {2.0, -1.0, 10 * kDeg});
  PoseGraphOptimizeOptions no_switch;
  no_switch.closure_chi2_max = 0;
  bent.graph.Optimize(no_switch);
  EXPECT_GT(GraphError(bent), 2 * good_error + 0.1);
}

TEST(PoseGraph, RelativeCovarianceGrowsAlongTheChainAndShrinksWithAClosure) {
  SquareGraph s = DriftingSquare();
  const auto open = s.graph.RelativeCovariances(40);
  EXPECT_DOUBLE_EQ(open[40].norm(), 0.0);
  EXPECT_GT(open[0].trace(), open[30].trace());
  EXPECT_GT(open[30].trace(), open[39].trace());
  // 40 steps of 2 cm and 1 deg: several decimetres at the far end.
  EXPECT_GT(std::sqrt(open[0](0, 0) + open[0](1, 1)), 0.3);
  AddTrueClosure(&s, 0, 40);
  const auto closed = s.graph.RelativeCovariances(40);
  EXPECT_LT(closed[0].trace(), 0.05 * open[0].trace());
  EXPECT_LT(closed[2].trace(), closed[20].trace());
  s.graph.SetEnabled(static_cast<int>(s.graph.edges().size()) - 1, false);
  EXPECT_NEAR(s.graph.RelativeCovariances(40)[0].trace(), open[0].trace(), 1e-9);
  // Node 0 relative to itself; an isolated node is unreachable.
  PoseGraph g;
  g.AddNode({});
  g.AddNode({1, 0, 0});
  EXPECT_TRUE(std::isinf(g.RelativeCovariances(0)[1](0, 0)));
  EXPECT_THROW(g.AddEdge(0, 5, {}, Eigen::Matrix3d::Identity(), PoseGraphEdgeKind::kOdometry), std::invalid_argument);
  EXPECT_THROW(g.AddEdge(0, 1, {}, -Eigen::Matrix3d::Identity(), PoseGraphEdgeKind::kOdometry), std::invalid_argument);
}

// ---- The loop matcher.

// A submap for the matcher: a scan's points, densified along its walls, in the world frame.
std::vector<Eigen::Vector2d> WorldPointsOf(const std::vector<Segment>& world, const Pose2& pose, std::mt19937* rng) {
  std::vector<Eigen::Vector2d> out;
  for (const Eigen::Vector2d& p : DensifyScan(Scan(world, pose, rng), 0.3, 0.025)) out.push_back(pose.Transform(p));
  return out;
}

TEST(BranchAndBound, FindsTheBestPoseOfTheExhaustiveSearch) {
  std::mt19937 rng(3);
  const std::vector<Segment> world = LoopWorld();
  const Pose2 map_pose{1.0, 0.0, 0.0}, truth{1.8, 0.3, 4 * kDeg};
  const auto submap = WorldPointsOf(world, map_pose, &rng);
  const auto scan = DecimatePoints(Scan(world, truth, &rng), 0.1);
  CorrelativeSearchOptions o;
  const LikelihoodPyramid pyramid(submap, o, 0.0);
  const Pose2 guess{1.0, 0.0, 0.0};
  const auto r = BranchAndBoundSearch(pyramid, scan, guess, 1.2, 8 * kDeg, 0.3, o);
  ASSERT_TRUE(r.found);
  EXPECT_NEAR(r.pose.x_m, truth.x_m, 0.06);
  EXPECT_NEAR(r.pose.y_m, truth.y_m, 0.06);
  EXPECT_NEAR(r.pose.theta_rad, truth.theta_rad, 0.6 * kDeg);
  EXPECT_GT(r.score, 0.6);
  // The exhaustive search on the finest grid finds no better pose.
  double exhaustive = 0;
  const int n = static_cast<int>(std::ceil(1.2 / o.cell_m)), m = static_cast<int>(std::ceil(8 * kDeg / o.step_rad));
  for (int k = -m; k <= m; ++k) {
    const Pose2 rot{guess.x_m, guess.y_m, guess.theta_rad + k * o.step_rad};
    std::vector<std::pair<int, int>> cells;
    for (const auto& q : scan) {
      const Eigen::Vector2d g = (rot.Transform(q) - pyramid.origin()) / pyramid.cell_m();
      cells.emplace_back(static_cast<int>(std::floor(g.x())), static_cast<int>(std::floor(g.y())));
    }
    for (int ix = -n; ix <= n; ++ix) {
      for (int iy = -n; iy <= n; ++iy) {
        double sum = 0;
        for (const auto& [x, y] : cells) sum += pyramid.At(0, x + ix, y + iy);
        exhaustive = std::max(exhaustive, sum / (255.0 * static_cast<double>(scan.size())));
      }
    }
  }
  EXPECT_NEAR(r.score, exhaustive, 1e-9);
  const int64_t all = static_cast<int64_t>(2 * m + 1) * (2 * n + 1) * (2 * n + 1);
  EXPECT_LT(r.scored, all / 5) << "branch and bound scores a fraction of the window";
  EXPECT_LT(r.second_score, 0.9 * r.score) << "a place with boxes in its walls is not ambiguous";
}

TEST(BranchAndBound, APlainCorridorIsAmbiguousAlongItsAxis) {
  std::mt19937 rng(4);
  std::vector<Segment> corridor = {{{-30, -1}, {30, -1}}, {{-30, 1}, {30, 1}}};
  const auto submap = WorldPointsOf(corridor, {0, 0, 0}, &rng);
  const auto scan = DecimatePoints(Scan(corridor, {0.5, 0, 0}, &rng), 0.1);
  CorrelativeSearchOptions o;
  const LikelihoodPyramid pyramid(submap, o, 0.0);
  const auto r = BranchAndBoundSearch(pyramid, scan, {0, 0, 0}, 1.5, 5 * kDeg, 0.3, o);
  ASSERT_TRUE(r.found);
  ASSERT_TRUE(r.second_found);
  EXPECT_GT(r.second_score / r.score, 0.9);
  EXPECT_NEAR(r.second.y_m, r.pose.y_m, 0.06) << "the second peak lies along the axis";
}

// ---- GraphSlam.

GraphSlamOptions TestGraphOptions() {
  GraphSlamOptions o;
  o.loop_min_travel_m = 10;
  return o;
}

// The front end as dead reckoning: no scan ever matches (it coasts on odometry, its covariance
// growing with the odometry noise), so that every correction is the back end's.
LaserSlamOptions DeadReckoningFrontEnd() {
  LaserSlamOptions f;
  f.gate_mahalanobis2 = 1e-12;  // every match beyond the gate
  f.outlier_scale = 1;          // ... and no heavy tail
  f.wall_orientation = false;   // ... and no heading from the walls either
  return f;
}

TEST(GraphSlam, ASquareLoopWithDriftingOdometryIsClosed) {
  std::mt19937 rng(5);
  const std::vector<Segment> world = LoopWorld();
  const std::vector<Pose2> path = SquarePath(2);
  const std::vector<Pose2> odometry = DriftingOdometry(path, &rng);
  const RunResult r = RunGraphSlam(world, path, odometry, DeadReckoningFrontEnd(), TestGraphOptions());
  const double dr = Rmse(r.dead_reckoning, path), graph = Rmse(r.optimized, path);
  EXPECT_GT(dr, 1.0) << "the odometry drifts";
  EXPECT_GE(r.accepted, 5);
  EXPECT_GE(r.corrections, 1);
  EXPECT_LT(graph, 0.2) << "dead reckoning " << dr << ", candidates " << r.candidates << ", accepted " << r.accepted << ": "
                        << Outcomes(r.closures);
  EXPECT_LT(graph, 0.15 * dr);
  int wrong = 0;
  std::string wrong_ones;
  for (const LoopClosure& c : r.closures) {
    if (c.outcome != LoopOutcome::kAccepted || ClosureIsRight(c, path)) continue;
    ++wrong;
    const Pose2 claimed = path[static_cast<size_t>(c.from_scan - 1)].Compose(c.relative);
    const Pose2& to = path[static_cast<size_t>(c.to_scan - 1)];
    wrong_ones += std::to_string(c.from_keyframe) + ">" + std::to_string(c.to_keyframe) + " score " +
                  std::to_string(c.score) + " amb " + std::to_string(c.ambiguity) + " m2 " +
                  std::to_string(c.mahalanobis2) + " sigma " + std::to_string(c.graph_sigma_m) + " off " +
                  std::to_string(std::hypot(claimed.x_m - to.x_m, claimed.y_m - to.y_m)) + " m; ";
  }
  EXPECT_EQ(wrong, 0) << wrong_ones;
  // The live pose follows the corrections: at the end it is near the truth too.
  EXPECT_LT(std::hypot(r.live.back().x_m - path.back().x_m, r.live.back().y_m - path.back().y_m), 0.3);
}

TEST(GraphSlam, WithTheRobustFrontEndTheLoopStaysClosed) {
  std::mt19937 rng(6);
  const std::vector<Segment> world = LoopWorld();
  const std::vector<Pose2> path = SquarePath(2);
  const std::vector<Pose2> odometry = DriftingOdometry(path, &rng);
  GraphSlamOptions o = TestGraphOptions();
  o.local_map_m = 10;  // the front end alone would not close the loop
  const RunResult r = RunGraphSlam(world, path, odometry, LaserSlamOptions{}, o);
  EXPECT_GE(r.accepted, 3);
  EXPECT_LT(Rmse(r.optimized, path), 0.1);
  for (const LoopClosure& c : r.closures) {
    if (c.outcome == LoopOutcome::kAccepted) {
      EXPECT_TRUE(ClosureIsRight(c, path));
    }
  }
}

// The loop search and optimization on the worker thread (loop_async): the loop is closed as well,
// every result joins exactly loop_async_scans scans after its job started (never in the scan that
// started it), and two runs give the same poses to the bit: what the worker's speed decides is
// only whether the scan thread waits, not what it gets.
TEST(GraphSlam, OffTheScanThreadTheLoopIsClosedTheSameOnEveryRun) {
  std::mt19937 rng(5);
  const std::vector<Segment> world = LoopWorld();
  const std::vector<Pose2> path = SquarePath(2);
  const std::vector<Pose2> odometry = DriftingOdometry(path, &rng);
  GraphSlamOptions o = TestGraphOptions();
  o.loop_async = true;
  o.loop_async_scans = 5;
  const RunResult a = RunGraphSlam(world, path, odometry, DeadReckoningFrontEnd(), o);
  const RunResult b = RunGraphSlam(world, path, odometry, DeadReckoningFrontEnd(), o);
  GraphSlamOptions sync = TestGraphOptions();
  sync.loop_async = false;
  const RunResult inside = RunGraphSlam(world, path, odometry, DeadReckoningFrontEnd(), sync);
  EXPECT_TRUE(inside.job_scans.empty()) << "without loop_async no job outlives its scan";
  EXPECT_FALSE(a.job_scans.empty());
  ASSERT_EQ(a.optimized.size(), b.optimized.size());
  for (size_t i = 0; i < a.optimized.size(); ++i) {
    ASSERT_EQ(a.optimized[i].x_m, b.optimized[i].x_m) << "scan " << i;
    ASSERT_EQ(a.optimized[i].y_m, b.optimized[i].y_m) << "scan " << i;
    ASSERT_EQ(a.live[i].theta_rad, b.live[i].theta_rad) << "scan " << i;
  }
  EXPECT_EQ(a.corrected_scans, b.corrected_scans);
  EXPECT_EQ(a.accepted, b.accepted);
  EXPECT_GE(a.accepted, 5);
  EXPECT_GE(a.corrections, 1);
  // Each correction joins 5 scans after its job started: the 4 scans before it ran with the job.
  for (const size_t c : a.corrected_scans) {
    ASSERT_GE(c, 5u);
    for (size_t k = c - 4; k < c; ++k) {
      EXPECT_TRUE(std::find(a.job_scans.begin(), a.job_scans.end(), k) != a.job_scans.end())
          << "scan " << k << " before the correction at " << c;
    }
  }
  const double dr = Rmse(a.dead_reckoning, path);
  EXPECT_LT(Rmse(a.optimized, path), 0.2) << "inside the scan's update: " << Rmse(inside.optimized, path);
  EXPECT_LT(Rmse(a.optimized, path), 0.15 * dr);
  for (const LoopClosure& c : a.closures) {
    if (c.outcome == LoopOutcome::kAccepted) {
      EXPECT_TRUE(ClosureIsRight(c, path));
    }
  }
  EXPECT_LT(std::hypot(a.live.back().x_m - path.back().x_m, a.live.back().y_m - path.back().y_m), 0.3);
}

// Laps of one room for a long time (8-10 laps, 320-400 m): with keyframe reuse the graph stops
// growing once the room is mapped (from the first revisit: keyframes and map points plateau after
// the first lap; with five keyframes per place, after the fifth) while the trajectory stays on the
// truth; without it, it grows with every lap.
struct LapCounts {
  std::vector<int> keyframes;      // after each lap
  std::vector<size_t> map_points;  // ...
  double rmse_m = 0;
  int64_t reuses = 0;
};

LapCounts DriveLaps(int laps, const GraphSlamOptions& options) {
  std::mt19937 rng(12);
  const std::vector<Segment> world = LoopWorld();
  const std::vector<Pose2> path = SquarePath(laps);
  const std::vector<Pose2> odometry = DriftingOdometry(path, &rng);
  GraphSlam slam(LaserSlamOptions{}, options, path.front());
  LapCounts c;
  std::vector<std::pair<int, Pose2>> anchors;
  const size_t per_lap = (path.size() - 1) / static_cast<size_t>(laps);
  for (size_t i = 0; i < path.size(); ++i) {
    if (i > 0) slam.Predict(odometry[i - 1]);
    const GraphSlamUpdate u = slam.Update(Scan(world, path[i], &rng));
    anchors.push_back({u.anchor_keyframe, u.anchor_relative});
    if (i > 0 && i % per_lap == 0) {
      c.keyframes.push_back(slam.keyframes());
      c.map_points.push_back(slam.Map().size());
    }
  }
  slam.Flush();
  std::vector<Pose2> optimized;
  for (const auto& [k, rel] : anchors) optimized.push_back(slam.OptimizedPose(k, rel));
  c.rmse_m = Rmse(optimized, path);
  c.reuses = slam.keyframe_reuses();
  return c;
}

TEST(GraphSlam, KeyframeReuseKeepsTheGraphBoundedInOneRoom) {
  GraphSlamOptions o = TestGraphOptions();
  o.keyframe_reuse_m = 0.3;
  o.keyframes_per_place = 1;  // reuse from the first revisit
  o.loop_async = true;        // (as a live robot would run it)
  const LapCounts reuse = DriveLaps(8, o);
  ASSERT_EQ(reuse.keyframes.size(), 8u);
  std::string counts;
  for (size_t i = 0; i < reuse.keyframes.size(); ++i) {
    counts += std::to_string(reuse.keyframes[i]) + "/" + std::to_string(reuse.map_points[i]) + " ";
  }
  std::cout << "8 laps with keyframe reuse: keyframes/map points after each lap " << counts << "; " << reuse.reuses
            << " reuses, RMSE " << reuse.rmse_m << " m\n";
  EXPECT_LE(reuse.keyframes.back(), reuse.keyframes[1] + 10) << "keyframes/map points per lap: " << counts;
  EXPECT_LE(reuse.map_points.back(), reuse.map_points[1] + reuse.map_points[1] / 10) << counts;
  EXPECT_GT(reuse.reuses, 300) << counts;
  EXPECT_LT(reuse.rmse_m, 0.1) << counts;
  // With five keyframes per place (as shipped) the first passes each add theirs, as without reuse
  // (the real logs' few revisits never reach five: their graphs are as without reuse), and once a
  // place holds five the graph stays as it is.
  o.keyframes_per_place = 5;
  const LapCounts five = DriveLaps(10, o);
  ASSERT_EQ(five.keyframes.size(), 10u);
  counts.clear();
  for (size_t i = 0; i < five.keyframes.size(); ++i) counts += std::to_string(five.keyframes[i]) + " ";
  std::cout << "10 laps, 5 keyframes per place: keyframes after each lap " << counts << "; " << five.reuses
            << " reuses, RMSE " << five.rmse_m << " m\n";
  EXPECT_GE(five.keyframes[3], five.keyframes[0] * 3) << "the first passes add their keyframes: " << counts;
  EXPECT_LE(five.keyframes.back(), five.keyframes[6] + 10) << "then the graph stays: " << counts;
  EXPECT_GT(five.reuses, 100) << counts;
  EXPECT_LT(five.rmse_m, 0.1) << counts;
  // Without reuse every lap adds its keyframes.
  o.keyframe_reuse_m = 0;
  const LapCounts grow = DriveLaps(4, o);
  ASSERT_EQ(grow.keyframes.size(), 4u);
  std::cout << "4 laps without: keyframes after each lap " << grow.keyframes[0] << " " << grow.keyframes[1] << " "
            << grow.keyframes[2] << " " << grow.keyframes[3] << ", RMSE " << grow.rmse_m << " m\n";
  EXPECT_GE(grow.keyframes[3], grow.keyframes[1] + 100) << "without reuse";
  EXPECT_EQ(grow.reuses, 0);
}

// Two parallel corridors 3 m apart (a U: out along one, back along the other) with their boxes at
// different places: the old keyframes of the first lie within the search reach of the second's, the
// corridors' shape is the same, but the places differ: no closure.
TEST(GraphSlam, NoClosureWhenThePlacesDiffer) {
  std::mt19937 rng(8);
  std::vector<Segment> world;
  world.push_back({{-2, -1}, {22, -1}});
  world.push_back({{-2, 1}, {20, 1}});    // between the corridors (open at the far end)
  world.push_back({{-2, 2}, {20, 2}});
  world.push_back({{-2, 4}, {22, 4}});
  world.push_back({{22, -1}, {22, 4}});
  world.push_back({{-2, -1}, {-2, 1}});
  world.push_back({{-2, 2}, {-2, 4}});
  world.push_back({{20, 1}, {20, 2}});
  const double first[][2] = {{2, -1}, {6.5, 1}, {9, -1}, {13.2, 1}, {16, -1}};
  const double second[][2] = {{3.7, 2}, {5, 4}, {10.4, 2}, {12, 4}, {17.5, 2}};
  for (const auto& b : first) AddBox(&world, b[0], b[1] - 0.25, b[0] + 0.5, b[1] + 0.25);
  for (const auto& b : second) AddBox(&world, b[0], b[1] - 0.25, b[0] + 0.4, b[1] + 0.25);
  std::vector<Pose2> path;
  Pose2 p{0, 0, 0};
  path.push_back(p);
  for (int i = 0; i < 200; ++i) path.push_back(p = p.Compose({0.1, 0, 0}));  // along y = 0 to x = 20
  for (int i = 0; i < 9; ++i) path.push_back(p = p.Compose({0, 0, 10 * kDeg}));
  for (int i = 0; i < 30; ++i) path.push_back(p = p.Compose({0.1, 0, 0}));  // across to y = 3
  for (int i = 0; i < 9; ++i) path.push_back(p = p.Compose({0, 0, 10 * kDeg}));
  for (int i = 0; i < 200; ++i) path.push_back(p = p.Compose({0.1, 0, 0}));  // back along y = 3
  const std::vector<Pose2> odometry = DriftingOdometry(path, &rng);
  const RunResult r = RunGraphSlam(world, path, odometry, LaserSlamOptions{}, TestGraphOptions());
  EXPECT_GT(r.candidates, 5) << "the first corridor's keyframes are searched";
  EXPECT_EQ(r.accepted, 0);
  EXPECT_EQ(r.corrections, 0);
}

// The front end's map rebuilt (as the graph back end does after a correction): the new points
// replace the old ones, one within add_distance_m, and the next scan matches against them.
TEST(LaserSlam, ResetMapReplacesTheMapAndTheFilterMatchesAgainstIt) {
  std::mt19937 rng(11);
  const std::vector<Segment> world = LoopWorld();
  LaserSlam slam(LaserSlamOptions{}, {0, 0, 0});
  slam.Update(Scan(world, {0, 0, 0}, &rng));  // a map of the start
  ASSERT_GT(slam.map().size(), 100u);
  // The map of another place, the robot moved there (the rebuilt map of a corrected graph).
  const Pose2 there{10, 5, kPi / 2};
  std::vector<Eigen::Vector2d> points, normals;
  const std::vector<Eigen::Vector2d> scan = Scan(world, there, &rng);
  const std::vector<Eigen::Vector2d> scan_normals = ScanNormals(scan);
  for (size_t i = 0; i < scan.size(); ++i) {
    points.push_back(there.Transform(scan[i]));
    normals.push_back(Eigen::Rotation2Dd(there.theta_rad) * scan_normals[i]);
    points.push_back(there.Transform(scan[i]) + Eigen::Vector2d(0.01, 0));  // a near duplicate
    normals.push_back(normals.back());
  }
  slam.ResetMap(points, normals);
  EXPECT_LE(slam.map().size(), scan.size());
  EXPECT_GT(slam.map().size(), 50u);  // (one point within add_distance_m: walls 8 cm apart)
  for (const Eigen::Vector2d& p : slam.map().points()) EXPECT_GT(p.y(), 0.9) << "the start's map is gone";
  slam.ResetPose({10.05, 5.0, kPi / 2}, Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal());
  const LaserSlamUpdate u = slam.Update(Scan(world, there, &rng));
  EXPECT_EQ(u.outcome, MatchOutcome::kAccepted);
  EXPECT_NEAR(slam.pose().x_m, there.x_m, 0.03);
  EXPECT_NEAR(slam.pose().y_m, there.y_m, 0.03);
  EXPECT_THROW(slam.ResetMap(points, {}), std::invalid_argument);
}

// The graph's front end is the EKF's, the walls' heading measurement included (unless the EKF's
// options turn it off), but it never applies the odometry calibration.
TEST(GraphSlam, TheFrontEndIsTheEkfsButNeverAppliesTheCalibration) {
  const std::vector<Segment> world = LoopWorld();
  const std::vector<Pose2> path = SquarePath(1);
  for (const bool walls : {true, false}) {
    std::mt19937 rng(5);
    LaserSlamOptions front;  // the EKF's defaults
    front.wall_orientation = walls;
    front.odometry_calibration.apply = true;
    GraphSlam slam(front, TestGraphOptions(), path.front());
    EXPECT_FALSE(slam.front_end().odometry_calibration().options().apply);
    int measured = 0;
    for (size_t i = 0; i < path.size(); ++i) {
      if (i > 0) slam.Predict(path[i - 1].Between(path[i]));
      measured += slam.Update(Scan(world, path[i], &rng)).front_end.wall_measured;
    }
    if (walls) {
      EXPECT_GT(measured, static_cast<int>(path.size()) / 2) << "the walls measure the heading";
    } else {
      EXPECT_EQ(measured, 0);
    }
  }
}

TEST(GraphSlamOptions, InvalidValuesAreRejected) {
  GraphSlamOptions o;
  o.keyframe_distance_m = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = {};
  o.loop_window_max_m = 0.1;  // below the minimum
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = {};
  o.loop_max_ambiguity = 0;
  EXPECT_THROW(GraphSlam(LaserSlamOptions{}, o), std::invalid_argument);
  o = {};
  o.loop_async_scans = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = {};
  o.keyframes_per_place = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  EXPECT_NO_THROW(GraphSlamOptions{}.Validate());
  EXPECT_STREQ(LoopOutcomeName(LoopOutcome::kSwitchedOff), "switched_off");
}

}  // namespace
}  // namespace snapnav::nav
