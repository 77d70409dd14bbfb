// Route following (libnav): the thesis routes, the pose tracker (odometry prediction, place-cell
// fixes, the gate) and the route follower (turn then drive, waypoints, laps, the final approach
// by homing).
#include "snapnav/nav/places/navigator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace snapnav::nav {
namespace {

constexpr int64_t kSecond = 1000000;

// ------------------------------------------------------------------------------------- routes
TEST(ThesisRoute, ScalesTheFigureUnitsToTheSquare) {
  const Eigen::Vector2d origin(2.3, 1.8);
  const auto left = ThesisRoute(1, origin, 2.4);
  ASSERT_EQ(left.size(), 6u);
  const double expect_left[][2] = {{100, 0}, {54, 81}, {0, 0}, {0, 100}, {100, 100}, {100, 0}};
  for (size_t i = 0; i < left.size(); ++i) {
    EXPECT_NEAR(left[i].x(), 2.3 + expect_left[i][0] * 0.024, 1e-12) << i;
    EXPECT_NEAR(left[i].y(), 1.8 + expect_left[i][1] * 0.024, 1e-12) << i;
  }
  EXPECT_NEAR(left[1].x(), 3.596, 1e-12);
  EXPECT_NEAR(left[1].y(), 3.744, 1e-12);
  const auto right = ThesisRoute(2, Eigen::Vector2d::Zero(), 3.5);  // the thesis' own 3.5 m
  ASSERT_EQ(right.size(), 6u);
  EXPECT_NEAR(right[1].x(), 1.89, 1e-12);
  EXPECT_NEAR(right[1].y(), 2.835, 1e-12);
  EXPECT_EQ(right[2], right[0]);  // back to the start, then around the square
  EXPECT_NEAR(right[4].x(), 0.0, 1e-12);
  EXPECT_NEAR(right[4].y(), 3.5, 1e-12);
  // Both routes end where they start.
  EXPECT_EQ(left.front(), left.back());
  EXPECT_EQ(right.front(), right.back());
}

TEST(ThesisRoute, RejectsUnknownRoutesAndSizes) {
  EXPECT_THROW(ThesisRoute(0, Eigen::Vector2d::Zero(), 1), std::invalid_argument);
  EXPECT_THROW(ThesisRoute(3, Eigen::Vector2d::Zero(), 1), std::invalid_argument);
  EXPECT_THROW(ThesisRoute(1, Eigen::Vector2d::Zero(), 0), std::invalid_argument);
  EXPECT_THROW(ThesisRoute(1, Eigen::Vector2d(NAN, 0), 1), std::invalid_argument);
  EXPECT_EQ(ParseThesisRoute("thesis1"), 1);
  EXPECT_EQ(ParseThesisRoute("thesis2"), 2);
  EXPECT_FALSE(ParseThesisRoute("thesis3"));
}

// ------------------------------------------------------------------------------- pose tracker
PoseTrackerOptions NoNoise() {
  PoseTrackerOptions o;
  o.odometry.translation_noise_m_per_m = 0;
  o.odometry.rotation_noise_rad_per_rad = 0;
  o.odometry.rotation_noise_rad_per_m = 0;
  return o;
}

TEST(PoseTracker, PredictionCarriesHeadingUncertaintyIntoTheLateralPosition) {
  PoseTracker t(NoNoise());
  t.Initialize(0, {0, 0, 0}, Eigen::Vector3d(0, 0, 0.01).asDiagonal());
  t.AddOdometry(kSecond, {1, 0, 0});
  EXPECT_NEAR(t.pose().x_m, 1, 1e-12);
  EXPECT_NEAR(t.pose().y_m, 0, 1e-12);
  // J = [1 0 0; 0 1 1; 0 0 1]: a heading variance of 0.01 rad^2 becomes 0.01 m^2 sideways after 1 m.
  const Eigen::Matrix3d& p = t.covariance();
  EXPECT_NEAR(p(0, 0), 0, 1e-12);
  EXPECT_NEAR(p(1, 1), 0.01, 1e-12);
  EXPECT_NEAR(p(1, 2), 0.01, 1e-12);
  EXPECT_NEAR(p(2, 2), 0.01, 1e-12);
  EXPECT_EQ(t.utime(), kSecond);
}

TEST(PoseTracker, CovarianceGrowsWithTheDistanceDriven) {
  PoseTracker t;  // default noise: 5 cm per metre
  t.Initialize(0, {0, 0, 0}, Eigen::Matrix3d::Zero());
  double previous = 0;
  for (int i = 1; i <= 10; ++i) {
    t.AddOdometry(i * kSecond / 10, {0.1, 0, 0});
    EXPECT_GT(t.position_sigma_m(), previous);
    previous = t.position_sigma_m();
  }
  EXPECT_NEAR(t.pose().x_m, 1.0, 1e-12);
  EXPECT_NEAR(t.covariance()(0, 0), 10 * 0.005 * 0.005, 1e-12);  // 10 steps of 0.05 x 0.1 m
}

TEST(PoseTracker, FixUpdatesLikeTheHandComputedKalmanGain) {
  PoseTrackerOptions o = NoNoise();
  PoseTracker t(o);
  t.Initialize(0, {1, 2, 0}, Eigen::Vector3d(0.04, 0.04, 0.01).asDiagonal());
  // Equal prior and fix covariances: K = I / 2, the estimate moves half way, the covariance halves.
  const auto outcome = t.AddFix(0, {1.3, 2.0, 0.1}, Eigen::Vector3d(0.04, 0.04, 0.01).asDiagonal());
  EXPECT_EQ(outcome, FixOutcome::kAccepted);
  EXPECT_NEAR(t.pose().x_m, 1.15, 1e-12);
  EXPECT_NEAR(t.pose().y_m, 2.0, 1e-12);
  EXPECT_NEAR(t.pose().theta_rad, 0.05, 1e-12);
  EXPECT_NEAR(t.covariance()(0, 0), 0.02, 1e-12);
  EXPECT_NEAR(t.covariance()(1, 1), 0.02, 1e-12);
  EXPECT_NEAR(t.covariance()(2, 2), 0.005, 1e-12);
  EXPECT_NEAR(t.covariance()(0, 1), 0, 1e-12);
  // d^2 = 0.3^2 / 0.08 + 0.1^2 / 0.02
  EXPECT_NEAR(t.last_mahalanobis2(), 1.125 + 0.5, 1e-12);
  EXPECT_EQ(t.fixes_accepted(), 1);
  EXPECT_EQ(t.fixes_rejected(), 0);
}

TEST(PoseTracker, HeadingInnovationIsWrapped) {
  PoseTracker t(NoNoise());
  t.Initialize(0, {0, 0, M_PI - 0.05}, Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal());
  ASSERT_EQ(t.AddFix(0, {0, 0, -M_PI + 0.05}, Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal()), FixOutcome::kAccepted);
  // Half way across the +-pi seam, not through 0.
  EXPECT_NEAR(std::abs(t.pose().theta_rad), M_PI, 1e-9);
}

TEST(PoseTracker, PositionOnlyFixesLeaveTheHeadingAlone) {
  PoseTrackerOptions o = NoNoise();
  o.use_fix_heading = false;
  PoseTracker t(o);
  t.Initialize(0, {0, 0, 0.3}, Eigen::Vector3d(0.04, 0.04, 0.01).asDiagonal());
  ASSERT_EQ(t.AddFix(0, {0.2, 0, -1.0}, Eigen::Vector3d(0.04, 0.04, 0.0001).asDiagonal()), FixOutcome::kAccepted);
  EXPECT_NEAR(t.pose().x_m, 0.1, 1e-12);
  EXPECT_NEAR(t.pose().theta_rad, 0.3, 1e-12);  // uncorrelated: the heading does not move
}

TEST(PoseTracker, OutlierIsGatedAndConsecutiveRejectionsReset) {
  PoseTrackerOptions o = NoNoise();
  o.reset_after_rejections = 3;
  PoseTracker t(o);
  const Eigen::Matrix3d r = Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal();
  t.Initialize(0, {1, 1, 0}, r);
  // A wrong cell 3 m away: d^2 = 9 / 0.02 * 2 >> 11.34.
  EXPECT_EQ(t.AddFix(0, {4, 1, 0}, r), FixOutcome::kRejectedGate);
  EXPECT_NEAR(t.pose().x_m, 1, 1e-12);
  EXPECT_GT(t.last_mahalanobis2(), 100);
  EXPECT_EQ(t.fixes_rejected(), 1);
  // A good fix in between clears the streak.
  EXPECT_EQ(t.AddFix(0, {1.05, 1, 0}, r), FixOutcome::kAccepted);
  EXPECT_EQ(t.consecutive_rejections(), 0);
  // The estimate is wrong (kidnapped): the fixes keep disagreeing; after 3 rejections the next resets.
  for (int i = 0; i < 3; ++i) EXPECT_EQ(t.AddFix(0, {4, 4, 1}, r), FixOutcome::kRejectedGate);
  EXPECT_EQ(t.AddFix(0, {4, 4, 1}, r), FixOutcome::kReset);
  EXPECT_NEAR(t.pose().x_m, 4, 1e-12);
  EXPECT_NEAR(t.pose().y_m, 4, 1e-12);
  EXPECT_EQ(t.resets(), 1);
  EXPECT_EQ(t.fixes_rejected(), 4);
  EXPECT_EQ(t.fixes_accepted(), 2);
}

TEST(PoseTracker, LateFixIsCarriedForwardByTheOdometrySince) {
  PoseTrackerOptions o = NoNoise();
  PoseTracker t(o);
  t.Initialize(0, {0, 0, 0}, Eigen::Vector3d(100, 100, 0.0001).asDiagonal());
  t.AddOdometry(kSecond / 10, {0.1, 0, 0});
  t.AddOdometry(2 * kSecond / 10, {0.1, 0, 0});
  // A fix of the pose at 0.1 s: (0.1, 0.05); the robot has moved 0.1 m forward since.
  ASSERT_EQ(t.AddFix(kSecond / 10, {0.1, 0.05, 0}, Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal()),
            FixOutcome::kAccepted);
  EXPECT_NEAR(t.pose().x_m, 0.2, 1e-3);
  EXPECT_NEAR(t.pose().y_m, 0.05, 1e-3);
  // Older than max_fix_age_s: stale.
  t.AddOdometry(5 * kSecond, {0, 0, 0});
  EXPECT_EQ(t.AddFix(kSecond, {9, 9, 0}, Eigen::Matrix3d::Identity()), FixOutcome::kRejectedStale);
  EXPECT_EQ(t.fixes_rejected(), 1);
}

TEST(PoseTracker, FirstFixInitialisesAndBadInputThrows) {
  PoseTracker t;
  EXPECT_FALSE(t.initialized());
  t.AddOdometry(kSecond, {0.5, 0, 0});  // before any fix: only time
  EXPECT_EQ(t.AddFix(kSecond, {2, 3, 0.5}, Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal()), FixOutcome::kInitialized);
  EXPECT_TRUE(t.initialized());
  EXPECT_NEAR(t.pose().x_m, 2, 1e-12);
  EXPECT_THROW(t.AddOdometry(2 * kSecond, {NAN, 0, 0}), std::invalid_argument);
  EXPECT_THROW(t.AddOdometry(0, {0, 0, 0}), std::invalid_argument);  // back in time
  EXPECT_THROW(t.AddFix(2 * kSecond, {0, 0, 0}, -Eigen::Matrix3d::Identity()), std::invalid_argument);
  EXPECT_THROW(t.AddFix(2 * kSecond, {0, INFINITY, 0}, Eigen::Matrix3d::Identity()), std::invalid_argument);
  PoseTrackerOptions bad;
  bad.min_fix_position_sigma_m = 0;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
  EXPECT_THROW(PoseTracker{bad}, std::invalid_argument);
}

// ------------------------------------------------------------------------------ route follower
Route Square(bool loop, int laps) {
  Route r;
  r.name = "square";
  r.waypoints = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
  r.loop = loop;
  r.laps = laps;
  r.tolerance_m = 0.05;
  return r;
}

TEST(RouteFollower, TurnsOnTheSpotTowardsTheNextWaypointThenDrives) {
  RouteFollower f;
  Route r;
  r.waypoints = {{0, 1}};
  f.SetRoute(r);
  // Waypoint on the left: turn left, standing.
  FollowStep s = f.Update(0, {0, 0, 0});
  EXPECT_EQ(s.state, FollowState::kTurning);
  EXPECT_EQ(s.command.linear_mps, 0);
  EXPECT_GT(s.command.angular_radps, 0);
  EXPECT_NEAR(s.heading_error_rad, M_PI / 2, 1e-12);
  EXPECT_NEAR(s.distance_m, 1, 1e-12);
  EXPECT_LE(s.command.angular_radps, f.options().max_angular_radps);
  // On the right: turn right.
  s = f.Update(1, {0, 0, M_PI});
  EXPECT_LT(s.command.angular_radps, 0);
  EXPECT_EQ(s.command.linear_mps, 0);
  // Facing it: drive at full speed, no turn.
  s = f.Update(2, {0, 0, M_PI / 2});
  EXPECT_EQ(s.state, FollowState::kDriving);
  EXPECT_NEAR(s.command.linear_mps, f.options().max_linear_mps, 1e-12);
  EXPECT_NEAR(s.command.angular_radps, 0, 1e-12);
  // Slightly off while driving: keep driving, steer proportionally.
  s = f.Update(3, {0, 0, M_PI / 2 - 0.2});
  EXPECT_EQ(s.state, FollowState::kDriving);
  EXPECT_NEAR(s.command.angular_radps, f.options().heading_gain_per_s * 0.2, 1e-9);
  EXPECT_GT(s.command.linear_mps, 0);
  // Slows down near the waypoint.
  s = f.Update(4, {0, 0.8, M_PI / 2});
  EXPECT_LT(s.command.linear_mps, f.options().max_linear_mps);
  EXPECT_GE(s.command.linear_mps, f.options().min_linear_mps);
}

// A perfect unicycle following the follower's commands.
struct Drive {
  Drive(RouteFollower* f, const Pose2& start) : follower(f), pose(start) {}
  RouteFollower* follower;
  Pose2 pose;
  int64_t utime = 0;
  std::vector<int> arrived;
  std::vector<int> laps_at;
  FollowStep Step(double dt_s = 0.05) {
    const FollowStep s = follower->Update(utime, pose);
    if (s.arrival != ArrivalReason::kNone) {
      arrived.push_back(s.arrived_waypoint);
      if (s.lap_completed) laps_at.push_back(static_cast<int>(arrived.size()));
    }
    pose = pose.Compose({s.command.linear_mps * dt_s, 0, s.command.angular_radps * dt_s});
    utime += static_cast<int64_t>(dt_s * 1e6);
    return s;
  }
};

TEST(RouteFollower, AdvancesThroughTheWaypointsAndCountsLaps) {
  RouteFollower f;
  f.SetRoute(Square(true, 2), 1);  // the robot starts on waypoint 0
  Drive d(&f, {0, 0, 0});
  for (int i = 0; i < 20000 && f.state() != FollowState::kFinished; ++i) {
    const FollowStep s = d.Step();
    if (s.arrival != ArrivalReason::kNone) {
      const auto& w = f.route().waypoints[s.arrived_waypoint];
      EXPECT_LT((Eigen::Vector2d(d.pose.x_m, d.pose.y_m) - w).norm(), f.route().tolerance_m);
      EXPECT_EQ(s.arrival, ArrivalReason::kEstimate);
    }
  }
  ASSERT_EQ(f.state(), FollowState::kFinished);
  // A closed route's next lap starts at waypoint 1: 1 2 3 4, 1 2 3 4.
  EXPECT_EQ(d.arrived, (std::vector<int>{1, 2, 3, 4, 1, 2, 3, 4}));
  EXPECT_EQ(d.laps_at, (std::vector<int>{4, 8}));
  EXPECT_EQ(f.laps(), 2);
  EXPECT_EQ(f.arrivals(), 8);
  const FollowStep s = f.Update(d.utime, d.pose);
  EXPECT_EQ(s.state, FollowState::kFinished);
  EXPECT_EQ(s.command.linear_mps, 0);
  EXPECT_EQ(s.command.angular_radps, 0);
}

TEST(RouteFollower, OpenRouteWithoutLoopFinishesAtItsEnd) {
  RouteFollower f;
  Route r;
  r.waypoints = {{1, 0}, {1, 1}};
  r.tolerance_m = 0.05;
  f.SetRoute(r);
  Drive d(&f, {0, 0, 0});
  for (int i = 0; i < 5000 && f.state() != FollowState::kFinished; ++i) d.Step();
  EXPECT_EQ(f.state(), FollowState::kFinished);
  EXPECT_EQ(d.arrived, (std::vector<int>{0, 1}));
  EXPECT_EQ(f.laps(), 1);
}

TEST(RouteFollower, FinalApproachSteersByTheHomingDirection) {
  FollowerOptions o;
  o.homing_radius_m = 0.3;
  o.homing_max_deviation_rad = M_PI;  // any direction is taken
  o.arrival = ArrivalRule::kHoming;
  RouteFollower f(o);
  Route r;
  r.waypoints = {{1, 0}};
  r.tolerance_m = 0.05;
  f.SetRoute(r);
  // Far away: the homing direction is not used.
  f.SetHoming({0, -M_PI / 2, false});
  FollowStep s = f.Update(0, {0, 0, 0});
  EXPECT_FALSE(s.homing_used);
  EXPECT_EQ(s.state, FollowState::kDriving);
  // Within the radius with a fresh homing direction to the right: it turns right, though the
  // estimate has the waypoint straight ahead.
  s = f.Update(kSecond / 10, {0.8, 0, 0});
  EXPECT_TRUE(s.homing_used);
  EXPECT_EQ(s.state, FollowState::kTurning);
  EXPECT_LT(s.command.angular_radps, 0);
  // Homing ahead: drive at the homing speed.
  f.SetHoming({kSecond / 5, 0.0, false});
  s = f.Update(kSecond / 5, {0.8, 0, 0});
  EXPECT_EQ(s.state, FollowState::kHoming);
  EXPECT_NEAR(s.command.linear_mps, o.homing_speed_mps, 1e-12);
  // The estimate is within the tolerance, but the homing says "not yet": no arrival.
  f.SetHoming({kSecond / 2, 0.0, false});
  s = f.Update(kSecond / 2, {0.98, 0, 0});
  EXPECT_EQ(s.arrival, ArrivalReason::kNone);
  // The homing says "arrived".
  f.SetHoming({kSecond, 0.0, true});
  s = f.Update(kSecond, {0.9, 0, 0});
  EXPECT_EQ(s.arrival, ArrivalReason::kHoming);
  EXPECT_EQ(s.state, FollowState::kFinished);
}

TEST(RouteFollower, HomingFarFromTheEstimatesDirectionIsRefused) {
  FollowerOptions o;
  o.homing_max_deviation_rad = 0.8;
  RouteFollower f(o);
  Route r;
  r.waypoints = {{1, 0}};
  f.SetRoute(r);
  // The estimate has the waypoint straight ahead; homing says behind: refused.
  f.SetHoming({0, 3.0, false});
  FollowStep s = f.Update(0, {0.8, 0, 0});
  EXPECT_FALSE(s.homing_used);
  EXPECT_TRUE(s.homing_refused);
  EXPECT_EQ(s.state, FollowState::kDriving);
  EXPECT_NEAR(s.command.angular_radps, 0, 1e-12);
  // 0.3 rad to the left: within the cone, it steers by it.
  f.SetHoming({1, 0.3, false});
  s = f.Update(1, {0.8, 0, 0});
  EXPECT_TRUE(s.homing_used);
  EXPECT_FALSE(s.homing_refused);
  EXPECT_NEAR(s.heading_error_rad, 0.3, 1e-12);
  EXPECT_GT(s.command.angular_radps, 0);
  o.homing_max_deviation_rad = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
}

TEST(RouteFollower, StaleHomingFallsBackToTheEstimate) {
  FollowerOptions o;
  o.arrival = ArrivalRule::kHoming;
  o.homing_max_age_s = 0.5;
  RouteFollower f(o);
  Route r;
  r.waypoints = {{1, 0}, {2, 0}};
  f.SetRoute(r);
  f.SetHoming({0, M_PI / 2, false});
  FollowStep s = f.Update(2 * kSecond, {0.85, 0, 0});  // homing 2 s old
  EXPECT_FALSE(s.homing_used);
  EXPECT_NEAR(s.command.angular_radps, 0, 1e-12);
  s = f.Update(3 * kSecond, {0.95, 0, 0});  // no fresh homing: the estimate decides
  EXPECT_EQ(s.arrival, ArrivalReason::kEstimate);
  EXPECT_EQ(s.waypoint, 1);
  // A homing computed before the waypoint changed belongs to the old one: ignored.
  f.SetHoming({3 * kSecond - 1, M_PI / 2, true});
  s = f.Update(3 * kSecond + 1, {1.85, 0, 0});
  EXPECT_FALSE(s.homing_used);
  EXPECT_EQ(s.arrival, ArrivalReason::kNone);
}

TEST(RouteFollower, ApproachTimeoutKeepsTheRouteGoing) {
  FollowerOptions o;
  o.approach_timeout_s = 5;
  RouteFollower f(o);
  Route r;
  r.waypoints = {{1, 0}, {2, 0}};
  r.tolerance_m = 0.01;
  f.SetRoute(r);
  EXPECT_EQ(f.Update(0, {0.8, 0.1, 0}).arrival, ArrivalReason::kNone);
  EXPECT_EQ(f.Update(4 * kSecond, {0.8, 0.1, 0}).arrival, ArrivalReason::kNone);
  const FollowStep s = f.Update(5 * kSecond, {0.8, 0.1, 0});
  EXPECT_EQ(s.arrival, ArrivalReason::kTimeout);
  EXPECT_EQ(s.arrived_waypoint, 0);
  EXPECT_EQ(f.waypoint(), 1);
}

TEST(RouteFollower, OptionsAndRoutesAreValidated) {
  FollowerOptions o;
  o.turn_in_place_rad = 0.01;  // below align_rad
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = FollowerOptions{};
  o.homing_speed_mps = 1.0;  // above max_linear_mps
  EXPECT_THROW(RouteFollower{o}, std::invalid_argument);
  RouteFollower f;
  EXPECT_THROW(f.SetRoute(Route{}), std::invalid_argument);
  Route r = Square(true, 0);
  EXPECT_THROW(f.SetRoute(r, 5), std::invalid_argument);
  r.tolerance_m = 0;
  EXPECT_THROW(f.SetRoute(r), std::invalid_argument);
  Route single;
  single.waypoints = {{1, 1}};
  single.loop = true;
  EXPECT_THROW(single.Validate(), std::invalid_argument);
  EXPECT_EQ(ParseArrivalRule("either"), ArrivalRule::kEither);
  EXPECT_FALSE(ParseArrivalRule("never"));
  // Without a route: idle, standing still.
  const FollowStep s = f.Update(0, {0, 0, 0});
  EXPECT_EQ(s.state, FollowState::kIdle);
  EXPECT_EQ(s.command.linear_mps, 0);
  EXPECT_EQ(s.waypoint, -1);
}

}  // namespace
}  // namespace snapnav::nav
