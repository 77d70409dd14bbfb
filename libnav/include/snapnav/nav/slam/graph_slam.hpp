#pragma once
// Laser SLAM's graph back end (issue 22; `[laser_slam] backend = graph`): the robust front end
// (LaserSlam, the EKF of issue 20) tracks the pose scan by scan; every keyframe_distance_m or
// keyframe_angle_rad of its motion a keyframe (its pose and scan) joins a pose graph (PoseGraph,
// optimized by MRPT's graph SLAM) with an edge from the keyframe before: the front end's motion
// between them and its covariance. Each new keyframe is matched against older keyframes that are
// not recent (loop_min_travel_m of travel behind) and lie within the pose uncertainty (the graph's
// relative covariance, Dijkstra projection), each as a submap of its neighbouring keyframes, by
// branch-and-bound correlative search and ICP (loop_closure.hpp). A candidate is a loop closure
// only when its score, its ambiguity (the best distinct other pose) and its consistency with the
// graph (Mahalanobis distance against the graph's relative pose and covariance) say so; while the
// graph is unsure (the relative position's std. dev. above loop_confident_sigma_m: the first
// closure of a loop) it waits for a second, independent closure that agrees with it (pairwise
// consistency) before either joins. The graph is then optimized (closures beyond closure_chi2_max
// afterwards switched off and the graph optimized again), the live pose carries the correction,
// and the front end's map is rebuilt from the optimized keyframes.
//
// Bounded work per scan: at most loop_candidates searches per keyframe (the nearest distinct
// places), one optimization per keyframe. No wall clock: the caller times FrontEnd and BackEnd.
//
// Off the scan thread (loop_async): the loop search and the optimization of a keyframe run as a
// job on a worker thread of GraphSlam's own, on a copy of the graph (the keyframes' scans shared,
// immutable); the scan thread only adds keyframes. The job's result (its closures, the optimized
// poses) joins the live graph exactly loop_async_scans scans after the job started (keyframes that
// joined meanwhile follow their predecessor's correction rigidly and are searched by the next job),
// whether the worker finished early or not (then, and only then, the scan thread waits for it): the
// outputs depend on the scans alone, not on the machine's speed, so a replay is reproducible.
// Without loop_async the job runs inside BackEnd and its result joins at once (as before).
#include <cstdint>
#include <deque>
#include <exception>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/slam/laser_slam.hpp"
#include "snapnav/nav/slam/loop_closure.hpp"
#include "snapnav/nav/slam/pose_graph.hpp"

