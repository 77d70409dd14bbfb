#include "snapnav/nav/slam/pose_graph.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>

#include <mrpt/graphs/CNetworkOfPoses.h>
#include <mrpt/graphslam/levmarq.h>

namespace snapnav::nav {
namespace {

Eigen::Matrix3d BlockRotation(double theta_rad) {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r(0, 0) = c;
  r(0, 1) = -s;
  r(1, 0) = s;
  r(1, 1) = c;
  return r;
}

// d(a (+) z) / da at a, z.
Eigen::Matrix3d ComposeJacobianA(const Pose2& a, const Pose2& z) {
  const double c = std::cos(a.theta_rad), s = std::sin(a.theta_rad);
  Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
  j(0, 2) = -s * z.x_m - c * z.y_m;
  j(1, 2) = c * z.x_m - s * z.y_m;
  return j;
}

}  // namespace

Eigen::Matrix3d RotateCovariance(const Eigen::Matrix3d& covariance, double theta_rad) {
  const Eigen::Matrix3d r = BlockRotation(theta_rad);
  return r * covariance * r.transpose();
}

Eigen::Matrix3d ToFrameInformation(const Pose2& mean, const Eigen::Matrix3d& covariance_from_axes) {
  // The error's x, y in `to`'s frame are those of from's axes rotated by -theta.
  const Eigen::Matrix3d to_axes = RotateCovariance(covariance_from_axes, -mean.theta_rad);
  const Eigen::Matrix3d sym = 0.5 * (to_axes + to_axes.transpose());
  return sym.inverse();
}

int PoseGraph::AddNode(const Pose2& pose) {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad)) {
    throw std::invalid_argument("pose graph: node pose is not finite");
  }
  poses_.push_back(pose);
  adjacent_.emplace_back();
  return static_cast<int>(poses_.size()) - 1;
}

int PoseGraph::AddEdge(int from, int to, const Pose2& mean, const Eigen::Matrix3d& information,
                       PoseGraphEdgeKind kind) {
  if (from < 0 || to < 0 || from >= nodes() || to >= nodes() || from == to) {
    throw std::invalid_argument("pose graph: edge " + std::to_string(from) + " -> " + std::to_string(to) +
                                " between unknown nodes");
  }
  if (!std::isfinite(mean.x_m) || !std::isfinite(mean.y_m) || !std::isfinite(mean.theta_rad) ||
      !information.allFinite() || (information - information.transpose()).cwiseAbs().maxCoeff() >
                                      1e-6 * (1 + information.cwiseAbs().maxCoeff())) {
    throw std::invalid_argument("pose graph: edge mean or information not finite, or not symmetric");
  }
  if (information.diagonal().minCoeff() <= 0) throw std::invalid_argument("pose graph: information not positive");
  PoseGraphEdge e;
  e.from = from;
  e.to = to;
  e.mean = mean;
  e.information = 0.5 * (information + information.transpose());
  e.kind = kind;
  edges_.push_back(e);
  const int index = static_cast<int>(edges_.size()) - 1;
  adjacent_[static_cast<size_t>(from)].push_back(index);
  adjacent_[static_cast<size_t>(to)].push_back(index);
  return index;
}

Eigen::Vector3d PoseGraph::EdgeError(int edge) const {
  const PoseGraphEdge& e = edges_.at(static_cast<size_t>(edge));
  const Pose2 d = e.mean.Inverse().Compose(pose(e.from).Between(pose(e.to)));
  return {d.x_m, d.y_m, d.theta_rad};
}

double PoseGraph::EdgeChi2(int edge) const {
  const Eigen::Vector3d v = EdgeError(edge);
  return v.dot(edges_.at(static_cast<size_t>(edge)).information * v);
}

double PoseGraph::TotalChi2() const {
  double chi2 = 0;
  for (size_t i = 0; i < edges_.size(); ++i) {
    if (edges_[i].enabled) chi2 += EdgeChi2(static_cast<int>(i));
  }
  return chi2;
}

