#include "snapnav/nav/slam/graph_slam.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "snapnav/nav/slam/cell_key.hpp"
#include "snapnav/nav/slam/map_matcher.hpp"

namespace snapnav::nav {
namespace {

double MaxPositionSigma(const Eigen::Matrix3d& c) {
  const Eigen::Matrix2d xy = 0.5 * (c.topLeftCorner<2, 2>() + c.topLeftCorner<2, 2>().transpose());
  if (!xy.allFinite()) return std::numeric_limits<double>::infinity();
  const double tr = xy.trace(), det = xy.determinant();
  const double disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
  return std::sqrt(std::max(0.0, tr / 2 + disc));
}

Eigen::Matrix3d ClampPsd(const Eigen::Matrix3d& m) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (m + m.transpose()));
  const Eigen::Vector3d d = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * d.asDiagonal() * es.eigenvectors().transpose();
}

Eigen::Vector3d Difference(const Pose2& a, const Pose2& b) {  // a - b, additive, heading wrapped
  return {a.x_m - b.x_m, a.y_m - b.y_m, WrapAngle(a.theta_rad - b.theta_rad)};
}

// The covariance of r^-1 from r's (additive x, y, theta in the parent's axes).
Eigen::Matrix3d InverseCovariance(const Pose2& r, const Eigen::Matrix3d& c) {
  const double cs = std::cos(r.theta_rad), sn = std::sin(r.theta_rad);
  Eigen::Matrix3d j;
  j << -cs, -sn, sn * r.x_m - cs * r.y_m, sn, -cs, cs * r.x_m + sn * r.y_m, 0, 0, -1;
  return j * c * j.transpose();
}

}  // namespace

void GraphSlamOptions::Validate() const {
  // Each option checked on its own, the message naming it as the config's key does (without the
  // "graph_" prefix), so a refusal points at one line of the file.
  const auto require = [](bool ok, const char* name, const char* rule) {
    if (!ok) throw std::invalid_argument(std::string("graph slam: ") + name + " " + rule);
  };
  const auto nonneg = [](double v) { return v >= 0 && std::isfinite(v); };
  const auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  const auto fraction = [](double v) { return v >= 0 && v <= 1; };
  require(positive(keyframe_distance_m), "keyframe_distance_m", "must be > 0");
  require(positive(keyframe_angle_rad), "keyframe_angle_deg", "must be > 0");
  require(nonneg(keyframe_reuse_m), "keyframe_reuse_m", "must be >= 0");
  require(nonneg(keyframe_reuse_rad), "keyframe_reuse_deg", "must be >= 0");
  require(keyframes_per_place >= 1, "keyframes_per_place", "must be >= 1");
  require(nonneg(edge_sigma_xy_m), "edge_sigma_xy_m", "must be >= 0");
  require(nonneg(edge_sigma_xy_per_m), "edge_sigma_xy_per_m", "must be >= 0");
  require(nonneg(edge_sigma_theta_rad), "edge_sigma_theta_deg", "must be >= 0");
  require(nonneg(edge_sigma_theta_per_m), "edge_sigma_theta_deg_per_m", "must be >= 0");
  require(edge_sigma_xy_m + edge_sigma_xy_per_m > 0, "edge_sigma_xy_m",
          "and edge_sigma_xy_per_m must not both be 0 (an edge would be exact)");
  require(edge_sigma_theta_rad + edge_sigma_theta_per_m > 0, "edge_sigma_theta_deg",
          "and edge_sigma_theta_deg_per_m must not both be 0 (an edge would be exact)");
  require(nonneg(local_map_m), "local_map_m", "must be >= 0");
  require(nonneg(frontend_reset_m), "frontend_reset_m", "must be >= 0");
  require(nonneg(frontend_reset_rad), "frontend_reset_deg", "must be >= 0");
  require(nonneg(loop_min_travel_m), "loop_min_travel_m", "must be >= 0");
  require(nonneg(loop_distance_m), "loop_distance_m", "must be >= 0");
  require(positive(loop_search_sigmas), "loop_search_sigmas", "must be > 0");
  require(nonneg(loop_window_min_m), "loop_window_min_m", "must be >= 0");
  require(loop_window_max_m >= loop_window_min_m && loop_window_max_m <= 50, "loop_window_max_m",
          "must be in [loop_window_min_m, 50]");
  require(nonneg(loop_window_min_rad), "loop_window_min_deg", "must be >= 0");
  require(loop_window_max_rad >= loop_window_min_rad && loop_window_max_rad <= 3.15, "loop_window_max_deg",
          "must be in [loop_window_min_deg, 180]");
  require(nonneg(loop_submap_sigma_m), "loop_submap_sigma_m", "must be >= 0");
  require(positive(loop_submap_m), "loop_submap_m", "must be > 0");
  require(positive(loop_max_range_m), "loop_max_range_m", "must be > 0");
  require(loop_candidates >= 0, "loop_candidates", "must be >= 0");
  require(positive(loop_search.cell_m), "loop_cell_m", "must be > 0");
  require(positive(loop_search.sigma_m), "loop_sigma_m", "must be > 0");
  require(loop_search.levels >= 0 && loop_search.levels <= 8, "loop_levels", "must be in [0, 8]");
  require(positive(loop_search.step_rad), "loop_step_deg", "must be > 0");
  require(nonneg(loop_search.exclusion_m), "loop_exclusion_m", "must be >= 0");
  require(nonneg(loop_search.exclusion_rad), "loop_exclusion_deg", "must be >= 0");
  require(loop_search.ambiguity_floor > 0 && loop_search.ambiguity_floor <= 1, "loop_ambiguity_floor",
          "must be in (0, 1]");
  require(nonneg(loop_scan_cell_m), "loop_scan_cell_m", "must be >= 0");
  require(nonneg(loop_query_m), "loop_query_m", "must be >= 0");
  require(nonneg(loop_max_turn_rate_rad_s), "loop_max_turn_rate_deg_s", "must be >= 0");
  require(fraction(loop_min_score), "loop_min_score", "must be in [0, 1]");
  require(fraction(loop_min_fit), "loop_min_fit", "must be in [0, 1]");
  require(loop_max_ambiguity > 0 && loop_max_ambiguity <= 1, "loop_max_ambiguity", "must be in (0, 1]");
  require(fraction(loop_alone_min_score), "loop_alone_min_score", "must be in [0, 1]");
  require(positive(loop_gate_mahalanobis2), "loop_gate_mahalanobis2", "must be > 0");
  require(nonneg(loop_confident_sigma_m), "loop_confident_sigma_m", "must be >= 0");
  require(loop_pending_keyframes >= 0, "loop_pending_keyframes", "must be >= 0");
  require(positive(loop_sigma_xy_m), "loop_sigma_xy_m", "must be > 0");
  require(positive(loop_sigma_theta_rad), "loop_sigma_theta_deg", "must be > 0");
  require(optimizer_iterations >= 1, "optimizer_iterations", "must be >= 1");
  require(nonneg(closure_chi2_max), "closure_chi2_max", "must be >= 0");
  require(nonneg(optimize_min_m), "optimize_min_m", "must be >= 0");
  require(nonneg(optimize_min_rad), "optimize_min_deg", "must be >= 0");
  require(optimize_every >= 1, "optimize_every", "must be >= 1");
  require(loop_async_scans >= 1, "loop_async_scans", "must be >= 1");
}