namespace snapnav::nav {

struct GraphSlamOptions {
  // Keyframes: a new one when the front end moved this far, or turned this much, since the last.
  double keyframe_distance_m = 0.5;
  double keyframe_angle_rad = 15 * kRadPerDeg;
  // Memory that grows with the area, not with time: where a new keyframe is due but the scan's
  // pose (in the graph) lies within keyframe_reuse_m and keyframe_reuse_rad of an existing
  // keyframe, and the front end's match of the scan against its map (those keyframes' points) was
  // accepted, and the graph knows that keyframe's position relative to the last keyframe to
  // loop_confident_sigma_m (no drift since: not a loop yet to close), no keyframe joins: the scan's
  // pose is kept relative to that keyframe instead, and the next keyframe's edge starts from it. New keyframes then lie at least keyframe_reuse_m from all
  // others (as the graph placed them), so their number is bounded by the area driven (0: off).
  double keyframe_reuse_m = 0.3;
  double keyframe_reuse_rad = 30 * kRadPerDeg;
  // ... and only where at least this many keyframes already lie within keyframe_reuse_m and
  // keyframe_reuse_rad of the scan's pose (the place mapped on that many passes): the first passes
  // of a place each add their keyframes, scan-matched edges and loop searches, as without reuse,
  // and from the next pass on the place's keyframes are reused, so a place keeps at most about this
  // many keyframes however often the robot comes back (1: reuse from the first revisit).
  int keyframes_per_place = 5;
  // The edge between consecutive keyframes: the front end's motion; its covariance the front end's
  // uncertainty relative to the keyframe before (its prediction noise since, narrowed by each
  // accepted match's measurement covariance) plus this much per edge and per metre of the edge's
  // travel (the front end's own drift: its map's error, systematic matching errors; std. devs.).
  double edge_sigma_xy_m = 0.01;
  double edge_sigma_xy_per_m = 0.01;
  double edge_sigma_theta_rad = 0.2 * kRadPerDeg;
  double edge_sigma_theta_per_m = 0.2 * kRadPerDeg;
  // The front end's map: the keyframes within this much travel behind it (rebuilt every half of
  // it), so that it never closes a loop itself; 0: all keyframes (it matches against the whole map,
  // rebuilt after each correction).
  double local_map_m = 0;
  // After a correction larger than this (position or heading) the front end is moved with it and
  // its map rebuilt from the optimized keyframes; smaller ones only move the published pose.
  double frontend_reset_m = 0.05;
  double frontend_reset_rad = 0.5 * kRadPerDeg;
  // Loop closure: candidates are keyframes at least loop_min_travel_m of travel behind the new one
  // whose position lies within loop_distance_m plus loop_search_sigmas relative std. devs. of it.
  double loop_min_travel_m = 10;
  double loop_distance_m = 4;
  double loop_search_sigmas = 3;
  // The search window around the graph's relative pose: loop_search_sigmas std. devs., within these.
  double loop_window_min_m = 0.5, loop_window_max_m = 4;
  double loop_window_min_rad = 5 * kRadPerDeg, loop_window_max_rad = 30 * kRadPerDeg;
  double loop_submap_m = 10;     // a candidate's submap: the keyframes within +-this much travel of it
  // ... whose position relative to it the graph knows to this std. dev. (larger axis): a submap is
  // as consistent as the front end's motion across it (0: no limit).
  double loop_submap_sigma_m = 0.2;
  double loop_max_range_m = 20;  // scan points farther than this are left out of loop matching
  int loop_candidates = 2;       // at most this many searches per keyframe (distinct places, nearest first)
  CorrelativeSearchOptions loop_search;
  double loop_scan_cell_m = 0.1;  // the keyframe's points for the search: one per cell of this size
  // What is matched against a candidate's submap: the new keyframe's scan and those of the
  // keyframes within this much travel behind it, placed by the graph (a laser seeing 180 degrees
  // then also sees behind: a place driven through the other way overlaps); 0: its scan alone.
  double loop_query_m = 0;
  // Keyframes taken while turning faster than this (the front end's turn since the scan before,
  // over the time between them) neither start nor end a closure: their scans are skewed and their
  // time matters most [rad/s; 0: no limit; untimed updates count as not turning].
  double loop_max_turn_rate_rad_s = 0;
  // Acceptance: score (mean likelihood of the keyframe's points on the submap, 0-1) and ICP fit
  // (fraction within match_distance_m / 2) at least these; the best distinct other pose's score
  // at most loop_max_ambiguity of the best; the squared Mahalanobis distance of the closure from
  // the graph's relative pose (covariances of both) at most loop_gate_mahalanobis2.
  double loop_min_score = 0.3;
  double loop_min_fit = 0.3;
  double loop_max_ambiguity = 0.9;
  double loop_gate_mahalanobis2 = 16.27;
  // Alone, a closure joins only where the graph's relative position std. dev. is at most this
  // otherwise it waits (at most loop_pending_keyframes keyframes) for a second one from another
  // keyframe that agrees with it (the cycle of both closures and the graph within the gate).
  double loop_confident_sigma_m = 0.3;
  int loop_pending_keyframes = 10;
  // ... and only when it scores at least this (a weaker one, between loop_min_score and this, waits
  // for a second agreeing one wherever it is).
  double loop_alone_min_score = 0.5;
  // The closure's covariance: ICP's, plus these (the submap's own error; std. devs.).
  double loop_sigma_xy_m = 0.05;
  double loop_sigma_theta_rad = 1 * kRadPerDeg;
  // The optimizer (PoseGraph::Optimize): iterations, the chi2 beyond which a closure is switched off.
  int optimizer_iterations = 20;
  double closure_chi2_max = 16.27;
  // When to optimize: after a keyframe whose closures differ from the graph's relative pose by at
  // least optimize_min_m or optimize_min_rad, or once optimize_every closures joined since the last
  // optimization (closures that agree with the graph change it little; each optimization costs the
  // whole graph, the front end's map and the submaps near the change).
  double optimize_min_m = 0.05;
  double optimize_min_rad = 0.5 * kRadPerDeg;
  int optimize_every = 20;
  // The loop search and optimization on a worker thread, their result applied loop_async_scans
  // scans after the job started (see above); false: inside BackEnd, applied at once.
  bool loop_async = false;
  int loop_async_scans = 10;
  void Validate() const;  // throws std::invalid_argument
};

// What became of a loop-closure candidate.
enum class LoopOutcome {
  kAccepted,     // joined the graph
  kPending,      // consistent but alone where the graph is unsure: waiting for a second
  kLowScore,     // no pose in the window scored loop_min_score, or ICP failed or fit too little
  kAmbiguous,    // a distinct other pose scored nearly as well
  kGated,        // inconsistent with the graph
  kExpired,      // pending, no second closure agreed in time
  kSwitchedOff,  // joined, then switched off by the optimizer (chi2 beyond closure_chi2_max)
};
const char* LoopOutcomeName(LoopOutcome o);

struct LoopClosure {
  int from_keyframe = 0, to_keyframe = 0;  // the old keyframe (submap centre) and the new one
  int64_t from_scan = 0, to_scan = 0;      // their scans (1 = the first scan the SLAM got)
  Pose2 predicted;                         // the graph's pose of `to` in `from`'s frame before
  Pose2 relative;                          // the match's
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // the match's, in from's axes
  double score = 0, fit = 0, ambiguity = 0, mahalanobis2 = 0;
  double graph_sigma_m = 0;                // the graph's relative position std. dev. (larger axis)
  LoopOutcome outcome = LoopOutcome::kLowScore;
  int edge = -1;                           // its edge in the graph, once it joined
};

struct GraphSlamUpdate {
  LaserSlamUpdate front_end;
  bool keyframe = false;           // this scan made a keyframe
  bool reused_keyframe = false;    // a keyframe was due, an existing one near the scan taken instead (keyframe_reuse_m)
  int anchor_keyframe = -1;        // the keyframe the scan's pose is kept relative to (-1: none yet)
  Pose2 anchor_relative;           // the scan's pose in the anchor keyframe's frame
  int loop_candidates = 0;         // searches this scan
  int loop_accepted = 0, loop_rejected = 0;  // closures that joined (or were rejected, expired, switched off) this scan
  bool corrected = false;          // the graph was optimized this scan
  double correction_m = 0;         // how far the live pose moved with it [m]
  double correction_rad = 0;       // ... and turned [rad]
  int optimizer_iterations = 0;
};

class GraphSlam {
 public:
  GraphSlam(const LaserSlamOptions& front_end, const GraphSlamOptions& options, const Pose2& start = {});
  ~GraphSlam();  // waits for the worker's job, if one runs
  GraphSlam(const GraphSlam&) = delete;
  GraphSlam& operator=(const GraphSlam&) = delete;

