#pragma once
// The pose graph of laser SLAM's graph back end (GraphSlam): keyframe poses (nodes) and relative
// pose constraints between them (edges: the front end's motion between consecutive keyframes, and
// loop closures), each with its information matrix. Optimized by MRPT's graph SLAM: the sparse
// Levenberg-Marquardt of mrpt::graphslam::optimize_graph_spa_levmarq (Konolige et al. 2010's SPA)
// over a mrpt::graphs::CNetworkOfPoses2DInf; nothing here solves the graph itself.
//
// Conventions (MRPT's): an edge from a to b holds the pose of b in a's frame; its error at the
// current poses is e = (x, y, theta) of mean^-1 (+) (a^-1 (+) b), so the information matrix is of
// a perturbation of b expressed in b's own frame (ToFrameInformation converts one given in the
// axes of a's frame). Node 0 is the root, held fixed.
//
// Robustness (switchable-constraint style, Suenderhauf and Protzel 2012, as a hard switch): after an
// optimization the loop closure with the largest chi2 (e^T Omega e) beyond closure_chi2_max is
// switched off and the graph optimized again from the poses it started from, until no enabled
// closure is beyond it. A wrong closure that disagrees with the others and the odometry is left out
// instead of bending the map.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

enum class PoseGraphEdgeKind { kOdometry, kLoopClosure };

struct PoseGraphEdge {
  int from = 0, to = 0;
  Pose2 mean;                                                  // pose of `to` in the frame of `from`
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();  // of the error in `to`'s frame (MRPT's)
  PoseGraphEdgeKind kind = PoseGraphEdgeKind::kOdometry;
  bool enabled = true;  // false: switched off (left out of the optimization)
};

struct PoseGraphOptimizeOptions {
  int max_iterations = 100;        // Levenberg-Marquardt iterations per optimization
  double closure_chi2_max = 16.27; // an enabled closure's chi2 beyond this after optimizing: switched off [0: never]
  int max_switch_rounds = 5;       // at most this many closures switched off per call
};

struct PoseGraphOptimizeResult {
  int optimizations = 0;          // calls of MRPT's optimizer (1 + closures switched off)
  int iterations = 0;             // their Levenberg-Marquardt iterations
  std::vector<int> switched_off;  // edges switched off by this call
  double chi2_before = 0;         // sum of e^T Omega e over the enabled edges, before and after
  double chi2_after = 0;
};

// The information of a relative pose's error given as a covariance in the axes of the `from`
// frame (additive x, y, theta, as ICP against a map in that frame reports it), turned into MRPT's
// convention (the error in the `to` frame: its x, y rotated by -mean.theta_rad).
Eigen::Matrix3d ToFrameInformation(const Pose2& mean, const Eigen::Matrix3d& covariance_from_axes);
// A covariance in the axes of a pose's frame rotated into the parent frame's axes, and back.
Eigen::Matrix3d RotateCovariance(const Eigen::Matrix3d& covariance, double theta_rad);

class PoseGraph {
 public:
  int AddNode(const Pose2& pose);  // returns its id (0, 1, ...)
  // Returns the edge's index. Throws std::invalid_argument for an unknown node, a non-finite or
  // non-symmetric-positive information matrix.
  int AddEdge(int from, int to, const Pose2& mean, const Eigen::Matrix3d& information, PoseGraphEdgeKind kind);
  int nodes() const { return static_cast<int>(poses_.size()); }
  const Pose2& pose(int node) const { return poses_.at(static_cast<size_t>(node)); }
  const std::vector<Pose2>& poses() const { return poses_; }
  void SetPose(int node, const Pose2& pose) { poses_.at(static_cast<size_t>(node)) = pose; }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  void SetEnabled(int edge, bool enabled) { edges_.at(static_cast<size_t>(edge)).enabled = enabled; }
  // The edge's error at the current poses (MRPT's), and its chi2 e^T Omega e.
  Eigen::Vector3d EdgeError(int edge) const;
  double EdgeChi2(int edge) const;
  double TotalChi2() const;  // over the enabled edges
  // MRPT's optimizer over every node (the root fixed), then the switch rounds (see the header).
  PoseGraphOptimizeResult Optimize(const PoseGraphOptimizeOptions& options);
  // Dijkstra projection (Bosse et al. 2004; as Karto and slam_toolbox bound their loop search):
  // the covariance of each node's pose relative to `from` (x, y in from's axes, theta), propagated
  // along the enabled edges by first-order composition at the current poses, on the path of least
  // position variance (trace). from's own is zero; a node not connected to it has +inf on the diagonal.
  std::vector<Eigen::Matrix3d> RelativeCovariances(int from) const;

 private:
  std::vector<Pose2> poses_;
  std::vector<PoseGraphEdge> edges_;
  std::vector<std::vector<int>> adjacent_;  // per node, the edges that touch it
};

}  // namespace snapnav::nav