const char* LoopOutcomeName(LoopOutcome o) {
  switch (o) {
    case LoopOutcome::kAccepted: return "accepted";
    case LoopOutcome::kPending: return "pending";
    case LoopOutcome::kLowScore: return "low_score";
    case LoopOutcome::kAmbiguous: return "ambiguous";
    case LoopOutcome::kGated: return "gated";
    case LoopOutcome::kExpired: return "expired";
    case LoopOutcome::kSwitchedOff: return "switched_off";
  }
  return "?";
}

namespace {

// The graph's front end: the EKF's, its walls' heading measurement and heading floor included (with
// them the graph's geometric mean ATE over the 101 real runs went from 0.136 to 0.119 m,
// docs/experiments/2026-12-07-graph-front-end-walls.md), but without applying the odometry
// calibration (estimated all the same): its narrower prediction makes the keyframe edges'
// covariances narrower, and the graph lost 3-8 of 76 runs within its goal
// (docs/experiments/2026-12-07-odometry-calibration.md).
LaserSlamOptions GraphFrontEnd(LaserSlamOptions o) {
  o.odometry_calibration.apply = false;
  return o;
}

}  // namespace

GraphSlam::GraphSlam(const LaserSlamOptions& front_end, const GraphSlamOptions& options, const Pose2& start)
    : front_options_(GraphFrontEnd(front_end)), options_(options), front_(front_options_, start), start_(start) {
  options_.Validate();
  last_posterior_ = front_.covariance();
}

GraphSlam::~GraphSlam() {
  if (worker_.joinable()) worker_.join();
}

GraphSlamUpdate GraphSlam::Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime) {
  GraphSlamUpdate u = FrontEnd(points_robot, utime);
  BackEnd(&u);
  return u;
}

GraphSlamUpdate GraphSlam::Update(const std::vector<Eigen::Vector2d>& points_robot) {
  GraphSlamUpdate u = FrontEnd(points_robot);
  BackEnd(&u);
  return u;
}

GraphSlamUpdate GraphSlam::FrontEnd(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime) {
  if (pending_front_) throw std::logic_error("graph slam: FrontEnd twice without BackEnd");
  const Pose2 before = front_.scan_pose();
  const LaserSlamUpdate fu = front_.Update(points_robot, utime);
  turn_rate_rad_s_ = 0;
  if (last_scan_utime_ && utime > *last_scan_utime_) {
    turn_rate_rad_s_ = std::abs(WrapAngle(front_.scan_pose().theta_rad - before.theta_rad)) /
                       (1e-6 * static_cast<double>(utime - *last_scan_utime_));
  }
  last_scan_utime_ = utime;
  return AfterFrontEnd(fu, points_robot);
}

GraphSlamUpdate GraphSlam::FrontEnd(const std::vector<Eigen::Vector2d>& points_robot) {
  if (pending_front_) throw std::logic_error("graph slam: FrontEnd twice without BackEnd");
  turn_rate_rad_s_ = 0;
  return AfterFrontEnd(front_.Update(points_robot), points_robot);
}

