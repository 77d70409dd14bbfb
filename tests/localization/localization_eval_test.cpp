// The localization evaluation's helpers: the grid area, off-grid test positions, the random
// exploration walk (5.1.4) and the manual route, error statistics. A 4 x 4 m empty room built
// inline; no rendering.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "localization_eval.hpp"

namespace snapnav::eval {
namespace {

nav::sim::Scene Room() {
  nav::sim::Scene s;
  s.name = "room";
  s.textures.push_back(nav::sim::MakeTexture("plain", cv::Mat(8, 8, CV_8UC3, cv::Scalar(120, 120, 120)), 1, 1));
  const Eigen::Vector2d c[4] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
  for (int i = 0; i < 4; ++i) {
    nav::sim::Wall w;
    w.a = c[i];
    w.b = c[(i + 1) % 4];
    s.walls.push_back(w);
  }
  s.grid.origin_x_m = 1.0;
  s.grid.origin_y_m = 1.0;
  s.grid.spacing_m = 0.2;
  s.grid.nx = 11;
  s.grid.ny = 11;
  s.start_pose = {2, 2, 0};
  return s;
}

TEST(LocalizationEvalTest, GridAreaSpansTheGrid) {
  const auto scene = Room();
  const Area a = GridArea(scene.grid);
  EXPECT_NEAR(a.min.x(), 1.0, 1e-12);
  EXPECT_NEAR(a.max.y(), 3.0, 1e-12);
  EXPECT_NEAR(a.area_m2(), 4.0, 1e-9);
  EXPECT_TRUE(a.Contains({3.05, 2.0}, 0.1));
  EXPECT_FALSE(a.Contains({3.05, 2.0}));
  nav::sim::GridSpec one = scene.grid;
  one.nx = 1;
  EXPECT_THROW(GridArea(one), std::invalid_argument);
}

TEST(LocalizationEvalTest, TestPosesAreInsideOffTheGridAndSeeded) {
  const auto scene = Room();
  const Area a = GridArea(scene.grid);
  const auto poses = RandomTestPoses(a, scene.grid, 30, 0.03, 7);
  ASSERT_EQ(poses.size(), 30u);
  std::set<int> quadrants;
  for (const auto& p : poses) {
    EXPECT_TRUE(a.Contains({p.x_m, p.y_m}));
    EXPECT_GE(p.theta_rad, -M_PI);
    EXPECT_LT(p.theta_rad, M_PI);
    double nearest = 1e9;
    for (int iy = 0; iy < scene.grid.ny; ++iy) {
      for (int ix = 0; ix < scene.grid.nx; ++ix) {
        nearest = std::min(nearest, (scene.grid.Position(ix, iy) - Eigen::Vector2d(p.x_m, p.y_m)).norm());
      }
    }
    EXPECT_GE(nearest, 0.03);
    quadrants.insert((p.x_m > 2) + 2 * (p.y_m > 2));
  }
  EXPECT_EQ(quadrants.size(), 4u);  // spread over the area
  const auto again = RandomTestPoses(a, scene.grid, 30, 0.03, 7);
  EXPECT_EQ(again[17].x_m, poses[17].x_m);
  EXPECT_NE(RandomTestPoses(a, scene.grid, 30, 0.03, 8)[0].x_m, poses[0].x_m);
  EXPECT_THROW(RandomTestPoses(a, scene.grid, 3, 0.15, 1), std::invalid_argument);  // >= spacing / 2
}

TEST(LocalizationEvalTest, RandomWalkStaysInTheAreaCoversItAndTendsForward) {
  const auto scene = Room();
  const Area a = GridArea(scene.grid);
  RandomWalkOptions o;
  o.runs = 4;
  o.steps = 150;
  const auto samples = RandomWalk(scene, a, {}, o, 3);
  ASSERT_EQ(samples.size(), 4u * 151u);
  std::set<std::pair<int, int>> visited;
  std::set<double> start_headings;
  int small_turns = 0, turns = 0;
  double worst_odometry = 0, odometry_sum = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto& s = samples[i];
    EXPECT_TRUE(a.Contains({s.truth.x_m, s.truth.y_m}, o.border_margin_m + o.step_m + 0.02)) << i;
    visited.insert({static_cast<int>((s.truth.x_m - a.min.x()) / 0.2), static_cast<int>((s.truth.y_m - a.min.y()) / 0.2)});
    if (i == 0 || samples[i - 1].run != s.run) {
      start_headings.insert(std::round(s.truth.theta_rad * 100));
      EXPECT_NEAR(s.truth.x_m, 2.0, 1e-9);
      EXPECT_NEAR(s.odometry.x_m, s.truth.x_m, 1e-9);  // each run starts at a known pose
    } else {
      const double step = std::hypot(s.truth.x_m - samples[i - 1].truth.x_m, s.truth.y_m - samples[i - 1].truth.y_m);
      EXPECT_NEAR(step, o.step_m, 0.01);
      ++turns;
      small_turns += std::abs(nav::WrapAngle(s.truth.theta_rad - samples[i - 1].truth.theta_rad)) < 0.6;
      EXPECT_GT(s.utime, samples[i - 1].utime);
    }
    const double odo = std::hypot(s.odometry.x_m - s.truth.x_m, s.odometry.y_m - s.truth.y_m);
    worst_odometry = std::max(worst_odometry, odo);
    odometry_sum += odo;
  }
  EXPECT_EQ(start_headings.size(), 4u);
  EXPECT_GE(visited.size(), 0.6 * 100);  // of the 10 x 10 bins of 20 cm
  EXPECT_GT(small_turns, 0.85 * turns);  // a forward tendency: drastic turns only at the border
  EXPECT_GT(odometry_sum, 0.0);          // odometry is noisy ...
  EXPECT_LT(worst_odometry, 0.25);       // ... but not wild over 7.5 m (0.07 m seen)
  // Seeded.
  const auto again = RandomWalk(scene, a, {}, o, 3);
  EXPECT_EQ(again.back().truth.x_m, samples.back().truth.x_m);
}

TEST(LocalizationEvalTest, ManualRouteIsASerpentineWithCellsEverySpacing) {
  const auto scene = Room();
  const Area a = GridArea(scene.grid);
  const auto w = ManualRouteWaypoints(a, 0.5);
  ASSERT_EQ(w.size(), 10u);  // 5 rows, 2 ends each
  EXPECT_NEAR(w[0].x(), 1.0, 1e-12);
  EXPECT_NEAR(w[1].x(), 3.0, 1e-12);
  EXPECT_NEAR(w[2].x(), 3.0, 1e-12);
  EXPECT_NEAR(w[3].x(), 1.0, 1e-12);
  EXPECT_NEAR(w.back().y(), 3.0, 1e-12);
  const auto samples = DriveRoute(scene, w, {}, 0.4, 5);
  // 5 rows of 2 m and 4 steps of 0.5 m: 12 m, a cell every 0.4 m.
  EXPECT_GE(samples.size(), 28u);
  EXPECT_LE(samples.size(), 34u);
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_TRUE(a.Contains({samples[i].truth.x_m, samples[i].truth.y_m}, 0.15)) << i;
    if (i > 0) {
      EXPECT_LE(std::hypot(samples[i].truth.x_m - samples[i - 1].truth.x_m, samples[i].truth.y_m - samples[i - 1].truth.y_m),
                0.45);
    }
  }
  EXPECT_NEAR(samples.back().truth.y_m, 3.0, 0.15);
  EXPECT_THROW(DriveRoute(scene, {w[0]}, {}, 0.4, 5), std::invalid_argument);
}