PoseGraphOptimizeResult PoseGraph::Optimize(const PoseGraphOptimizeOptions& options) {
  PoseGraphOptimizeResult result;
  result.chi2_before = TotalChi2();
  if (nodes() < 2) return result;
  const std::vector<Pose2> start = poses_;
  const auto run_mrpt = [&] {
    mrpt::graphs::CNetworkOfPoses2DInf graph;
    graph.root = 0;
    for (size_t i = 0; i < poses_.size(); ++i) {
      graph.nodes[i] = mrpt::poses::CPose2D(poses_[i].x_m, poses_[i].y_m, poses_[i].theta_rad);
    }
    int enabled = 0;
    for (const PoseGraphEdge& e : edges_) {
      if (!e.enabled) continue;
      mrpt::poses::CPosePDFGaussianInf pdf;
      pdf.mean = mrpt::poses::CPose2D(e.mean.x_m, e.mean.y_m, e.mean.theta_rad);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) pdf.cov_inv(r, c) = e.information(r, c);
      }
      graph.insertEdge(static_cast<mrpt::graphs::TNodeID>(e.from), static_cast<mrpt::graphs::TNodeID>(e.to), pdf);
      ++enabled;
    }
    if (enabled == 0) return;
    mrpt::graphslam::TResultInfoSpaLevMarq info;
    mrpt::containers::yaml params = mrpt::containers::yaml::Map();
    params["max_iterations"] = static_cast<uint64_t>(options.max_iterations);
    mrpt::graphslam::optimize_graph_spa_levmarq(graph, info, nullptr, params);
    ++result.optimizations;
    result.iterations += static_cast<int>(info.num_iters) + 1;
    for (const auto& [id, p] : graph.nodes) {
      poses_[static_cast<size_t>(id)] = {p.x(), p.y(), WrapAngle(p.phi())};
    }
  };
  run_mrpt();
  for (int round = 0; options.closure_chi2_max > 0 && round < options.max_switch_rounds; ++round) {
    int worst = -1;
    double worst_chi2 = options.closure_chi2_max;
    for (size_t i = 0; i < edges_.size(); ++i) {
      if (!edges_[i].enabled || edges_[i].kind != PoseGraphEdgeKind::kLoopClosure) continue;
      const double chi2 = EdgeChi2(static_cast<int>(i));
      if (chi2 > worst_chi2) {
        worst_chi2 = chi2;
        worst = static_cast<int>(i);
      }
    }
    if (worst < 0) break;
    edges_[static_cast<size_t>(worst)].enabled = false;
    result.switched_off.push_back(worst);
    poses_ = start;
    run_mrpt();
  }
  result.chi2_after = TotalChi2();
  return result;
}

std::vector<Eigen::Matrix3d> PoseGraph::RelativeCovariances(int from) const {
  const double inf = std::numeric_limits<double>::infinity();
  const size_t n = poses_.size();
  std::vector<Eigen::Matrix3d> cov(n, Eigen::Vector3d(inf, inf, inf).asDiagonal().toDenseMatrix());
  if (from < 0 || static_cast<size_t>(from) >= n) return cov;
  std::vector<char> done(n, 0);
  cov[static_cast<size_t>(from)].setZero();
  const Pose2 origin = pose(from);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  queue.push({0.0, from});
  while (!queue.empty()) {
    const auto [trace, a] = queue.top();
    queue.pop();
    const size_t ua = static_cast<size_t>(a);
    if (done[ua]) continue;
    done[ua] = 1;
    const Pose2 ra = origin.Between(pose(a));  // a relative to `from`
    for (const int ei : adjacent_[ua]) {
      const PoseGraphEdge& e = edges_[static_cast<size_t>(ei)];
      if (!e.enabled) continue;
      const int b = e.from == a ? e.to : e.from;
      const size_t ub = static_cast<size_t>(b);
      if (done[ub]) continue;
      const Pose2 rb = origin.Between(pose(b));
      // The edge's covariance as a perturbation of its `to` node in that node's frame.
      const Eigen::Matrix3d edge_cov = e.information.inverse();
      Eigen::Matrix3d next;
      if (e.from == a) {
        // b = a (+) z (+) delta, delta in b's frame.
        const Pose2 z = ra.Between(rb);
        const Eigen::Matrix3d j = ComposeJacobianA(ra, z);
        next = j * cov[ua] * j.transpose() + RotateCovariance(edge_cov, rb.theta_rad);
      } else {
        // a = b (+) z (+) delta (the edge runs from b to a), so b = (a (+) delta^-1) (+) z^-1:
        // a's covariance grown by delta (in a's frame), then carried to b.
        const Eigen::Matrix3d grown = cov[ua] + RotateCovariance(edge_cov, ra.theta_rad);
        const Pose2 z_inv = ra.Between(rb);
        const Eigen::Matrix3d j = ComposeJacobianA(ra, z_inv);
        next = j * grown * j.transpose();
      }
      next = 0.5 * (next + next.transpose());
      const double t = next(0, 0) + next(1, 1);
      if (t < cov[ub](0, 0) + cov[ub](1, 1)) {
        cov[ub] = next;
        queue.push({t, b});
      }
    }
  }
  return cov;
}

}  // namespace snapnav::nav