GraphSlamUpdate GraphSlam::AfterFrontEnd(const LaserSlamUpdate& front_update,
                                         const std::vector<Eigen::Vector2d>& points_robot) {
  GraphSlamUpdate u;
  u.front_end = front_update;
  pending_points_.clear();
  // The front end's uncertainty relative to the last keyframe (map frame's axes), a filter of its
  // own beside the EKF's: the EKF's prediction noise this scan (its covariance's growth) adds to
  // it, an accepted match's measurement narrows it.
  {
    const bool accepted = front_update.measured;
    const Eigen::Matrix3d predicted = accepted ? front_update.predicted_covariance : front_.covariance();
    const Eigen::Matrix3d growth = ClampPsd(predicted - last_posterior_);
    relative_covariance_ += growth;
    if (accepted) {
      const Eigen::Matrix3d eps = Eigen::Vector3d(1e-12, 1e-12, 1e-12).asDiagonal();
      relative_covariance_ =
          ((relative_covariance_ + eps).inverse() + (front_update.measurement_covariance + eps).inverse()).inverse();
      relative_covariance_ = 0.5 * (relative_covariance_ + relative_covariance_.transpose());
    }
    last_posterior_ = front_.covariance();
  }
  const Pose2 sp = front_.scan_pose();
  if (have_scan_) {
    const Pose2 moved = last_scan_front_.Between(sp);
    travel_m_ += std::hypot(moved.x_m, moved.y_m);
  }
  last_scan_front_ = sp;
  have_scan_ = true;
  if (last_keyframe_ < 0) {
    u.keyframe = true;
  } else {
    const Pose2 d = last_keyframe_front_.Between(sp);
    u.keyframe = std::hypot(d.x_m, d.y_m) >= options_.keyframe_distance_m ||
                 std::abs(d.theta_rad) >= options_.keyframe_angle_rad;
  }
  if (u.keyframe && last_keyframe_ >= 0 && options_.keyframe_reuse_m > 0 &&
      front_update.outcome == MatchOutcome::kAccepted) {
    const int j = ReusableKeyframe(ToGraph(sp));
    if (j >= 0) {
      // The scan's pose kept relative to keyframe j from now on: the front end's frame pose of j
      // such that ToGraph stays as it was (no jump), the uncertainty relative to it that of a new keyframe.
      last_keyframe_front_ = last_keyframe_front_.Compose(graph_.pose(last_keyframe_).Between(graph_.pose(j)));
      last_keyframe_ = j;
      relative_covariance_.setZero();
      u.keyframe = false;
      u.reused_keyframe = true;
      ++keyframe_reuses_;
    }
  }
  if (u.keyframe) {
    pending_points_ = points_robot;
    u.anchor_keyframe = graph_.nodes();
  } else {
    u.anchor_keyframe = last_keyframe_;
    u.anchor_relative = last_keyframe_front_.Between(sp);
  }
  pending_front_ = true;
  return u;
}

void GraphSlam::BackEnd(GraphSlamUpdate* u) {
  if (!pending_front_) throw std::logic_error("graph slam: BackEnd without FrontEnd");
  pending_front_ = false;
  // A job that ran loop_async_scans scans is applied now (waiting for the worker if it is not done).
  if (job_running_ && ++job_scans_ >= options_.loop_async_scans) ApplyJob(u);
  if (u->keyframe) {
    AddKeyframe(pending_points_, u);
    pending_points_.clear();
    if (options_.local_map_m > 0 && travel_m_ - map_built_travel_m_ >= 0.5 * options_.local_map_m) {
      RebuildFrontEndMap();
    }
    todo_.push_back(last_keyframe_);
  }
  if (job_running_ || todo_.empty()) return;
  StartJob();
  if (!options_.loop_async) {
    RunJob();
    ApplyJob(u);
  }
}

GraphSlamUpdate GraphSlam::Flush() {
  GraphSlamUpdate u;
  if (job_running_) ApplyJob(&u);
  return u;
}

void GraphSlam::StartJob() {
  job_ = Job{};
  job_.graph = graph_;
  job_.keyframes = keyframes_;
  job_.todo.swap(todo_);
  job_.nodes_at_start = graph_.nodes();
  job_.edges_at_start = static_cast<int>(graph_.edges().size());
  job_running_ = true;
  job_scans_ = 0;
  if (options_.loop_async) worker_ = std::thread([this] { RunJob(); });
}

void GraphSlam::RunJob() {
  try {
    for (const int kf : job_.todo) {
      // Pending closures that waited too long.
      while (!pending_.empty() &&
             closures_[static_cast<size_t>(pending_.front())].to_keyframe + options_.loop_pending_keyframes < kf) {
        closures_[static_cast<size_t>(pending_.front())].outcome = LoopOutcome::kExpired;
        ++loop_rejected_;
        ++job_.loop_rejected;
        job_.closures_changed = true;
        pending_.pop_front();
      }
      SearchLoops(kf);
      if (optimize_due_ || (unoptimized_closures_ > 0 && unoptimized_closures_ >= options_.optimize_every)) Optimize();
    }
    if (job_.optimized) {
      // The front end's map at the optimized poses, in case the correction calls for it (ApplyJob).
      const int n0 = job_.nodes_at_start;
      const double travel = job_.keyframes[static_cast<size_t>(n0 - 1)]->travel_m;
      const double min_travel =
          options_.local_map_m > 0 ? travel - options_.local_map_m : -std::numeric_limits<double>::infinity();
      PointGridMap map = LaserSlam::MakeMap(front_options_);
      AddKeyframesToMap(job_.graph, job_.keyframes, 0, n0 - 1, min_travel, &map);
      job_.front_map = std::move(map);
    }
  } catch (...) {
    job_.error = std::current_exception();
  }
}

