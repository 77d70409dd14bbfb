#include <gtest/gtest.h>

#include <cmath>

#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {
namespace {

TEST(Pose2, WrapAngle) {
  EXPECT_NEAR(WrapAngle(3 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(-3 * M_PI / 2), M_PI / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(0.3), 0.3, 1e-12);
}

TEST(Pose2, ComposeInverseBetween) {
  const Pose2 a{1, 2, M_PI / 2};
  const Pose2 d{1, 0, 0};
  const Pose2 b = a.Compose(d);
  EXPECT_NEAR(b.x_m, 1, 1e-12);  // one metre forward when facing +y
  EXPECT_NEAR(b.y_m, 3, 1e-12);
  const Pose2 id = a.Compose(a.Inverse());
  EXPECT_NEAR(id.x_m, 0, 1e-12);
  EXPECT_NEAR(id.y_m, 0, 1e-12);
  EXPECT_NEAR(id.theta_rad, 0, 1e-12);
  const Pose2 back = a.Compose(a.Between(b));
  EXPECT_NEAR(back.x_m, b.x_m, 1e-12);
  EXPECT_NEAR(back.y_m, b.y_m, 1e-12);
  const auto p = a.Transform({1, 0});
  EXPECT_NEAR(p.x(), 1, 1e-12);
  EXPECT_NEAR(p.y(), 3, 1e-12);
}

TEST(DeadReckoning, SquareClosesAndCovarianceGrows) {
  DeadReckoning dr(DeadReckoningOptions{});
  double last_heading_var = 0;
  double first_side_trace = 0;
  for (int side = 0; side < 4; ++side) {
    for (int i = 0; i < 10; ++i) {
      dr.AddOdometry({0.1, 0, 0});
      // Heading uncertainty only grows; position uncertainty may shrink when the robot
      // drives back towards where an earlier heading error was made.
      EXPECT_GT(dr.covariance()(2, 2), last_heading_var);
      last_heading_var = dr.covariance()(2, 2);
    }
    if (side == 0) first_side_trace = dr.covariance().trace();
    dr.AddOdometry({0, 0, M_PI / 2});
  }
  EXPECT_GT(dr.covariance().trace(), first_side_trace);
  EXPECT_NEAR(dr.pose().x_m, 0, 1e-9);
  EXPECT_NEAR(dr.pose().y_m, 0, 1e-9);
  EXPECT_NEAR(dr.distance_m(), 4.0, 1e-9);
}

TEST(DeadReckoning, CovarianceOfAStraightLineMatchesHandComputation) {
  DeadReckoningOptions o;
  o.translation_noise_m_per_m = 0.1;
  o.rotation_noise_rad_per_rad = 0;
  o.rotation_noise_rad_per_m = 0;
  DeadReckoning dr(o);
  dr.AddOdometry({1, 0, 0});
  EXPECT_NEAR(dr.covariance()(0, 0), 0.01, 1e-12);
  EXPECT_NEAR(dr.covariance()(1, 1), 0.01, 1e-12);
  EXPECT_NEAR(dr.covariance()(2, 2), 0, 1e-12);
}

TEST(DeadReckoning, RejectsNonFiniteIncrementAndBadOptions) {
  DeadReckoning dr(DeadReckoningOptions{});
  EXPECT_THROW(dr.AddOdometry({NAN, 0, 0}), std::invalid_argument);
  EXPECT_EQ(dr.pose().x_m, 0);
  DeadReckoningOptions bad;
  bad.translation_noise_m_per_m = -1;
  EXPECT_THROW(DeadReckoning{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::nav

#include "snapnav/nav/trajectory.hpp"

namespace snapnav::nav {
namespace {

TEST(Trajectory, AlignmentRecoversARigidTransformAndAteIsZero) {
  const Pose2 t{1.5, -2.0, 0.7};
  std::vector<std::pair<Pose2, Pose2>> pairs;
  for (int i = 0; i < 20; ++i) {
    const Pose2 ref{0.3 * i, std::sin(0.4 * i), 0.1 * i};
    pairs.emplace_back(t.Inverse().Compose(ref), ref);  // estimate lives in a rotated frame
  }
  const Pose2 a = AlignSE2(pairs);
  EXPECT_NEAR(a.x_m, t.x_m, 1e-9);
  EXPECT_NEAR(a.y_m, t.y_m, 1e-9);
  EXPECT_NEAR(a.theta_rad, t.theta_rad, 1e-9);
  EXPECT_NEAR(ComputeAte(pairs, a).rmse_m, 0.0, 1e-9);
  EXPECT_GT(ComputeAte(pairs).rmse_m, 1.0);  // unaligned
  EXPECT_THROW(AlignSE2({pairs[0]}), std::invalid_argument);
}

TEST(Trajectory, AssociatesNearestInTimeWithinBound) {
  std::vector<StampedPose> ref, est;
  for (int i = 0; i < 10; ++i) ref.push_back({i * 1000, {double(i), 0, 0}});
  est.push_back({2100, {0, 0, 0}});
  est.push_back({5900, {0, 0, 0}});
  est.push_back({50000, {0, 0, 0}});  // no reference near it
  const auto pairs = AssociateByTime(est, ref, 200);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].second.x_m, 2);
  EXPECT_EQ(pairs[1].second.x_m, 6);
  const AteResult r = ComputeAte(pairs);
  EXPECT_NEAR(r.max_m, 6, 1e-12);
  EXPECT_NEAR(r.final_m, 6, 1e-12);
}

TEST(Trajectory, RelativePoseErrorOverOneMetreHandComputed) {
  // The reference drives 2 m along x in 0.5 m steps. The estimate overshoots the third pose by
  // 0.1 m and ends 0.1 rad off. Segments of 1 m: 0->2, 1->3, 2->4.
  //   0->2: estimate moved (1.1, 0, 0), reference (1, 0, 0): error 0.1 m, 0 rad
  //   1->3: (1.6 - 0.5, 0, 0) against (1, 0, 0): 0.1 m, 0 rad
  //   2->4: (2.0 - 1.1, 0, 0.1) against (1, 0, 0): (1,0,0)^-1 (0.9,0,0.1) = (-0.1, 0, 0.1)
  // Translation RMSE 0.1 m; rotation RMSE sqrt(0.1^2 / 3) rad = 3.3079 deg, max 5.7296 deg.
  const std::vector<Pose2> ref = {{0, 0, 0}, {0.5, 0, 0}, {1, 0, 0}, {1.5, 0, 0}, {2, 0, 0}};
  const std::vector<Pose2> est = {{0, 0, 0}, {0.5, 0, 0}, {1.1, 0, 0}, {1.6, 0, 0}, {2, 0, 0.1}};
  std::vector<std::pair<Pose2, Pose2>> pairs;
  for (size_t i = 0; i < ref.size(); ++i) pairs.emplace_back(est[i], ref[i]);
  const RpeResult r = ComputeRpe(pairs, 1.0);
  EXPECT_EQ(r.segments, 3);
  EXPECT_NEAR(r.translation_rmse_m, 0.1, 1e-12);
  EXPECT_NEAR(r.translation_mean_m, 0.1, 1e-12);
  EXPECT_NEAR(r.translation_max_m, 0.1, 1e-12);
  EXPECT_NEAR(r.rotation_rmse_deg, std::sqrt(0.01 / 3) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(r.rotation_max_deg, 0.1 * 180 / M_PI, 1e-9);
  // Over 2 m only 0->4 is a segment: (2, 0, 0.1) against (2, 0, 0).
  const RpeResult whole = ComputeRpe(pairs, 2.0);
  EXPECT_EQ(whole.segments, 1);
  EXPECT_NEAR(whole.translation_rmse_m, 0.0, 1e-12);
  EXPECT_NEAR(whole.rotation_rmse_deg, 0.1 * 180 / M_PI, 1e-9);
  // Longer than the path: no segment.
  EXPECT_EQ(ComputeRpe(pairs, 2.5).segments, 0);
  EXPECT_THROW(ComputeRpe(pairs, 0.0), std::invalid_argument);
  EXPECT_THROW(ComputeRpe(pairs, std::nan("")), std::invalid_argument);
}

TEST(Trajectory, RelativePoseErrorIgnoresTheFrameAndCountsTenthsAsAMetre) {
  // The estimate is the reference seen from another frame: ATE without alignment is large,
  // RPE is zero. Steps of 0.1 m: ten of them make 1 m despite rounding.
  const Pose2 frame{3.0, -1.0, 0.8};
  std::vector<std::pair<Pose2, Pose2>> pairs;
  Pose2 ref;
  for (int i = 0; i < 40; ++i) {
    pairs.emplace_back(frame.Compose(ref), ref);
    ref = ref.Compose({0.1, 0, 0.05});
  }
  EXPECT_GT(ComputeAte(pairs).rmse_m, 1.0);
  const RpeResult r = ComputeRpe(pairs, 1.0);
  EXPECT_EQ(r.segments, 40 - 10);
  EXPECT_NEAR(r.translation_max_m, 0.0, 1e-9);
  EXPECT_NEAR(r.rotation_max_deg, 0.0, 1e-9);
}

}  // namespace
}  // namespace snapnav::nav