  // As LaserSlam's.
  void Predict(const Pose2& odometry_delta) { front_.Predict(odometry_delta); }
  void Predict(const Pose2& odometry_delta, int64_t end_utime) { front_.Predict(odometry_delta, end_utime); }
  GraphSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime);
  GraphSlamUpdate Update(const std::vector<Eigen::Vector2d>& points_robot);
  // Update in two steps, for timing them apart: the front end and the keyframe decision, then the
  // back end (graph, loop search, optimization); BackEnd must follow each FrontEnd.
  GraphSlamUpdate FrontEnd(const std::vector<Eigen::Vector2d>& points_robot, int64_t utime);
  GraphSlamUpdate FrontEnd(const std::vector<Eigen::Vector2d>& points_robot);
  void BackEnd(GraphSlamUpdate* u);
  // loop_async: waits for the job that runs, if any, and applies its result now (the end of a log);
  // returns what it changed (loop_*, corrected, correction_*). Without a job: an empty update.
  GraphSlamUpdate Flush();
  bool job_running() const { return job_running_; }

  // The live pose (at the latest odometry) and the last scan's, in the graph's (map) frame, with
  // every correction so far; the front end's covariance.
  Pose2 pose() const { return ToGraph(front_.pose()); }
  Pose2 scan_pose() const { return ToGraph(front_.scan_pose()); }
  const Eigen::Matrix3d& covariance() const { return front_.covariance(); }
  const LaserSlam& front_end() const { return front_; }
  const PoseGraph& graph() const { return graph_; }
  int keyframes() const { return graph_.nodes(); }
  // The keyframe pose() and scan_pose() are kept relative to (-1: none yet, the start's frame).
  int anchor_keyframe() const { return last_keyframe_; }
  int64_t keyframe_reuses() const { return keyframe_reuses_; }  // keyframes due but reused (keyframe_reuse_m)
  int64_t keyframe_scan(int keyframe) const { return keyframes_.at(static_cast<size_t>(keyframe))->scan; }
  // The map from the optimized keyframes: their points, one per cell of cell_m.
  std::vector<Eigen::Vector2d> MapPoints(double cell_m) const;
  // The same, one per cell of the front end's map_resolution_m, kept up to date as keyframes join
  // (rebuilt after each optimization): what laser-slam publishes as its map.
  const std::vector<Eigen::Vector2d>& Map() const;
  // A scan's pose in the optimized graph (its anchor keyframe's pose composed with its relative pose).
  Pose2 OptimizedPose(int anchor_keyframe, const Pose2& anchor_relative) const;
  // Every loop-closure candidate searched, in order (outcomes updated as pending ones resolve).
  // (With loop_async: as of the last job applied.)
  const std::vector<LoopClosure>& closures() const { return shown_.closures; }
  int64_t loop_candidates() const { return static_cast<int64_t>(shown_.closures.size()); }
  int64_t loop_accepted() const { return shown_.loop_accepted; }  // joined and still enabled
  int64_t loop_rejected() const { return shown_.loop_rejected; }  // rejected, expired or switched off
  int64_t corrections() const { return corrections_; }
  double last_correction_m() const { return last_correction_m_; }
  double last_correction_rad() const { return last_correction_rad_; }
  int64_t optimizations() const { return shown_.optimizations; }
  int64_t scans() const { return front_.scans(); }