void GraphSlam::ApplyJob(GraphSlamUpdate* u) {
  if (worker_.joinable()) worker_.join();
  job_running_ = false;
  if (job_.error) std::rethrow_exception(job_.error);
  u->loop_candidates += job_.loop_candidates;
  u->loop_accepted += job_.loop_accepted;
  u->loop_rejected += job_.loop_rejected;
  u->optimizer_iterations += job_.optimizer_iterations;
  if (job_.closures_changed) shown_.closures = closures_;
  shown_.loop_accepted = loop_accepted_;
  shown_.loop_rejected = loop_rejected_;
  shown_.optimizations = optimizations_;
  if (job_.loop_accepted == 0 && !job_.optimized) return;  // the graph is as it was
  // The job's graph, then the keyframes that joined since (and their edges): each follows the
  // correction of the keyframe its edge comes from (the one before it, or a reused one).
  const Pose2 before = pose();
  PoseGraph g = std::move(job_.graph);
  const int n0 = job_.nodes_at_start;
  const bool same_nodes = graph_.nodes() == n0;
  std::vector<Pose2> correction(static_cast<size_t>(graph_.nodes()));
  for (int n = 0; n < n0; ++n) correction[static_cast<size_t>(n)] = g.pose(n).Compose(graph_.pose(n).Inverse());
  for (size_t e = static_cast<size_t>(job_.edges_at_start); e < graph_.edges().size(); ++e) {
    const PoseGraphEdge& edge = graph_.edges()[e];  // (only odometry edges join the live graph: from < to)
    if (edge.to >= n0) correction[static_cast<size_t>(edge.to)] = correction[static_cast<size_t>(edge.from)];
  }
  for (int n = n0; n < graph_.nodes(); ++n) g.AddNode(correction[static_cast<size_t>(n)].Compose(graph_.pose(n)));
  for (size_t e = static_cast<size_t>(job_.edges_at_start); e < graph_.edges().size(); ++e) {
    const PoseGraphEdge& edge = graph_.edges()[e];
    const int index = g.AddEdge(edge.from, edge.to, edge.mean, edge.information, edge.kind);
    if (!edge.enabled) g.SetEnabled(index, false);
  }
  graph_ = std::move(g);
  if (!job_.optimized) return;
  ++graph_version_;
  const Pose2 after = pose();
  u->corrected = true;
  u->correction_m = std::hypot(after.x_m - before.x_m, after.y_m - before.y_m);
  u->correction_rad = std::abs(WrapAngle(after.theta_rad - before.theta_rad));
  ++corrections_;
  last_correction_m_ = u->correction_m;
  last_correction_rad_ = u->correction_rad;
  if (u->correction_m >= options_.frontend_reset_m || u->correction_rad >= options_.frontend_reset_rad) {
    // The worker's map of the keyframes it knew, the ones that joined since added here. (With
    // local_map_m its travel window is the last known keyframe's: rebuilt from scratch when
    // keyframes joined since.)
    if (job_.front_map && (same_nodes || options_.local_map_m <= 0)) {
      RebuildFrontEndMap(std::move(job_.front_map), n0);
    } else {
      RebuildFrontEndMap();
    }
  }
  job_.front_map.reset();
}

int GraphSlam::ReusableKeyframe(const Pose2& pose) const {
  std::vector<std::pair<double, int>> near;  // (distance, keyframe)
  for (int k = 0; k < graph_.nodes(); ++k) {
    if (k == last_keyframe_) continue;
    const Pose2& q = graph_.pose(k);
    const double d = std::hypot(q.x_m - pose.x_m, q.y_m - pose.y_m);
    if (d > options_.keyframe_reuse_m || std::abs(WrapAngle(q.theta_rad - pose.theta_rad)) > options_.keyframe_reuse_rad) {
      continue;
    }
    near.push_back({d, k});
  }
  if (near.size() < static_cast<size_t>(options_.keyframes_per_place)) return -1;  // (keyframes_per_place >= 1)
  std::sort(near.begin(), near.end());
  // Only where the graph knows the keyframe's position relative to the last one (as a closure may
  // join alone: loop_confident_sigma_m); where it does not (drift since the last closure), a new
  // keyframe joins and the loop search runs.
  const std::vector<Eigen::Matrix3d> from_last = graph_.RelativeCovariances(last_keyframe_);
  for (const auto& [d, k] : near) {
    if (MaxPositionSigma(from_last[static_cast<size_t>(k)]) <= options_.loop_confident_sigma_m) return k;
  }
  return -1;
}

void GraphSlam::NoteClosure(const LoopClosure& c) {
  ++unoptimized_closures_;
  const Eigen::Vector3d e = Difference(c.relative, c.predicted);
  if (std::hypot(e.x(), e.y()) >= options_.optimize_min_m || std::abs(e.z()) >= options_.optimize_min_rad) {
    optimize_due_ = true;
  }
}

