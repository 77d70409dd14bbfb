#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "snapnav/nav/slam/wall_orientations.hpp"

namespace snapnav::nav {
namespace {

constexpr double kDeg = M_PI / 180;

Eigen::Vector2d Normal(double deg) { return {std::cos(deg * kDeg), std::sin(deg * kDeg)}; }

// A map of walls along two perpendicular directions (12 and 102 deg normals), each normal a little
// off (+-0.5 deg), some facing the other way (a wall has two sides).
WallOrientations Building() {
  WallOrientations walls;
  for (int i = 0; i < 400; ++i) {
    const double jitter = 0.5 * std::sin(i * 1.7);
    walls.Add((i % 2 ? 1.0 : -1.0) * Normal(12 + jitter));
    walls.Add(Normal(102 + jitter));
  }
  return walls;
}

// A scan of the same walls seen with its heading `turn_deg` off: its normals all turned by that much.
std::vector<Eigen::Vector2d> ScanTurnedBy(double turn_deg) {
  std::vector<Eigen::Vector2d> n;
  for (int i = 0; i < 120; ++i) n.push_back(Normal((i % 3 ? 12 : 102) + turn_deg + 0.3 * std::cos(i * 2.3)));
  for (int i = 0; i < 20; ++i) n.push_back(Eigen::Vector2d::Zero());  // corners, clutter: no normal
  return n;
}

TEST(WallOrientations, AlignsAScanTurnedAwayFromTheMapsWalls) {
  const WallOrientations walls = Building();
  EXPECT_DOUBLE_EQ(walls.total(), 800);
  for (const double turn : {-6.3, -2.0, 0.0, 0.7, 4.4}) {
    const auto a = walls.Align(ScanTurnedBy(turn), 10 * kDeg);
    ASSERT_TRUE(a.has_value()) << turn;
    EXPECT_NEAR(a->offset_rad / kDeg, -turn, 0.15) << turn;
    EXPECT_GT(a->contrast, 2.0) << "a clear alignment in a window of +-10 deg";
    EXPECT_GT(a->score, 0.8) << "the scan's walls lie on the map's";
    EXPECT_LT(a->ambiguity, 0.5) << "no other way to align within +-10 deg";
  }
}

// A scan's directions in its own frame, turned by its heading, align as its normals turned into the
// map frame do (LaserSlam computes a scan's directions once and aligns them at two headings); and
// a direction added by its angle counts as the same normal added (turned by a whole turn, or the
// other way round: a wall has two sides).
TEST(WallOrientations, DirectionsTurnedByTheHeadingAlignAsTheTurnedNormals) {
  const WallOrientations walls = Building();
  const std::vector<Eigen::Vector2d> map_frame = ScanTurnedBy(3.1);
  for (const double heading : {-170.0, -33.0, 0.0, 47.5, 179.0}) {
    std::vector<double> robot_frame;
    for (const Eigen::Vector2d& n : map_frame) {
      const double a = -heading * kDeg;  // the normal in the robot's frame
      robot_frame.push_back(WallOrientations::Direction({std::cos(a) * n.x() - std::sin(a) * n.y(),
                                                          std::sin(a) * n.x() + std::cos(a) * n.y()}));
    }
    const auto a = walls.Align(map_frame, 10 * kDeg);
    const auto b = walls.Align(robot_frame, heading * kDeg, 10 * kDeg);
    ASSERT_TRUE(a.has_value() && b.has_value()) << heading;
    EXPECT_NEAR(b->offset_rad, a->offset_rad, 1e-6) << heading;
    EXPECT_NEAR(b->contrast, a->contrast, 1e-6) << heading;
  }
  EXPECT_TRUE(std::isnan(WallOrientations::Direction(Eigen::Vector2d::Zero())));
  WallOrientations by_angle, by_normal;
  by_angle.AddDirection(12 * kDeg + 2 * M_PI);
  by_angle.AddDirection(102 * kDeg - M_PI);
  by_normal.Add(Normal(12));
  by_normal.Add(-Normal(102));
  const auto x = by_angle.Align(ScanTurnedBy(2), 10 * kDeg), y = by_normal.Align(ScanTurnedBy(2), 10 * kDeg);
  ASSERT_TRUE(x.has_value() && y.has_value());
  EXPECT_NEAR(x->offset_rad, y->offset_rad, 1e-9);
  EXPECT_NEAR(x->offset_rad / kDeg, -2, 0.15);
}

TEST(WallOrientations, NoAnswerWithoutWallsOrOutsideTheWindow) {
  WallOrientations empty;
  EXPECT_FALSE(empty.Align(ScanTurnedBy(0), 10 * kDeg).has_value()) << "a map without walls";
  const WallOrientations walls = Building();
  EXPECT_FALSE(walls.Align(std::vector<Eigen::Vector2d>(5, Eigen::Vector2d::Zero()), 10 * kDeg).has_value())
      << "a scan without walls";
  // Turned by 25 deg: within +-10 deg the best lies at the window's edge, no maximum inside.
  EXPECT_FALSE(walls.Align(ScanTurnedBy(25), 10 * kDeg).has_value());
  // Turned by 45 deg, halfway between the building's directions: both ways are alike.
  const auto half = walls.Align(ScanTurnedBy(45), 50 * kDeg);
  ASSERT_TRUE(half.has_value());
  EXPECT_GT(half->ambiguity, 0.8);
  // Cleared: nothing to align with.
  WallOrientations cleared = Building();
  cleared.Clear();
  EXPECT_EQ(cleared.total(), 0);
  EXPECT_FALSE(cleared.Align(ScanTurnedBy(0), 10 * kDeg).has_value());
  EXPECT_THROW(WallOrientations(0), std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::nav