TEST(LocalizationEvalTest, SummarizeLeavesUnansweredHeadingsOut) {
  const auto s = Summarize({0.1, 0.3, 0.2, 0.4}, {0.1, std::nan(""), -0.2, 0.0});
  EXPECT_NEAR(s.mean_m, 0.25, 1e-12);
  EXPECT_NEAR(s.median_m, 0.25, 1e-12);
  EXPECT_NEAR(s.max_m, 0.4, 1e-12);
  EXPECT_NEAR(s.mean_heading_deg, 0.1 * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.max_heading_deg, 0.2 * 180 / M_PI, 1e-9);
  EXPECT_TRUE(std::isnan(Summarize({0.1}, {std::nan("")}).mean_heading_deg));
}

TEST(LocalizationEvalTest, MeasureVariants) {
  for (const auto& name : MeasureVariantNames()) ASSERT_TRUE(ParseMeasureVariant(name)) << name;
  EXPECT_EQ(ParseMeasureVariant("bearing-ransac")->refinement, nav::MatchRefinement::kRansac);
  EXPECT_EQ(ParseMeasureVariant("count")->measure, nav::PlaceMeasure::kMatchCount);
  EXPECT_EQ(ParseMeasureVariant("bearing")->name, "bearing-smallest");
  EXPECT_FALSE(ParseMeasureVariant("hog"));
  LocalizationEvalOptions o;
  o.measures = {"nope"};
  EXPECT_THROW(o.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::eval