void GraphSlam::AddKeyframe(const std::vector<Eigen::Vector2d>& points, GraphSlamUpdate* u) {
  const Pose2 sp = front_.scan_pose();
  Keyframe k;
  k.scan = front_.scans();
  k.travel_m = travel_m_;
  const double max_range2 = front_options_.max_range_m > 0 ? front_options_.max_range_m * front_options_.max_range_m
                                                            : std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < points.size(); i += static_cast<size_t>(front_options_.scan_step)) {
    if (points[i].squaredNorm() <= max_range2) k.points.push_back(points[i]);
  }
  k.normals = ScanNormals(k.points);
  std::vector<Eigen::Vector2d> near;
  const double loop_range2 = options_.loop_max_range_m * options_.loop_max_range_m;
  for (const Eigen::Vector2d& p : k.points) {
    if (p.squaredNorm() <= loop_range2) near.push_back(p);
  }
  k.search_points = DecimatePoints(near, options_.loop_scan_cell_m);
  k.turn_rate_rad_s = turn_rate_rad_s_;
  int id;
  if (last_keyframe_ < 0) {
    id = graph_.AddNode(sp);  // the graph's frame is the front end's at the start
  } else {
    const Pose2 mean = last_keyframe_front_.Between(sp);
    const double dist = std::hypot(mean.x_m, mean.y_m);
    const double sxy = options_.edge_sigma_xy_m + options_.edge_sigma_xy_per_m * dist;
    const double sth = options_.edge_sigma_theta_rad + options_.edge_sigma_theta_per_m * dist;
    // The front end's uncertainty relative to the keyframe before, in that keyframe's axes.
    Eigen::Matrix3d cov = RotateCovariance(relative_covariance_, -last_keyframe_front_.theta_rad);
    cov += Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal();
    id = graph_.AddNode(graph_.pose(last_keyframe_).Compose(mean));
    graph_.AddEdge(last_keyframe_, id, mean, ToFrameInformation(mean, cov), PoseGraphEdgeKind::kOdometry);
  }
  keyframes_.push_back(std::make_shared<const Keyframe>(std::move(k)));
  relative_covariance_.setZero();
  last_keyframe_ = id;
  last_keyframe_front_ = sp;
  u->anchor_keyframe = id;
  u->anchor_relative = {};
}

void GraphSlam::RebuildFrontEndMap(std::optional<PointGridMap> prebuilt, int prebuilt_nodes) {
  // The front end moves into the graph's frame (its pose with every correction), then its map is
  // the keyframes' points at their optimized poses (the newest first: theirs are kept where two meet).
  const Pose2 now = pose();
  const double dtheta = WrapAngle(now.theta_rad - front_.pose().theta_rad);
  front_.ResetPose(now, RotateCovariance(front_.covariance(), dtheta));
  last_posterior_ = front_.covariance();
  last_scan_front_ = front_.scan_pose();
  last_keyframe_front_ = graph_.pose(last_keyframe_);
  const double min_travel =
      options_.local_map_m > 0 ? travel_m_ - options_.local_map_m : -std::numeric_limits<double>::infinity();
  PointGridMap map = prebuilt ? std::move(*prebuilt) : LaserSlam::MakeMap(front_options_);
  AddKeyframesToMap(graph_, keyframes_, prebuilt ? prebuilt_nodes : 0, graph_.nodes() - 1, min_travel, &map);
  front_.ResetMap(std::move(map));
  map_built_travel_m_ = travel_m_;
}

void GraphSlam::AddKeyframesToMap(const PoseGraph& g, const Keyframes& ks, int first, int last, double min_travel_m,
                                  PointGridMap* map) const {
  for (int k = last; k >= first; --k) {
    const Keyframe& kf = *ks[static_cast<size_t>(k)];
    if (kf.travel_m < min_travel_m) continue;
    const Pose2& p = g.pose(k);
    const double c = std::cos(p.theta_rad), s = std::sin(p.theta_rad);
    for (size_t i = 0; i < kf.points.size(); ++i) {
      const Eigen::Vector2d& n = kf.normals[i];
      LaserSlam::AddMapPoint(front_options_, p.Transform(kf.points[i]), {c * n.x() - s * n.y(), s * n.x() + c * n.y()},
                             map);
    }
  }
}