 private:
  struct Keyframe {
    int64_t scan = 0;
    double travel_m = 0;                              // front end's travel from the start to it
    std::vector<Eigen::Vector2d> points, normals;     // robot frame
    std::vector<Eigen::Vector2d> search_points;       // decimated, within loop_max_range_m
    double turn_rate_rad_s = 0;                       // the front end's turn rate into it
  };
  // The points of a new keyframe (and those behind it, loop_query_m) matched against the submaps.
  struct Query {
    std::vector<Eigen::Vector2d> search;              // for the correlative search (loop_scan_cell_m)
    std::vector<Eigen::Vector2d> points, normals;     // for ICP (the map's resolution)
  };
  using Keyframes = std::vector<std::shared_ptr<const Keyframe>>;
  // A job of the back end: the loop search of the keyframes in `todo` (and the optimizations they
  // call for) on a copy of the graph; its outcome for the update that applies it.
  struct Job {
    PoseGraph graph;
    Keyframes keyframes;
    std::vector<int> todo;
    int nodes_at_start = 0, edges_at_start = 0;
    int loop_candidates = 0, loop_accepted = 0, loop_rejected = 0, optimizer_iterations = 0;
    bool optimized = false;
    bool closures_changed = false;
    // After an optimization: the front end's map of the keyframes the job knew at their optimized
    // poses (built on the worker; the scan thread adds the keyframes that joined since, if it takes it).
    std::optional<PointGridMap> front_map;
    std::exception_ptr error;
  };
  void StartJob();
  void RunJob();              // the worker's part: touches job_ and the loop state only
  void ApplyJob(GraphSlamUpdate* u);
  Query MakeQuery(int keyframe) const;
  MatcherOptions LoopIcpOptions() const;
  struct Submap {
    std::unique_ptr<LikelihoodPyramid> pyramid;
    std::unique_ptr<PointGridMap> map;  // for ICP
    int64_t version = -1;
    std::vector<std::pair<int, Pose2>> members;  // its keyframes and their poses relative to the centre, when built
  };
  // A pose in the front end's frame in the graph's (the last keyframe's correction applied).
  Pose2 ToGraph(const Pose2& front_pose) const {
    return last_keyframe_ < 0 ? front_pose : graph_.pose(last_keyframe_).Compose(last_keyframe_front_.Between(front_pose));
  }
  GraphSlamUpdate AfterFrontEnd(const LaserSlamUpdate& front_update, const std::vector<Eigen::Vector2d>& points_robot);
  void AddKeyframe(const std::vector<Eigen::Vector2d>& points, GraphSlamUpdate* u);
  void SearchLoops(int keyframe);
  LoopClosure MatchCandidate(int old_keyframe, int keyframe, const Query& query,
                             const std::vector<Eigen::Matrix3d>& from_new);
  const Submap& SubmapAt(int keyframe);
  bool PairConsistent(const LoopClosure& a, const LoopClosure& b) const;
  // The front end moved into the graph's frame, its map rebuilt from the optimized keyframes (or
  // `prebuilt`, the map of keyframes 0 .. prebuilt_nodes - 1, with the others added).
  void RebuildFrontEndMap(std::optional<PointGridMap> prebuilt = std::nullopt, int prebuilt_nodes = 0);
  // Adds the points of keyframes last, last - 1, ..., first (at g's poses; those with travel_m of at
  // least min_travel_m) to the map, as LaserSlam::ResetMap adds them.
  void AddKeyframesToMap(const PoseGraph& g, const Keyframes& ks, int first, int last, double min_travel_m,
                         PointGridMap* map) const;
  void Optimize();

