// The fused filter (libnav): visual pose measurements in the laser SLAM's EKF, the gate, the
// relocalisation after a kidnapping, late measurements and the map protection. Hand-checked
// numbers where the filter is a plain Kalman update.
#include "snapnav/nav/slam/fused_slam.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>

namespace snapnav::nav {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;  // [us]

Eigen::Matrix3d Diag(double sxy, double stheta) {
  return Eigen::Vector3d(sxy * sxy, sxy * sxy, stheta * stheta).asDiagonal();
}

// Points a laser at `robot` sees inside the rectangle [0, w] x [0, h] (walls only), every 1 deg
// over 360 deg, in the robot frame.
std::vector<Eigen::Vector2d> RoomScan(const Pose2& robot, double w, double h) {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 360; ++i) {
    const double a = robot.theta_rad + i * M_PI / 180.0;
    const double dx = std::cos(a), dy = std::sin(a);
    double t = std::numeric_limits<double>::infinity();
    if (dx > 1e-9) t = std::min(t, (w - robot.x_m) / dx);
    if (dx < -1e-9) t = std::min(t, -robot.x_m / dx);
    if (dy > 1e-9) t = std::min(t, (h - robot.y_m) / dy);
    if (dy < -1e-9) t = std::min(t, -robot.y_m / dy);
    const Eigen::Vector2d world(robot.x_m + t * dx, robot.y_m + t * dy);
    points.push_back(robot.Inverse().Transform(world));
  }
  return points;
}

// RoomScan with a person (a disc at `person`, radius r) in the room: the beams that hit the disc
// end on it. `hits` (optional) gets how many do.
std::vector<Eigen::Vector2d> RoomScanWithPerson(const Pose2& robot, double w, double h, const Eigen::Vector2d& person,
                                                double r, int* hits = nullptr) {
  std::vector<Eigen::Vector2d> points = RoomScan(robot, w, h);
  int n = 0;
  const Eigen::Vector2d o(robot.x_m, robot.y_m);
  for (int i = 0; i < 360; ++i) {
    const double a = robot.theta_rad + i * M_PI / 180.0;
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    const double along = (person - o).dot(dir);
    const double across2 = (person - o).squaredNorm() - along * along;
    if (along <= 0 || across2 >= r * r) continue;
    const double t = along - std::sqrt(r * r - across2);
    if (t >= points[static_cast<size_t>(i)].norm()) continue;
    points[static_cast<size_t>(i)] = robot.Inverse().Transform(o + t * dir);
    ++n;
  }
  if (hits) *hits = n;
  return points;
}

// Options with no uncertainty of the laser's pose relative to its own map at the start: the fused
// covariance is then the start's alone (the map's offset from the world), and the visual updates
// are plain Kalman updates of that offset.
FusedSlamOptions PlainOptions() {
  FusedSlamOptions o;
  o.laser.initial_sigma_xy_m = 0;
  o.laser.initial_sigma_theta_rad = 0;
  o.suspect_after = 1;  // map protection on (off by default), as these cases count on it
  o.map_cell_m = 1.0;
  return o;
}

TEST(FusedSlam, ConsistentVisualMeasurementPullsADriftedPoseBack) {
  // Drifted prediction at x = 1.2 (sigma 0.1 m, 0.05 rad); a visual fix at the truth x = 1.0
  // (sigma 0.05 m, 0.03 rad). S_xx = 0.01 + 0.0025 = 0.0125: d2 = 0.2^2 / 0.0125 = 3.2, accepted;
  // K_xx = 0.01 / 0.0125 = 0.8: x = 1.2 - 0.8 * 0.2 = 1.04, var = 0.01 * 0.0025 / 0.0125 = 0.002.
  FusedSlamOptions o = PlainOptions();
  FusedSlam f(o, {1.2, 0.0, 0.0}, Diag(0.1, 0.05));
  const VisualUpdate v = f.AddVisual(kT0, {1.0, 0.0, 0.0}, Diag(0.05, 0.03));
  EXPECT_EQ(v.outcome, VisualOutcome::kAccepted);
  EXPECT_NEAR(v.mahalanobis2, 3.2, 1e-9);
  EXPECT_NEAR(f.pose().x_m, 1.04, 1e-9);
  EXPECT_NEAR(f.pose().y_m, 0.0, 1e-12);
  EXPECT_NEAR(f.covariance()(0, 0), 0.002, 1e-12);
  // Heading: the first fix left var = 0.0025 * 0.0009 / 0.0034; a fix 0.05 rad off moves the
  // heading by K = var / (var + 0.0009) times 0.05 (= 0.02119 rad).
  const double var = 0.0025 * 0.0009 / 0.0034;
  EXPECT_NEAR(f.covariance()(2, 2), var, 1e-12);
  const VisualUpdate h = f.AddVisual(kT0, {1.04, 0.0, 0.05}, Diag(0.05, 0.03));
  EXPECT_EQ(h.outcome, VisualOutcome::kAccepted);
  EXPECT_NEAR(f.pose().theta_rad, 0.05 * var / (var + 0.0009), 1e-9);
  EXPECT_EQ(f.accepted(), 2);
  EXPECT_EQ(f.rejected(), 0);
}

