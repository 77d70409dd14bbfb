#pragma once
// Route following (thesis 5.1.2-5.1.3): the robot follows a route of waypoints. Place cells give
// position fixes (the memory's snapshot nearest to the current view); between fixes the pose
// is carried by odometry; the last metres to a waypoint can be driven by snapshot homing towards
// the waypoint's own snapshot.
//
//   ThesisRoute     the routes of thesis figure 5.5, scaled to a square area.
//   PoseTracker     odometry predicts (x, y, theta) with a growing covariance; a place-cell fix
//                   (pose and covariance) corrects it by a Kalman update behind a Mahalanobis
//                   gate. Fixes may be late: they are carried forward by the odometry since.
//   RouteFollower   turns towards the next waypoint, then drives (proportional heading control,
//                   speed limits); within homing_radius_m it steers by the homing direction
//                   when one is given; counts waypoints and laps.
//
// Streaming APIs: time (utime, microseconds) is a parameter, nothing here reads a clock.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// ------------------------------------------------------------------------------------- routes
// The navigation routes of thesis figure 5.5 in its 0..100 units (100 units = 3.5 m there),
// scaled to a square: unit point (u, v) -> origin + (u, v) * size_m / 100.
//   which = 1 (left):  (100,0) (54,81) (0,0) (0,100) (100,100) (100,0)
//   which = 2 (right): (100,0) (54,81) (100,0) (0,0) (0,100) (100,0)
// Both end where they start. Throws std::invalid_argument for another `which`, a non-positive
// or non-finite size, or a non-finite origin.
std::vector<Eigen::Vector2d> ThesisRoute(int which, const Eigen::Vector2d& origin, double size_m);
// "thesis1" / "thesis2" -> 1 / 2; nullopt otherwise.
std::optional<int> ParseThesisRoute(const std::string& name);

// ------------------------------------------------------------------------------- pose tracker
struct PoseTrackerOptions {
  DeadReckoningOptions odometry;           // motion noise of the prediction
  double initial_position_sigma_m = 0.05;  // Initialize() without a covariance
  double initial_heading_sigma_rad = 0.05;
  // Mahalanobis distance^2 of a fix's innovation above which it is rejected, for the degrees of
  // freedom used (3 with the heading, 2 without: 11.34 and 9.21 are the 99 % points); <= 0: no gate.
  double gate_chi2 = 11.34;
  // After this many consecutive rejected fixes the next fix re-initialises the tracker (the
  // estimate has drifted off and the fixes agree elsewhere); 0: never.
  int reset_after_rejections = 6;
  bool use_fix_heading = true;              // false: only the fix's position is used
  double min_fix_position_sigma_m = 0.02;   // floor of a fix's position std. dev. [m]
  double min_fix_heading_sigma_rad = 0.02;  // floor of a fix's heading std. dev. [rad]
  // Late fixes are carried forward by the odometry since their time; one older than this
  // (relative to the last odometry) is rejected as stale [s].
  double max_fix_age_s = 2.0;
  void Validate() const;  // throws std::invalid_argument naming the bad option
};

enum class FixOutcome {
  kInitialized,    // the first fix started the tracker
  kAccepted,       // passed the gate, estimate updated
  kReset,          // re-initialised after reset_after_rejections rejections
  kRejectedGate,   // innovation beyond the gate
  kRejectedStale,  // older than max_fix_age_s
};
const char* FixOutcomeName(FixOutcome outcome);  // "initialized", "accepted", "reset", "gate", "stale"

class PoseTracker {
 public:
  explicit PoseTracker(const PoseTrackerOptions& options = {});

  // Starts (or restarts) at `pose` with the initial covariance of the options or the given one.
  // Throws std::invalid_argument on a non-finite pose or covariance.
  void Initialize(int64_t utime, const Pose2& pose);
  void Initialize(int64_t utime, const Pose2& pose, const Eigen::Matrix3d& covariance);
  bool initialized() const { return initialized_; }

  // One odometry increment (robot frame of the previous reading) at utime. Before the tracker is
  // initialised only the time is kept. Throws std::invalid_argument on a non-finite increment or
  // a utime before the previous one (nothing changes).
  void AddOdometry(int64_t utime, const Pose2& delta);

  // A place-cell fix: the pose at utime and its covariance (only its (x, y) block is used when
  // use_fix_heading is false). Uninitialised: the fix initialises the tracker. Throws
  // std::invalid_argument on a non-finite pose or covariance or a negative variance.
  FixOutcome AddFix(int64_t utime, const Pose2& pose, const Eigen::Matrix3d& covariance);

  const Pose2& pose() const { return pose_; }
  const Eigen::Matrix3d& covariance() const { return covariance_; }
  // sqrt of the larger eigenvalue of the position covariance [m].
  double position_sigma_m() const;
  int64_t utime() const { return utime_; }                         // time of the latest odometry or fix
  double last_mahalanobis2() const { return last_mahalanobis2_; }  // of the latest fix
  int64_t fixes_accepted() const { return accepted_; }             // initialisations and resets included
  int64_t fixes_rejected() const { return rejected_; }             // gate and stale
  int64_t resets() const { return resets_; }
  int consecutive_rejections() const { return consecutive_rejections_; }
  const PoseTrackerOptions& options() const { return options_; }

 private:
  PoseTrackerOptions options_;
  bool initialized_ = false;
  Pose2 pose_;
  Eigen::Matrix3d covariance_ = Eigen::Matrix3d::Zero();
  int64_t utime_ = 0;
  bool have_time_ = false;
  std::deque<std::pair<int64_t, Pose2>> history_;  // odometry increments of the last max_fix_age_s
  double last_mahalanobis2_ = 0;
  int64_t accepted_ = 0, rejected_ = 0, resets_ = 0;
  int consecutive_rejections_ = 0;
};