  LaserSlamOptions front_options_;
  GraphSlamOptions options_;
  LaserSlam front_;
  PoseGraph graph_;
  Keyframes keyframes_;
  int last_keyframe_ = -1;
  Pose2 last_keyframe_front_;  // the last keyframe's pose in the front end's frame
  Pose2 start_;
  double travel_m_ = 0;          // front end's travel so far
  // The front end's pose covariance after the last scan, and its uncertainty relative to the last
  // keyframe (the next edge's covariance, map frame's axes).
  Eigen::Matrix3d last_posterior_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d relative_covariance_ = Eigen::Matrix3d::Zero();
  Pose2 last_scan_front_;
  bool have_scan_ = false;
  std::optional<int64_t> last_scan_utime_;
  double turn_rate_rad_s_ = 0;   // the front end's turn rate into the last scan
  double map_built_travel_m_ = 0;  // travel when the front end's map was last rebuilt (local_map_m)
  // The loop state: the job's own while it runs (the scan thread reads none of it then).
  Job job_;
  std::vector<LoopClosure> closures_;
  std::deque<int> pending_;      // indices in closures_ of pending closures
  std::map<int, Submap> submaps_;
  int64_t loop_version_ = 0;     // bumped by each optimization of a job (submaps are rebuilt after)
  int unoptimized_closures_ = 0; // closures joined since the last optimization
  bool optimize_due_ = false;    // ... one of them moves the graph (optimize_min_*)
  void NoteClosure(const LoopClosure& c);
  int64_t loop_accepted_ = 0, loop_rejected_ = 0, optimizations_ = 0;
  // The scan thread's: what the getters show (copied from the loop state when a job is applied).
  struct Shown {
    std::vector<LoopClosure> closures;
    int64_t loop_accepted = 0, loop_rejected = 0, optimizations = 0;
  } shown_;
  std::vector<int> todo_;        // keyframes not yet searched (joined while a job ran)
  bool job_running_ = false;     // started, not yet applied
  int job_scans_ = 0;            // scans since it started
  std::thread worker_;
  int64_t graph_version_ = 0;    // the live graph's: bumped when a job's optimization is applied
  int64_t corrections_ = 0;
  int64_t keyframe_reuses_ = 0;
  // The existing keyframe (not the last) nearest to `pose` (graph frame) within keyframe_reuse_*, or -1.
  int ReusableKeyframe(const Pose2& pose) const;
  double last_correction_m_ = 0, last_correction_rad_ = 0;
  bool pending_front_ = false;   // FrontEnd ran, BackEnd not yet
  // Map()'s cache: its points, their cells, the keyframes in it and the graph version it is of.
  mutable std::vector<Eigen::Vector2d> map_points_;
  mutable std::unordered_set<uint64_t> map_cells_;
  mutable int map_keyframes_ = 0;
  mutable int64_t map_version_ = -1;
  std::vector<Eigen::Vector2d> pending_points_;
};

}  // namespace snapnav::nav