const GraphSlam::Submap& GraphSlam::SubmapAt(int keyframe) {
  Submap& s = submaps_[keyframe];
  const Pose2 origin = job_.graph.pose(keyframe);
  if (s.pyramid && s.version != loop_version_) {
    // An optimization since: the submap stands if its keyframes kept their poses relative to the
    // centre (within half a cell and 0.2 degrees).
    bool kept = true;
    for (const auto& [k, rel] : s.members) {
      const Pose2 now = origin.Between(job_.graph.pose(k));
      if (std::hypot(now.x_m - rel.x_m, now.y_m - rel.y_m) > 0.5 * options_.loop_search.cell_m ||
          std::abs(WrapAngle(now.theta_rad - rel.theta_rad)) > 0.2 * kRadPerDeg) {
        kept = false;
        break;
      }
    }
    if (kept) s.version = loop_version_;
  }
  if (s.version == loop_version_ && s.pyramid) return s;
  s.members.clear();
  const Keyframe& centre = (*job_.keyframes[static_cast<size_t>(keyframe)]);
  std::vector<Eigen::Vector2d> points, normals, search;
  const double range2 = options_.loop_max_range_m * options_.loop_max_range_m;
  std::vector<Eigen::Matrix3d> from_centre;
  if (options_.loop_submap_sigma_m > 0) from_centre = job_.graph.RelativeCovariances(keyframe);
  for (int k = 0; k < job_.graph.nodes(); ++k) {
    const Keyframe& kf = (*job_.keyframes[static_cast<size_t>(k)]);
    if (std::abs(kf.travel_m - centre.travel_m) > options_.loop_submap_m) continue;
    if (!from_centre.empty() && MaxPositionSigma(from_centre[static_cast<size_t>(k)]) > options_.loop_submap_sigma_m) {
      continue;
    }
    const Pose2 rel = origin.Between(job_.graph.pose(k));
    s.members.push_back({k, rel});
    const double c = std::cos(rel.theta_rad), sn = std::sin(rel.theta_rad);
    std::vector<Eigen::Vector2d> in_range;
    for (size_t i = 0; i < kf.points.size(); ++i) {
      if (kf.points[i].squaredNorm() > range2) continue;
      in_range.push_back(kf.points[i]);
      points.push_back(rel.Transform(kf.points[i]));
      const Eigen::Vector2d& n = kf.normals[i];
      normals.emplace_back(c * n.x() - sn * n.y(), sn * n.x() + c * n.y());
    }
    // The likelihood grid's walls as lines (ScanNormals' gap), not rows of far, sparse points.
    for (const Eigen::Vector2d& q : DensifyScan(in_range, 0.3, 0.5 * options_.loop_search.cell_m)) {
      search.push_back(rel.Transform(q));
    }
  }
  // (ICP from the search's pose, a cell and a search step away: buckets as wide as its first match distance.)
  s.map = std::make_unique<PointGridMap>(front_options_.map_resolution_m, LoopIcpOptions().match_distance_start_m);
  for (size_t i = 0; i < points.size(); ++i) s.map->Add(points[i], normals[i]);
  s.pyramid = std::make_unique<LikelihoodPyramid>(DecimatePoints(search, 0.5 * options_.loop_search.cell_m),
                                                  options_.loop_search, 0.0);
  s.version = loop_version_;
  // Keep the cache small: at most 64 submaps, those of older versions first out.
  while (submaps_.size() > 64) {
    auto oldest = submaps_.begin();
    for (auto it = submaps_.begin(); it != submaps_.end(); ++it) {
      if (it->first != keyframe && (oldest->first == keyframe || it->second.version < oldest->second.version)) oldest = it;
    }
    submaps_.erase(oldest);
  }
  return submaps_[keyframe];
}

MatcherOptions GraphSlam::LoopIcpOptions() const {
  // The front end's ICP, from the correlative search's pose: its first match distance need only
  // cover the search's grid (a cell, a heading step), not a prediction's error.
  MatcherOptions o = front_options_;
  o.match_distance_start_m = std::max(o.match_distance_m, std::min(o.match_distance_start_m, 0.3));
  return o;
}

GraphSlam::Query GraphSlam::MakeQuery(int kf) const {
  Query q;
  const Keyframe& now = (*job_.keyframes[static_cast<size_t>(kf)]);
  if (options_.loop_query_m <= 0) {
    q.search = now.search_points;
    q.points = now.points;
    q.normals = now.normals;
    return q;
  }
  const Pose2 origin = job_.graph.pose(kf);
  const double range2 = options_.loop_max_range_m * options_.loop_max_range_m;
  std::vector<Eigen::Vector2d> near, points, normals;
  for (int k = kf; k >= 0; --k) {
    const Keyframe& kk = (*job_.keyframes[static_cast<size_t>(k)]);
    if (kk.travel_m < now.travel_m - options_.loop_query_m) break;
    const Pose2 rel = origin.Between(job_.graph.pose(k));
    const double c = std::cos(rel.theta_rad), sn = std::sin(rel.theta_rad);
    for (size_t i = 0; i < kk.points.size(); ++i) {
      const Eigen::Vector2d p = rel.Transform(kk.points[i]);
      if (kk.points[i].squaredNorm() <= range2) near.push_back(p);
      points.push_back(p);
      const Eigen::Vector2d& n = kk.normals[i];
      normals.emplace_back(c * n.x() - sn * n.y(), sn * n.x() + c * n.y());
    }
  }
  q.search = DecimatePoints(near, options_.loop_scan_cell_m);
  // ICP's points: one per map cell (the newest keyframe's first), with their normals.
  std::unordered_set<uint64_t> taken;
  const double cell = front_options_.map_resolution_m;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!taken.insert(CellKey(points[i], cell)).second) continue;
    q.points.push_back(points[i]);
    q.normals.push_back(normals[i]);
  }
  return q;
}