// ------------------------------------------------------------------------------ route follower
struct Route {
  std::string name;
  std::vector<Eigen::Vector2d> waypoints;  // map frame [m]
  bool loop = false;                       // start again after the last waypoint
  int laps = 0;                            // with loop: finish after this many laps; 0: no limit
  double tolerance_m = 0.1;                // a waypoint is reached within this distance [m]
  // A closed route (last waypoint == first) starts its next lap at waypoint 1.
  bool closed() const;
  void Validate() const;  // throws std::invalid_argument: no waypoints, non-finite, tolerance <= 0, laps < 0
};

enum class FollowState { kIdle, kTurning, kDriving, kHoming, kFinished };
const char* FollowStateName(FollowState state);  // "idle", "turning", "driving", "homing", "finished"

// What decides that a waypoint is reached.
enum class ArrivalRule {
  kEstimate,  // the tracked position is within the route's tolerance
  kHoming,    // the homing says "arrived" (a fresh homing input); without one, the estimate
  kEither,    // whichever comes first
};
std::optional<ArrivalRule> ParseArrivalRule(const std::string& name);
const char* ArrivalRuleName(ArrivalRule rule);  // "estimate", "homing", "either"

struct FollowerOptions {
  double max_linear_mps = 0.2;
  double min_linear_mps = 0.03;  // slowest driving speed near a waypoint [m/s]
  double max_angular_radps = 1.0;
  double heading_gain_per_s = 2.0;  // angular = gain x heading error [1/s]
  double turn_in_place_rad = 0.5;   // heading error above this: stop and turn (the thesis: turn, then drive)
  double align_rad = 0.1;           // turning on the spot ends below this heading error
  double slow_down_m = 0.3;         // the speed falls linearly to min_linear_mps within this distance
  // Final approach: within this estimated distance of the waypoint the robot steers by the homing
  // direction (towards the waypoint's snapshot) while one is fresh; 0: never.
  double homing_radius_m = 0.3;
  double homing_speed_mps = 0.08;
  double homing_max_age_s = 0.5;  // a homing input older than this is not used [s]
  // A homing direction further than this from the direction to the waypoint by the tracked pose
  // is not used (a mismatched snapshot must not send the robot away); pi: no check.
  double homing_max_deviation_rad = 0.8;
  ArrivalRule arrival = ArrivalRule::kEstimate;
  // Within homing_radius_m for this long without arriving: the waypoint counts as reached
  // (ArrivalReason::kTimeout) so a wandering approach cannot stall the route; 0: no limit [s].
  double approach_timeout_s = 20;
  void Validate() const;  // throws std::invalid_argument naming the bad option
};

// A homing result towards the current waypoint's snapshot.
struct HomingInput {
  int64_t utime = 0;
  double direction_rad = 0;  // direction to move in, robot frame, counter-clockwise [rad]
  bool arrived = false;      // the homing measure says the robot is at the snapshot's place
};

struct DriveCommand {
  double linear_mps = 0;
  double angular_radps = 0;
};

enum class ArrivalReason { kNone, kEstimate, kHoming, kTimeout };
const char* ArrivalReasonName(ArrivalReason reason);  // "none", "estimate", "homing", "timeout"

struct FollowStep {
  DriveCommand command;
  FollowState state = FollowState::kIdle;
  int waypoint = -1;                             // the waypoint being approached after this step (-1: none)
  double distance_m = 0;                         // estimated distance to it [m]
  double heading_error_rad = 0;                  // direction to steer relative to the heading [rad]
  bool homing_used = false;                      // the command follows the homing direction
  bool homing_refused = false;                   // a fresh homing direction deviated too far from the estimate's
  ArrivalReason arrival = ArrivalReason::kNone;  // a waypoint was reached in this step
  int arrived_waypoint = -1;                     // ... this one
  bool lap_completed = false;                    // ... and it ended a lap
};

class RouteFollower {
 public:
  explicit RouteFollower(const FollowerOptions& options = {});

  // Follows `route` from waypoint `first` (e.g. 1 when the robot starts at waypoint 0). Resets
  // laps and state. Throws std::invalid_argument on an invalid route or first.
  void SetRoute(const Route& route, int first = 0);
  bool has_route() const { return !route_.waypoints.empty(); }

  // The latest homing towards the current waypoint's snapshot; forgotten when the waypoint
  // changes. Non-finite directions throw std::invalid_argument.
  void SetHoming(const HomingInput& homing);

  // One control step at utime from the tracked pose.
  FollowStep Update(int64_t utime, const Pose2& pose);

  const Route& route() const { return route_; }
  int waypoint() const { return waypoint_; }
  int laps() const { return laps_; }
  int arrivals() const { return arrivals_; }
  FollowState state() const { return state_; }
  const FollowerOptions& options() const { return options_; }

 private:
  void Advance(FollowStep* step);
  bool HomingFresh(int64_t utime) const;

  FollowerOptions options_;
  Route route_;
  int waypoint_ = -1;
  int laps_ = 0;
  int arrivals_ = 0;
  FollowState state_ = FollowState::kIdle;
  std::optional<HomingInput> homing_;
  std::optional<int64_t> approach_since_;  // first step within homing_radius_m of the waypoint
  std::optional<int64_t> waypoint_since_;  // when the current waypoint was taken on
};

}  // namespace snapnav::nav