TEST(FusedSlam, VisualMeasurementBelowTheSigmaFloorIsFloored) {
  // A fix claiming 1 mm is taken as min_fix_sigma_xy_m = 0.05 m: the same update as above.
  FusedSlamOptions o = PlainOptions();
  FusedSlam f(o, {1.2, 0.0, 0.0}, Diag(0.1, 0.05));
  EXPECT_EQ(f.AddVisual(kT0, {1.0, 0.0, 0.0}, Diag(0.001, 0.03)).outcome, VisualOutcome::kAccepted);
  EXPECT_NEAR(f.pose().x_m, 1.04, 1e-9);
}

TEST(FusedSlam, OutlierIsGatedOut) {
  // 1.8 m off: d2 = 1.8^2 / 0.0125 = 259.2 > 11.34: rejected, the pose does not move.
  FusedSlamOptions o = PlainOptions();
  FusedSlam f(o, {1.2, 0.0, 0.0}, Diag(0.1, 0.05));
  const VisualUpdate v = f.AddVisual(kT0, {3.0, 0.0, 0.0}, Diag(0.05, 0.03));
  EXPECT_EQ(v.outcome, VisualOutcome::kRejected);
  EXPECT_NEAR(v.mahalanobis2, 259.2, 1e-6);
  EXPECT_EQ(f.pose().x_m, 1.2);
  EXPECT_TRUE(f.covariance().isApprox(Diag(0.1, 0.05)));
  EXPECT_EQ(f.rejected(), 1);
  EXPECT_EQ(f.consecutive_rejections(), 1);
  EXPECT_TRUE(f.suspect());  // suspect_after = 1: the map is protected now
  // A consistent fix clears the suspicion and the hypothesis.
  EXPECT_EQ(f.AddVisual(kT0, {1.1, 0.0, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kAccepted);
  EXPECT_FALSE(f.suspect());
  EXPECT_FALSE(f.hypothesis().has_value());
  // The heading alone can fail the gate too: 0.5 rad off with S = 0.0025 + 0.0009.
  EXPECT_EQ(f.AddVisual(kT0, {f.pose().x_m, 0.0, 0.5}, Diag(0.05, 0.03)).outcome, VisualOutcome::kRejected);
}

TEST(FusedSlam, KidnappingIsRecoveredAfterAgreeingRejections) {
  // The filter believes it is at (1, 1) heading 0 with 2 cm; the robot was carried to (29, 1).
  // It drives 0.1 m per step; the visual fixes say (29 + 0.1 k, 1) with 0.05 m.
  FusedSlamOptions o = PlainOptions();
  o.relocalize_after = 4;
  FusedSlam f(o, {1.0, 1.0, 0.0}, Diag(0.02, 0.01));
  int64_t t = kT0;
  for (int k = 0; k < 4; ++k) {
    if (k > 0) {
      t += 500000;
      f.Predict(t, {0.1, 0.0, 0.0});
    }
    const VisualUpdate v = f.AddVisual(t, {29.0 + 0.1 * k, 1.0, 0.0}, Diag(0.05, 0.03));
    if (k < 3) {
      EXPECT_EQ(v.outcome, VisualOutcome::kRejected) << k;
      EXPECT_EQ(v.agreeing_rejections, k + 1);
      EXPECT_NEAR(f.pose().x_m, 1.0 + 0.1 * k, 1e-9);  // the laser pose stays where it was
    } else {
      EXPECT_EQ(v.outcome, VisualOutcome::kRelocalized);
    }
  }
  EXPECT_EQ(f.relocalizations(), 1);
  EXPECT_NEAR(f.pose().x_m, 29.3, 1e-3);
  EXPECT_NEAR(f.pose().y_m, 1.0, 1e-3);
  EXPECT_NEAR(f.pose().theta_rad, 0.0, 1e-3);
  // Widened to relocalize_sigma_xy_m = 0.2 m, relocalize_sigma_theta_rad = 0.087 rad.
  EXPECT_NEAR(f.covariance()(0, 0), 0.04, 1e-12);
  EXPECT_NEAR(f.covariance()(2, 2), 0.087 * 0.087, 1e-12);
  EXPECT_EQ(f.consecutive_rejections(), 0);
  EXPECT_FALSE(f.hypothesis().has_value());
  // After it the fixes agree with the filter again.
  t += 500000;
  f.Predict(t, {0.1, 0.0, 0.0});
  EXPECT_EQ(f.AddVisual(t, {29.4, 1.0, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kAccepted);
}

TEST(FusedSlam, RejectionsThatDisagreeDoNotRelocalise) {
  // Outliers all over the place (aliasing) rarely agree with each other: two at x = 10 do, but
  // fewer than relocalize_after = 3: no relocalisation.
  FusedSlamOptions o;
  o.relocalize_after = 3;
  FusedSlam f(o, {1.0, 1.0, 0.0}, Diag(0.02, 0.01));
  const double xs[] = {10.0, 20.0, 10.0, 25.0, 5.0, 15.0};
  const int agreeing[] = {1, 1, 2, 1, 1, 1};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(f.AddVisual(kT0, {xs[i], 1.0, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kRejected);
    EXPECT_EQ(f.agreeing_rejections(), agreeing[i]) << i;
  }
  EXPECT_EQ(f.relocalizations(), 0);
  EXPECT_NEAR(f.pose().x_m, 1.0, 1e-12);
  EXPECT_EQ(f.rejected(), 6);
  EXPECT_EQ(f.consecutive_rejections(), 6);
  // relocalize_after = 0: never, however consistent.
  o.relocalize_after = 0;
  FusedSlam never(o, {1.0, 1.0, 0.0}, Diag(0.02, 0.01));
  for (int k = 0; k < 20; ++k) never.AddVisual(kT0, {29.0, 1.0, 0.0}, Diag(0.05, 0.03));
  EXPECT_EQ(never.relocalizations(), 0);
  EXPECT_GE(never.agreeing_rejections(), 8);  // the window keeps at least 8
}

TEST(FusedSlam, OutliersBetweenAgreeingRejectionsDoNotStopTheRelocalisation) {
  // The filter was led 1 m astray; fixes at the truth (2, 1) alternate with aliasing outliers:
  // the 3rd agreeing rejection relocalises, the outliers between them do not matter.
  FusedSlamOptions o;
  o.relocalize_after = 3;
  FusedSlam f(o, {1.0, 1.0, 0.0}, Diag(0.02, 0.01));
  const double xs[] = {2.0, 15.0, 2.0, 8.0, 2.0};
  const VisualOutcome expected[] = {VisualOutcome::kRejected, VisualOutcome::kRejected, VisualOutcome::kRejected,
                                    VisualOutcome::kRejected, VisualOutcome::kRelocalized};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(f.AddVisual(kT0, {xs[i], 1.0, 0.0}, Diag(0.05, 0.03)).outcome, expected[i]) << i;
  EXPECT_NEAR(f.pose().x_m, 2.0, 1e-9);
  // Evidence older than relocalize_window_s (10 s) is forgotten.
  FusedSlam g(o, {1.0, 1.0, 0.0}, Diag(0.02, 0.01));
  g.Predict(kT0, {});
  g.AddVisual(kT0, {2.0, 1.0, 0.0}, Diag(0.05, 0.03));
  g.AddVisual(kT0, {2.0, 1.0, 0.0}, Diag(0.05, 0.03));
  g.Predict(kT0 + 11'000'000, {});
  EXPECT_EQ(g.AddVisual(kT0 + 11'000'000, {2.0, 1.0, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kRejected);
  EXPECT_EQ(g.agreeing_rejections(), 1);
}

TEST(FusedSlam, AliasedFixesAmongAcceptedOnesDoNotRelocalise) {
  // The filter is right at (1, 1); aliasing (views a metre ahead along a wall look alike) gives four
  // fixes that agree with each other at x + 1.2 m, interleaved with three right fixes it accepts
  // (people11, seed 1: such a run moved a right filter 1 m and it never came back). Net of the
  // accepted ones the evidence is 1, below relocalize_after = 4. The same rejected fixes with no
  // accepted ones between them (a kidnapping) relocalise; and so do these with the rule off.
  const auto run = [](bool net_of_accepted, bool with_right_fixes) {
    FusedSlamOptions o = PlainOptions();
    o.relocalize_after = 4;
    o.relocalize_net_of_accepted = net_of_accepted;
    FusedSlam f(o, {1.0, 1.0, 0.0}, Diag(0.02, 0.01));
    int64_t t = kT0;
    double x = 1.0;
    const bool wrong[] = {true, true, false, false, false, true, true};
    std::vector<VisualOutcome> outcomes;
    for (int k = 0; k < 7; ++k) {
      if (k > 0) {
        t += 500000;
        x += 0.15;
        f.Predict(t, {0.15, 0.0, 0.0});
      }
      if (!wrong[k] && !with_right_fixes) continue;
      outcomes.push_back(f.AddVisual(t, {wrong[k] ? x + 1.2 : x, 1.0, 0.0}, Diag(0.08, 0.02)).outcome);
    }
    return std::make_pair(f.relocalizations(), outcomes);
  };
  const auto [aliased, outcomes] = run(true, true);
  EXPECT_EQ(aliased, 0);
  ASSERT_EQ(outcomes.size(), 7u);
  for (int k : {2, 3, 4}) EXPECT_EQ(outcomes[static_cast<size_t>(k)], VisualOutcome::kAccepted) << k;
  for (int k : {0, 1, 5, 6}) EXPECT_EQ(outcomes[static_cast<size_t>(k)], VisualOutcome::kRejected) << k;
  EXPECT_EQ(run(true, false).first, 1);   // only the four agreeing rejections: a kidnapping
  EXPECT_EQ(run(false, true).first, 1);   // the rule off: the aliasing relocalises
}

TEST(FusedSlam, LateMeasurementIsCarriedForwardByOdometry) {
  // A fix of the pose 0.3 s ago arrives after three odometry increments of 0.1 m: it is compared
  // with the current pose after moving it by those 0.3 m.
  FusedSlamOptions o;
  FusedSlam f(o, {0.0, 0.0, 0.0}, Diag(0.1, 0.05));
  for (int k = 1; k <= 3; ++k) f.Predict(kT0 + k * 100000, {0.1, 0.0, 0.0});
  // The pose 0.3 s ago (kT0) is the current one moved back.
  const auto back = f.PoseAt(kT0);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(back->x_m, 0.0, 1e-12);
  EXPECT_NEAR(f.PoseAt(kT0 + 200000)->x_m, 0.2, 1e-12);
  const VisualUpdate v = f.AddVisual(kT0, {0.0, 0.0, 0.0}, Diag(0.05, 0.03));
  EXPECT_EQ(v.outcome, VisualOutcome::kAccepted);
  EXPECT_NEAR(v.measurement.x_m, 0.3, 1e-12);
  EXPECT_NEAR(v.mahalanobis2, 0.0, 1e-12);
  EXPECT_GT(v.measurement_covariance(0, 0), 0.05 * 0.05);  // the odometry's noise was added
  // Older than max_fix_age_s (2 s) before the latest odometry: stale, nothing changes.
  f.Predict(kT0 + 3'000'000, {0.0, 0.0, 0.0});
  EXPECT_EQ(f.AddVisual(kT0 + 500000, {5.0, 0.0, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kStale);
  EXPECT_EQ(f.stale(), 1);
  EXPECT_FALSE(f.PoseAt(kT0).has_value());
}

TEST(FusedSlam, MapIsProtectedWhileSuspect) {
  // A 6 x 4 m room: the first scan builds the map. While a rejected visual fix makes the filter
  // suspect, a scan seen from elsewhere (the robot was carried off) adds no points.
  FusedSlamOptions o;
  o.suspect_after = 1;  // map protection is off by default
  FusedSlam f(o, {1.0, 1.0, 0.0}, Diag(0.01, 0.01));
  f.Update(RoomScan({1.0, 1.0, 0.0}, 6, 4));
  const size_t mapped = f.map().size();
  ASSERT_GT(mapped, 100u);
  EXPECT_EQ(f.AddVisual(kT0, {5.0, 3.0, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kRejected);
  ASSERT_TRUE(f.suspect());
  // The robot is really at (5, 3) in a 10 x 4 room: points the map does not have.
  f.Update(RoomScan({5.0, 3.0, 0.0}, 10, 4));
  EXPECT_EQ(f.map().size(), mapped);
  EXPECT_EQ(f.unmapped_scans(), 1);
  // Without protection the same scan adds points.
  o.suspect_after = 0;
  FusedSlam open(o, {1.0, 1.0, 0.0}, Diag(0.01, 0.01));
  open.Update(RoomScan({1.0, 1.0, 0.0}, 6, 4));
  open.AddVisual(kT0, {5.0, 3.0, 0.0}, Diag(0.05, 0.03));
  EXPECT_FALSE(open.suspect());
  open.Update(RoomScan({5.0, 3.0, 0.0}, 10, 4));
  EXPECT_GT(open.map().size(), mapped);
}

TEST(FusedSlam, ScansKeepThePoseOnTheMapAndVisualFixesAnchorIt) {
  // Laser and visual measurements share one EKF: after a consistent visual fix, scans of a
  // 6 x 4 room hold the pose on the map while the odometry overestimates every step by 20 %.
  FusedSlamOptions o;
  FusedSlam f(o, {2.0, 1.5, 0.0}, Diag(0.01, 0.01));
  f.Update(RoomScan({2.0, 1.5, 0.0}, 6, 4));
  EXPECT_EQ(f.AddVisual(kT0, {2.02, 1.5, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kAccepted);
  for (int k = 1; k <= 10; ++k) {
    f.Predict(kT0 + k * 100000, {0.06, 0.0, 0.0});
    f.Update(RoomScan({2.0 + 0.05 * k, 1.5, 0.0}, 6, 4));
  }
  EXPECT_NEAR(f.pose().x_m, 2.5, 0.03);
  EXPECT_NEAR(f.pose().y_m, 1.5, 0.03);
  EXPECT_EQ(f.accepted(), 1);
}

TEST(FusedSlam, ConsistentFixesPullAMapThatIsOffBackAndTheLaserStaysOnIt) {
  // The start is 0.1 m off in x (sigma 0.1 m): the room's map, built from it, is 0.1 m off the
  // world. Fixes at the truth (sigma 0.05 m) update the offset of every map cell the scan sees:
  // the fused pose moves to the truth, the laser's pose in its own map does not move, and the
  // cells' covariances shrink but stay positive however many fixes come.
  FusedSlamOptions o;
  FusedSlam f(o, {2.1, 1.5, 0.0}, Diag(0.1, 0.05));
  f.Update(RoomScan({2.0, 1.5, 0.0}, 6, 4));
  const Pose2 laser = f.laser().pose();
  EXPECT_NEAR(f.pose().x_m, 2.1, 1e-3);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(f.AddVisual(kT0, {2.0, 1.5, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kAccepted) << k;
  }
  // Each cell: prior 0.01 m^2, ten fixes of ~0.0026 m^2: 0.1 m * 100 / (100 + 10 / 0.0026) is left.
  EXPECT_NEAR(f.pose().x_m, 2.0, 0.01);
  EXPECT_NEAR(f.pose().y_m, 1.5, 0.01);
  EXPECT_EQ(f.laser().pose().x_m, laser.x_m);
  EXPECT_EQ(f.laser().pose().y_m, laser.y_m);
  EXPECT_LT(f.covariance()(0, 0), 0.001);
  const auto wall = f.MapOffsetAt({0.1, 1.5});  // the left wall as the map has it
  ASSERT_TRUE(wall.has_value());
  EXPECT_NEAR(wall->offset.x(), 0.1, 0.02);
  for (int k = 0; k < 300; ++k) f.AddVisual(kT0, {2.0, 1.5, 0.0}, Diag(0.05, 0.03));
  EXPECT_NEAR(f.pose().x_m, 2.0, 0.002);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(f.robot_offset_covariance());
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  EXPECT_GT(f.covariance().diagonal().minCoeff(), 0.0);
  // An outlier is gated out and moves nothing.
  const Pose2 before = f.pose();
  EXPECT_EQ(f.AddVisual(kT0, {3.5, 1.5, 0.0}, Diag(0.05, 0.03)).outcome, VisualOutcome::kRejected);
  EXPECT_EQ(f.pose().x_m, before.x_m);
}

// Builds the map of the 6 x 4 room from (2, 1.5) over 1.1 s of scans (standing still), so that its
// points are older than dynamic_map_age_s (1 s).
void MapTheRoom(FusedSlam* f) {
  for (int k = 0; k <= 11; ++k) {
    f->Predict(kT0 + k * 100000, {0.0, 0.0, 0.0});
    f->Update(RoomScan({2.0, 1.5, 0.0}, 6, 4));
  }
}

TEST(FusedSlam, PersonInFrontOfAMappedWallIsLeftOutOfTheLasersScanAndMap) {
  // A person (0.25 m radius) steps 1 m in front of the robot, between it and the mapped wall: the
  // beams that end on them are dynamic (the wall behind is in the map, 1.1 s old), left out of the
  // laser's update and map; their share is the occluded fraction. The pose stays where it was.
  FusedSlamOptions o;
  ASSERT_GT(o.dynamic_explain_m, 0.0);  // on by default
  FusedSlam f(o, {2.0, 1.5, 0.0}, Diag(0.01, 0.01));
  MapTheRoom(&f);
  EXPECT_EQ(f.dynamic_points(), 0);  // the room alone: nothing dynamic
  EXPECT_EQ(f.occluded_fraction(), 0.0);
  int hits = 0;
  const auto scan = RoomScanWithPerson({2.0, 1.5, 0.0}, 6, 4, {3.0, 1.5}, 0.25, &hits);
  ASSERT_GT(hits, 20);
  const Pose2 before = f.pose();
  f.Predict(kT0 + 1'200'000, {0.0, 0.0, 0.0});
  f.Update(scan);
  EXPECT_EQ(f.dynamic_points(), hits);
  EXPECT_NEAR(f.occluded_fraction(), hits / 360.0, 1e-12);
  EXPECT_EQ(f.dynamic_overflow_scans(), 0);
  // The map frame is the start's: the person stands at (1, 0) in it.
  EXPECT_FALSE(f.map().Nearest({1.0, 0.0}, 0.3).has_value());
  EXPECT_NEAR(f.pose().x_m, before.x_m, 0.001);  // the scan of the rest holds the pose
  EXPECT_NEAR(f.pose().y_m, before.y_m, 0.001);
  // Without the test (dynamic_explain_m 0) the person joins the map.
  o.dynamic_explain_m = 0;
  FusedSlam plain(o, {2.0, 1.5, 0.0}, Diag(0.01, 0.01));
  MapTheRoom(&plain);
  plain.Predict(kT0 + 1'200'000, {0.0, 0.0, 0.0});
  plain.Update(scan);
  EXPECT_EQ(plain.dynamic_points(), 0);
  EXPECT_TRUE(plain.map().Nearest({1.0, 0.0}, 0.3).has_value());
}

TEST(FusedSlam, APersonTheMapHasJustSeenIsStillDynamic) {
  // The person walks along in front of the wall, 5 cm per scan: the map points of the scans just
  // before (younger than dynamic_map_age_s) do not explain them, so they stay out of the map.
  FusedSlamOptions o;
  FusedSlam f(o, {2.0, 1.5, 0.0}, Diag(0.01, 0.01));
  MapTheRoom(&f);
  int total = 0;
  for (int k = 0; k < 10; ++k) {
    int hits = 0;
    f.Predict(kT0 + 1'200'000 + k * 100000, {0.0, 0.0, 0.0});
    f.Update(RoomScanWithPerson({2.0, 1.5, 0.0}, 6, 4, {3.0, 1.2 + 0.05 * k}, 0.25, &hits));
    total += hits;
  }
  EXPECT_EQ(f.dynamic_points(), total);
  for (int k = 0; k < 10; ++k) EXPECT_FALSE(f.map().Nearest({1.0, -0.3 + 0.05 * k}, 0.3).has_value()) << k;
}

TEST(FusedSlam, TooManyDynamicPointsMeanTheWholeScanIsKept) {
  // More of the scan dynamic than dynamic_max_fraction: the prediction is off, not people; no
  // point is left out. A person 0.6 m away hides ~49 deg (13.6 %) of the 360 deg scan.
  FusedSlamOptions o;
  o.dynamic_max_fraction = 0.1;
  FusedSlam f(o, {2.0, 1.5, 0.0}, Diag(0.01, 0.01));
  MapTheRoom(&f);
  int hits = 0;
  f.Predict(kT0 + 1'200'000, {0.0, 0.0, 0.0});
  f.Update(RoomScanWithPerson({2.0, 1.5, 0.0}, 6, 4, {2.6, 1.5}, 0.25, &hits));
  ASSERT_GT(hits / 360.0, 0.1);
  EXPECT_NEAR(f.occluded_fraction(), hits / 360.0, 1e-12);
  EXPECT_EQ(f.dynamic_overflow_scans(), 1);
  EXPECT_EQ(f.dynamic_points(), 0);
  EXPECT_TRUE(f.map().Nearest({0.6, 0.0}, 0.3).has_value());  // the person joined the map
}

TEST(FusedSlam, AnOccludedViewsFixIsDownWeighted) {
  // occlusion_fix_inflation k: a fix taken while the last scan was occluded by a fraction f has its
  // covariance times (1 + k f)^2, so it moves the pose less than the same fix in a clear view.
  FusedSlamOptions o;
  o.occlusion_fix_inflation = 2;
  FusedSlam occluded(o, {2.0, 1.5, 0.0}, Diag(0.1, 0.05));
  FusedSlam clear(o, {2.0, 1.5, 0.0}, Diag(0.1, 0.05));
  MapTheRoom(&occluded);
  MapTheRoom(&clear);
  occluded.Predict(kT0 + 1'200'000, {0.0, 0.0, 0.0});
  clear.Predict(kT0 + 1'200'000, {0.0, 0.0, 0.0});
  occluded.Update(RoomScanWithPerson({2.0, 1.5, 0.0}, 6, 4, {3.0, 1.5}, 0.25));
  clear.Update(RoomScan({2.0, 1.5, 0.0}, 6, 4));
  const double f = occluded.occluded_fraction();
  ASSERT_GT(f, 0.05);
  ASSERT_EQ(clear.occluded_fraction(), 0.0);
  const VisualUpdate vo = occluded.AddVisual(kT0 + 1'200'000, {2.1, 1.5, 0.0}, Diag(0.1, 0.05));
  const VisualUpdate vc = clear.AddVisual(kT0 + 1'200'000, {2.1, 1.5, 0.0}, Diag(0.1, 0.05));
  ASSERT_EQ(vo.outcome, VisualOutcome::kAccepted);
  ASSERT_EQ(vc.outcome, VisualOutcome::kAccepted);
  EXPECT_NEAR(vc.measurement_covariance(0, 0), 0.01, 1e-12);
  EXPECT_NEAR(vo.measurement_covariance(0, 0), 0.01 * (1 + 2 * f) * (1 + 2 * f), 1e-12);
  EXPECT_GT(clear.pose().x_m - 2.0, occluded.pose().x_m - 2.0);
  EXPECT_GT(occluded.pose().x_m, 2.0);  // still pulled, less
}

// Points a laser at `robot` sees in a corridor between the walls y = 0 and y = 2 (no end in
// reach), every 0.5 deg over 240 deg ahead, up to 5.6 m (the simulator's laser), each range off by
// Gaussian noise of 1 cm (seeded): the walls' normals are a little noisy, as real ones are.
std::vector<Eigen::Vector2d> CorridorScan(const Pose2& robot, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector2d> points;
  for (int i = -240; i <= 240; ++i) {
    const double a = robot.theta_rad + i * 0.5 * M_PI / 180.0;
    const double dy = std::sin(a);
    double t = std::numeric_limits<double>::infinity();
    if (dy > 1e-9) t = (2.0 - robot.y_m) / dy;
    if (dy < -1e-9) t = -robot.y_m / dy;
    if (!(t <= 5.6)) continue;
    t += noise(*rng);
    const Eigen::Vector2d world(robot.x_m + t * std::cos(a), robot.y_m + t * dy);
    points.push_back(robot.Inverse().Transform(world));
  }
  return points;
}

// Drives `steps` scans of 0.1 m along the corridor's axis (x) from (0, 1); the odometry reports
// `odometry_m` per step.
void DriveTheCorridor(FusedSlam* f, int steps, double odometry_m, int64_t t0 = kT0) {
  std::mt19937 rng(7);
  f->Update(CorridorScan({0.0, 1.0, 0.0}, &rng));
  for (int k = 1; k <= steps; ++k) {
    f->Predict(t0 + k * 100000, {odometry_m, 0.0, 0.0});
    f->Update(CorridorScan({0.1 * k, 1.0, 0.0}, &rng));
  }
}

TEST(FusedSlam, ADegenerateCorridorLeavesItsAxisUncertain) {
  // Along a corridor's axis the walls constrain nothing, but the noisy normals give every scan a
  // little information there (a few % of a wall's), and scan after scan the laser's covariance
  // claims millimetres. laser_min_constraint leaves that direction out: along the axis fused SLAM's
  // covariance grows with the odometry (5 cm per metre of each increment: 0.05 * 0.1 * sqrt(50) =
  // 3.5 cm), across it and in heading it stays the laser's.
  FusedSlamOptions o;
  o.laser_min_constraint = 0.15;
  FusedSlam f(o, {0.0, 1.0, 0.0});
  DriveTheCorridor(&f, 50, 0.1);
  EXPECT_GT(f.degenerate_scans(), 45);
  EXPECT_LT(f.weakest_constraint(), 0.1);
  EXPECT_LT(std::sqrt(f.laser().covariance()(0, 0)), 0.01);  // the laser's own claim
  EXPECT_GT(std::sqrt(f.laser_covariance()(0, 0)), 0.025);
  EXPECT_LT(std::sqrt(f.laser_covariance()(1, 1)), 0.01);
  EXPECT_LT(std::sqrt(f.laser_covariance()(2, 2)), 0.01);
  EXPECT_GT(std::sqrt(f.covariance()(0, 0)), 0.025);  // the world pose's
  // Off: the laser's covariance, as before.
  FusedSlam off(FusedSlamOptions{}, {0.0, 1.0, 0.0});
  DriveTheCorridor(&off, 50, 0.1);
  EXPECT_EQ(off.laser_covariance(), off.laser().covariance());
  EXPECT_LT(std::sqrt(off.covariance()(0, 0)), 0.015);
  EXPECT_EQ(off.degenerate_scans(), 0);
}

TEST(FusedSlam, InARoomNoDirectionIsDegenerate) {
  FusedSlamOptions o;
  o.laser_min_constraint = 0.15;
  FusedSlam f(o, {2.0, 1.5, 0.0});
  f.Update(RoomScan({2.0, 1.5, 0.0}, 6, 4));
  for (int k = 1; k <= 10; ++k) {
    f.Predict(kT0 + k * 100000, {0.05, 0.0, 0.0});
    f.Update(RoomScan({2.0 + 0.05 * k, 1.5, 0.0}, 6, 4));
  }
  EXPECT_EQ(f.degenerate_scans(), 0);
  EXPECT_GT(f.weakest_constraint(), 0.18);  // well above laser_min_constraint
  EXPECT_LT((f.laser_covariance() - f.laser().covariance()).norm(), 1e-5);
}

TEST(FusedSlam, VisualFixesCorrectTheLasersSlideAlongACorridor) {
  // The odometry reports 0.098 m per 0.1 m step: along the featureless corridor the laser slides
  // off the truth (its map with it; 10-20 cm after 5 m). Fixes at the truth (8 cm) correct that where
  // the laser's drift is a state of its own (laser_min_constraint); without it the fixes are set
  // against a laser that claims millimetres, and correct less.
  const auto run = [](double min_constraint, bool inherit) {
    FusedSlamOptions o;
    o.laser_min_constraint = min_constraint;
    o.map_inherits_laser_drift = inherit;
    FusedSlam f(o, {0.0, 1.0, 0.0});
    DriveTheCorridor(&f, 50, 0.098);
    EXPECT_LT(f.pose().x_m, 4.95);  // slid (ICP's point-to-point matches along the walls add to it)
    for (int k = 0; k < 10; ++k) {
      const VisualUpdate v = f.AddVisual(kT0 + 50 * 100000, {5.0, 1.0, 0.0}, Diag(0.08, 0.02));
      EXPECT_EQ(v.outcome, VisualOutcome::kAccepted) << k;
    }
    return f.pose().x_m;
  };
  const double with = run(0.15, true), without = run(0, false);
  std::cout << "after the fixes: " << with << " m with the laser's drift a state of its own, " << without
            << " m without\n";
  EXPECT_NEAR(with, 5.0, 0.07);
  EXPECT_LT(std::abs(with - 5.0), std::abs(without - 5.0) - 0.02);
}

TEST(FusedSlam, TheMapsDriftAccumulatesOverScansThatMapNoNewCell) {
  // Exploring the corridor, a scan reaches a new 2 m cell about every 2 m; most scans map none.
  // With map_drift_accumulates the drift travelled in between goes into the next new cells, and the
  // offset's uncertainty grows along the exploration as map_drift_xy_m per square root of the
  // metres; without it each new cell gets one scan's (0.1 m) drift only.
  const auto sigma_x = [](bool accumulates) {
    FusedSlamOptions o;
    o.map_drift_accumulates = accumulates;
    FusedSlam f(o, {0.0, 1.0, 0.0});
    DriveTheCorridor(&f, 100, 0.1);
    return std::sqrt(f.robot_offset_covariance()(0, 0));
  };
  const double with = sigma_x(true), without = sigma_x(false);
  EXPECT_GT(with, 2 * without);
  EXPECT_GT(with, 0.05);  // 10 m explored: 0.05 sqrt(10) = 0.16 m at the newest cells
  EXPECT_LT(with, 0.2);
}

TEST(FusedSlam, CorrelatedFixesAreWorthFewerIndependentOnes) {
  // A robot standing still sees the same view: its fixes share their error. With
  // fix_correlation_m each fix after the first is worth (1 - rho) / (1 + rho) of one (rho =
  // exp(-s / L), s the travel since the previous fix): standing still, nothing.
  FusedSlamOptions o = PlainOptions();
  o.fix_correlation_m = 0.5;
  FusedSlam f(o, {2.1, 1.5, 0.0}, Diag(0.1, 0.05));
  f.Update(RoomScan({2.0, 1.5, 0.0}, 6, 4));
  for (int k = 0; k < 20; ++k) f.AddVisual(kT0, {2.0, 1.5, 0.0}, Diag(0.05, 0.03));
  // One fix's worth: 2.1 - 0.1 * 0.01 / (0.01 + 0.0025 (+ the laser's)) ~ 2.02.
  EXPECT_NEAR(f.pose().x_m, 2.02, 0.01);
  EXPECT_EQ(f.accepted(), 20);
}

TEST(FusedSlam, InvalidInputThrows) {
  FusedSlamOptions o;
  FusedSlam f(o);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(f.AddVisual(kT0, {nan, 0, 0}, Diag(0.1, 0.1)), std::invalid_argument);
  Eigen::Matrix3d bad = Diag(0.1, 0.1);
  bad(1, 1) = -1;
  EXPECT_THROW(f.AddVisual(kT0, {0, 0, 0}, bad), std::invalid_argument);
  bad(1, 1) = nan;
  EXPECT_THROW(f.AddVisual(kT0, {0, 0, 0}, bad), std::invalid_argument);
  EXPECT_THROW(f.Predict(kT0, {nan, 0, 0}), std::invalid_argument);
  o.gate_chi2 = 0;
  EXPECT_THROW(FusedSlam{o}, std::invalid_argument);
  o = {};
  o.map_min_fit = 1.5;
  EXPECT_THROW(FusedSlam{o}, std::invalid_argument);
  o = {};
  o.dynamic_explain_m = -0.1;
  EXPECT_THROW(FusedSlam{o}, std::invalid_argument);
  o = {};
  o.dynamic_max_fraction = 1.5;
  EXPECT_THROW(FusedSlam{o}, std::invalid_argument);
  o = {};
  o.occlusion_fix_inflation = -1;
  EXPECT_THROW(FusedSlam{o}, std::invalid_argument);
  o = {};
  o.relocalize_after = -1;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  EXPECT_EQ(std::string(VisualOutcomeName(VisualOutcome::kRelocalized)), "relocalized");
}

}  // namespace
}  // namespace snapnav::nav