LoopClosure GraphSlam::MatchCandidate(int old_kf, int kf, const Query& query,
                                      const std::vector<Eigen::Matrix3d>& from_new) {
  LoopClosure c;
  c.from_keyframe = old_kf;
  c.to_keyframe = kf;
  c.from_scan = (*job_.keyframes[static_cast<size_t>(old_kf)]).scan;
  c.to_scan = (*job_.keyframes[static_cast<size_t>(kf)]).scan;
  const Pose2 r_old = job_.graph.pose(kf).Between(job_.graph.pose(old_kf));  // old in the new one's frame
  c.predicted = r_old.Inverse();
  const Eigen::Matrix3d predicted_cov = InverseCovariance(r_old, from_new[static_cast<size_t>(old_kf)]);
  c.graph_sigma_m = MaxPositionSigma(predicted_cov);
  const double k = options_.loop_search_sigmas;
  const double window_xy = std::clamp(k * c.graph_sigma_m, options_.loop_window_min_m, options_.loop_window_max_m);
  const double window_th = std::clamp(k * std::sqrt(std::max(0.0, predicted_cov(2, 2))), options_.loop_window_min_rad,
                                      options_.loop_window_max_rad);
  const Submap& submap = SubmapAt(old_kf);
  const CorrelativeSearchResult found = BranchAndBoundSearch(*submap.pyramid, query.search, c.predicted, window_xy,
                                                             window_th, options_.loop_min_score, options_.loop_search);
  c.outcome = LoopOutcome::kLowScore;
  if (!found.found) return c;
  c.score = found.score;
  c.ambiguity = found.second_found && found.score > 0 ? found.second_score / found.score : 0.0;
  const MatcherOptions icp_options = LoopIcpOptions();
  const MapMatcher matcher(*submap.map, icp_options);
  const MapMatcher::Icp icp = matcher.Align(found.pose, query.points, query.normals);
  if (!icp.ok) return c;
  c.relative = icp.estimate;
  c.fit = matcher.Fit(icp.estimate, query.points, 1);
  c.score = submap.pyramid->Score(icp.estimate, query.search);
  Eigen::Matrix3d info = icp.info / std::max(1.0, icp.residual2 / std::max(1e-9, icp.weight_sum));
  info += Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();
  c.covariance = info.inverse();
  c.covariance += Eigen::Vector3d(options_.loop_sigma_xy_m * options_.loop_sigma_xy_m,
                                  options_.loop_sigma_xy_m * options_.loop_sigma_xy_m,
                                  options_.loop_sigma_theta_rad * options_.loop_sigma_theta_rad)
                      .asDiagonal();
  c.covariance = 0.5 * (c.covariance + c.covariance.transpose());
  const Eigen::Vector3d e = Difference(c.relative, c.predicted);
  c.mahalanobis2 = e.dot((predicted_cov + c.covariance).inverse() * e);
  if (c.score < options_.loop_min_score || c.fit < options_.loop_min_fit) {
    c.outcome = LoopOutcome::kLowScore;
  } else if (c.ambiguity > options_.loop_max_ambiguity) {
    c.outcome = LoopOutcome::kAmbiguous;
  } else if (!(c.mahalanobis2 <= options_.loop_gate_mahalanobis2)) {
    c.outcome = LoopOutcome::kGated;
  } else {
    const bool alone = c.graph_sigma_m <= options_.loop_confident_sigma_m && c.score >= options_.loop_alone_min_score;
    c.outcome = alone ? LoopOutcome::kAccepted : LoopOutcome::kPending;
  }
  return c;
}

bool GraphSlam::PairConsistent(const LoopClosure& a, const LoopClosure& b) const {
  // The cycle a.to -> a.from (closure a) -> b.from (graph) -> b.to (closure b) against the graph's
  // a.to -> b.to.
  const Pose2 g_from = job_.graph.pose(a.from_keyframe).Between(job_.graph.pose(b.from_keyframe));
  const Pose2 g_to = job_.graph.pose(a.to_keyframe).Between(job_.graph.pose(b.to_keyframe));
  const Pose2 cycle = a.relative.Inverse().Compose(g_from).Compose(b.relative);
  const Eigen::Vector3d e = Difference(cycle, g_to);
  // Covariances, each turned into a.to's axes (first order; lever arms of the short graph parts left out).
  const auto from_a_from = job_.graph.RelativeCovariances(a.from_keyframe);
  const auto from_a_to = job_.graph.RelativeCovariances(a.to_keyframe);
  const double th_a_to = job_.graph.pose(a.to_keyframe).theta_rad;
  const double th_a_from = job_.graph.pose(a.from_keyframe).theta_rad;
  const double th_b_from = job_.graph.pose(b.from_keyframe).theta_rad;
  Eigen::Matrix3d s = RotateCovariance(a.covariance, th_a_from - th_a_to);
  s += RotateCovariance(b.covariance, th_b_from - th_a_to);
  s += RotateCovariance(from_a_from[static_cast<size_t>(b.from_keyframe)], th_a_from - th_a_to);
  s += from_a_to[static_cast<size_t>(b.to_keyframe)];
  if (!s.allFinite()) return false;
  return e.dot(s.inverse() * e) <= options_.loop_gate_mahalanobis2;
}

void GraphSlam::SearchLoops(int kf) {
  if (options_.loop_candidates == 0) return;
  const Keyframe& now = (*job_.keyframes[static_cast<size_t>(kf)]);
  if (now.travel_m < options_.loop_min_travel_m || now.search_points.empty()) return;
  const auto turning = [&](const Keyframe& k) {
    return options_.loop_max_turn_rate_rad_s > 0 && k.turn_rate_rad_s > options_.loop_max_turn_rate_rad_s;
  };
  if (turning(now)) return;
  const std::vector<Eigen::Matrix3d> from_new = job_.graph.RelativeCovariances(kf);
  const Pose2 p = job_.graph.pose(kf);
  // Candidates: old keyframes within reach; of each run of consecutive ones (one place), the nearest.
  struct Candidate {
    int keyframe;
    double distance;
  };
  std::vector<Candidate> best_of_runs;
  int run_end = -2;
  for (int i = 0; i < kf; ++i) {
    const Keyframe& old = (*job_.keyframes[static_cast<size_t>(i)]);
    if (old.travel_m > now.travel_m - options_.loop_min_travel_m) break;
    if (turning(old)) continue;
    const double sigma = MaxPositionSigma(from_new[static_cast<size_t>(i)]);
    if (!std::isfinite(sigma)) continue;
    const Pose2& q = job_.graph.pose(i);
    const double d = std::hypot(q.x_m - p.x_m, q.y_m - p.y_m);
    const double reach =
        options_.loop_distance_m + std::min(options_.loop_search_sigmas * sigma, options_.loop_window_max_m);
    if (d > reach) continue;
    if (i == run_end + 1 && !best_of_runs.empty()) {
      if (d < best_of_runs.back().distance) best_of_runs.back() = {i, d};
    } else {
      best_of_runs.push_back({i, d});
    }
    run_end = i;
  }
  std::sort(best_of_runs.begin(), best_of_runs.end(),
            [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
  if (best_of_runs.size() > static_cast<size_t>(options_.loop_candidates)) {
    best_of_runs.resize(static_cast<size_t>(options_.loop_candidates));
  }
  if (best_of_runs.empty()) return;
  const Query query = MakeQuery(kf);
  for (const Candidate& cand : best_of_runs) {
    LoopClosure c = MatchCandidate(cand.keyframe, kf, query, from_new);
    ++job_.loop_candidates;
    job_.closures_changed = true;
    const int index = static_cast<int>(closures_.size());
    if (c.outcome == LoopOutcome::kPending) {
      // A second, independent closure (from another keyframe) that agrees confirms both.
      for (auto it = pending_.begin(); it != pending_.end(); ++it) {
        LoopClosure& other = closures_[static_cast<size_t>(*it)];
        if (other.to_keyframe == kf || !PairConsistent(other, c)) continue;
        other.outcome = LoopOutcome::kAccepted;
        other.edge = job_.graph.AddEdge(other.from_keyframe, other.to_keyframe, other.relative,
                                    ToFrameInformation(other.relative, other.covariance),
                                    PoseGraphEdgeKind::kLoopClosure);
        ++loop_accepted_;
        ++job_.loop_accepted;
        NoteClosure(other);
        pending_.erase(it);
        c.outcome = LoopOutcome::kAccepted;
        break;
      }
    }
    if (c.outcome == LoopOutcome::kAccepted) {
      c.edge = job_.graph.AddEdge(c.from_keyframe, c.to_keyframe, c.relative, ToFrameInformation(c.relative, c.covariance),
                              PoseGraphEdgeKind::kLoopClosure);
      ++loop_accepted_;
      ++job_.loop_accepted;
      NoteClosure(c);
    } else if (c.outcome == LoopOutcome::kPending) {
      pending_.push_back(index);
    } else {
      ++loop_rejected_;
      ++job_.loop_rejected;
    }
    closures_.push_back(c);
  }
}

void GraphSlam::Optimize() {
  PoseGraphOptimizeOptions o;
  o.max_iterations = options_.optimizer_iterations;
  o.closure_chi2_max = options_.closure_chi2_max;
  const PoseGraphOptimizeResult r = job_.graph.Optimize(o);
  ++optimizations_;
  unoptimized_closures_ = 0;
  optimize_due_ = false;
  ++loop_version_;
  job_.optimized = true;
  job_.optimizer_iterations += r.iterations;
  for (const int edge : r.switched_off) {
    for (LoopClosure& c : closures_) {
      if (c.edge != edge || c.outcome != LoopOutcome::kAccepted) continue;
      c.outcome = LoopOutcome::kSwitchedOff;
      --loop_accepted_;
      ++loop_rejected_;
      ++job_.loop_rejected;
      job_.closures_changed = true;
    }
  }
}

std::vector<Eigen::Vector2d> GraphSlam::MapPoints(double cell_m) const {
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k < graph_.nodes(); ++k) {
    const Pose2& p = graph_.pose(k);
    for (const Eigen::Vector2d& q : keyframes_[static_cast<size_t>(k)]->points) points.push_back(p.Transform(q));
  }
  return DecimatePoints(points, cell_m);
}

const std::vector<Eigen::Vector2d>& GraphSlam::Map() const {
  if (map_version_ != graph_version_) {
    map_points_.clear();
    map_cells_.clear();
    map_keyframes_ = 0;
    map_version_ = graph_version_;
  }
  const double cell = front_options_.map_resolution_m;
  for (; map_keyframes_ < graph_.nodes(); ++map_keyframes_) {
    const Pose2& p = graph_.pose(map_keyframes_);
    for (const Eigen::Vector2d& q : keyframes_[static_cast<size_t>(map_keyframes_)]->points) {
      const Eigen::Vector2d w = p.Transform(q);
      if (map_cells_.insert(CellKey(w, cell)).second) {
        map_points_.push_back(w);
      }
    }
  }
  return map_points_;
}

Pose2 GraphSlam::OptimizedPose(int anchor_keyframe, const Pose2& anchor_relative) const {
  if (anchor_keyframe < 0) return start_.Compose(anchor_relative);
  return graph_.pose(anchor_keyframe).Compose(anchor_relative);
}

}  // namespace snapnav::nav
