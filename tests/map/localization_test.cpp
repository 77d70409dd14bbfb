// Maps on the bus and localization in a saved map (issue 22): occupancy_grid_t round trip and the
// checks of a malformed one; the grid built scan by scan equals the batch; map files read back;
// the global search (branch and bound) finds a pose from nothing and knows when a room is
// symmetric; the localizer finds the pose, tracks it, notices a kidnapping and finds it again.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "../support/grid_scans.hpp"
#include "map_export.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/occupancy_grid_msg.hpp"
#include "snapnav/nav/slam/global_localizer.hpp"
#include "snapnav/nav/slam/map_localizer.hpp"
#include "snapnav/nav/slam/map_matcher.hpp"
#include "snapnav/nav/slam/occupancy_grid.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/sim/textures.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav {
namespace sim = nav::sim;
namespace {

using nav::GridScan;
using nav::Pose2;
constexpr double kDeg = M_PI / 180;

sim::Wall W(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y1}, 2.5, 0, 0, 0}; }

// An 8 x 6 m room that no turn or mirror maps onto itself: a wall sticking out of the south side,
// a box, a pillar and a niche.
sim::Scene AsymmetricRoom() {
  sim::Scene scene;
  scene.name = "asymmetric";
  scene.textures.push_back(sim::MakeTexture("plain", cv::Mat(4, 4, CV_8UC3, cv::Scalar(200, 200, 200)), 1, 1));
  scene.walls = {W(0, 0, 8, 0),     W(8, 0, 8, 4),     W(8, 4, 7, 4),     W(7, 4, 7, 6),     W(7, 6, 0, 6),
                 W(0, 6, 0, 0),     W(2.5, 0, 2.5, 1.8), W(5.2, 4.9, 6.2, 4.9), W(6.2, 4.9, 6.2, 5.5), W(6.2, 5.5, 5.2, 5.5),
                 W(5.2, 5.5, 5.2, 4.9), W(1.2, 4.4, 1.5, 4.4), W(1.5, 4.4, 1.5, 4.7), W(1.5, 4.7, 1.2, 4.7),
                 W(1.2, 4.7, 1.2, 4.4)};
  return scene;
}

sim::Scene SymmetricRoom() {  // 6 x 4 m, nothing in it: a half turn maps it onto itself
  sim::Scene scene;
  scene.name = "symmetric";
  scene.textures.push_back(sim::MakeTexture("plain", cv::Mat(4, 4, CV_8UC3, cv::Scalar(200, 200, 200)), 1, 1));
  scene.walls = {W(0, 0, 6, 0), W(6, 0, 6, 4), W(6, 4, 0, 4), W(0, 4, 0, 0)};
  return scene;
}

GridScan ScanAt(sim::World& world, const sim::LaserOptions& laser, const Pose2& pose) {
  return test_support::SimGridScan(world, laser, pose);
}

std::vector<Eigen::Vector2d> Points(const GridScan& g) {
  return nav::ScanToPoints(g.ranges_m, g.angle_min_rad, g.angle_increment_rad, g.range_min_m, g.range_max_m, g.sensor_on_robot);
}

// The map of a room from scans at a grid of poses (as map-export makes it from a run).
nav::OccupancyCells MapOf(const sim::Scene& scene, double x1, double y1) {
  sim::LaserOptions laser;
  sim::World world(scene, {}, laser, 5);
  std::vector<GridScan> scans;
  for (double x = 0.7; x < x1 - 0.5; x += 1.0)
    for (double y = 0.7; y < y1 - 0.5; y += 1.0)
      for (double th : {0.0, 2.1, 4.2}) scans.push_back(ScanAt(world, laser, {x, y, th}));
  const nav::OccupancyGridOptions options;
  return nav::ToOccupancyCells(nav::BuildOccupancyGrid(scans, options), options);
}

TEST(OccupancyGridMsg, RoundTripAndMalformedGridsNamed) {
  nav::OccupancyCells c;
  c.resolution_m = 0.05;
  c.origin_x_m = -1.5;
  c.origin_y_m = 2.25;
  c.width = 4;
  c.height = 3;
  c.cells = {-1, 0, 100, 55, 0, 0, 100, -1, 20, 0, 100, -1};
  const occupancy_grid_t m = glue::ToOccupancyGridMsg(c, 123, "map", "laser_slam");
  std::string error;
  const auto back = glue::Decode<occupancy_grid_t>(glue::Encode(m).data(), glue::Encode(m).size(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_FALSE(glue::CheckOccupancyGrid(*back));
  const nav::OccupancyCells d = glue::FromOccupancyGridMsg(*back);
  EXPECT_EQ(d.width, 4);
  EXPECT_EQ(d.height, 3);
  EXPECT_EQ(d.cells, c.cells);
  EXPECT_NEAR(d.resolution_m, 0.05, 1e-7);
  EXPECT_DOUBLE_EQ(d.origin_x_m, -1.5);
  EXPECT_DOUBLE_EQ(d.origin_y_m, 2.25);
  EXPECT_EQ(d.occupied, 3);
  EXPECT_EQ(d.unknown, 3);
  EXPECT_EQ(d.free, 4);  // the four 0s (20 is neither free nor occupied)
  EXPECT_EQ(back->source, "laser_slam");
  EXPECT_EQ(back->utime, 123);

  const auto reason = [](occupancy_grid_t g) {
    const auto p = glue::CheckOccupancyGrid(g);
    return p ? p->reason : std::string();
  };
  occupancy_grid_t bad = m;
  bad.ncells = 11;
  bad.cells.resize(11);
  EXPECT_EQ(reason(bad), "bad grid size");
  bad = m;
  bad.width = 0;
  EXPECT_EQ(reason(bad), "bad grid size");
  bad = m;
  bad.width = -4;
  bad.height = -3;
  EXPECT_EQ(reason(bad), "bad grid size");
  bad = m;
  bad.resolution_m = NAN;
  EXPECT_EQ(reason(bad), "bad resolution");
  bad = m;
  bad.resolution_m = 0;
  EXPECT_EQ(reason(bad), "bad resolution");
  bad = m;
  bad.origin_y_m = INFINITY;
  EXPECT_EQ(reason(bad), "bad origin");
  bad = m;
  bad.cells[5] = 101;
  EXPECT_EQ(reason(bad), "bad cell value");
  bad.cells[5] = -2;
  EXPECT_EQ(reason(bad), "bad cell value");
}

TEST(OccupancyGridBuilder, ScanByScanEqualsTheBatch) {
  sim::LaserOptions laser;
  const sim::Scene scene = AsymmetricRoom();  // the world keeps a reference
  sim::World world(scene, {}, laser, 5);
  std::vector<GridScan> scans;
  for (const Pose2& p : {Pose2{1, 1, 0.2}, Pose2{4, 2, 2.0}, Pose2{6.5, 1.5, 3.0}, Pose2{3, 5, -1}})
    scans.push_back(ScanAt(world, laser, p));
  const nav::OccupancyGridOptions options;
  const nav::OccupancyCells batch = nav::ToOccupancyCells(nav::BuildOccupancyGrid(scans, options), options);
  nav::OccupancyGridBuilder builder(options);
  for (const GridScan& s : scans) EXPECT_TRUE(builder.Insert(s));
  const nav::OccupancyCells live = builder.Cells();
  EXPECT_EQ(builder.inserted(), 4);
  // Same cells where both grids have them (the live grid grew in steps, its corner may differ).
  int compared = 0, differ = 0;
  for (int y = 0; y < batch.height; ++y) {
    for (int x = 0; x < batch.width; ++x) {
      const double wx = batch.origin_x_m + (x + 0.5) * batch.resolution_m, wy = batch.origin_y_m + (y + 0.5) * batch.resolution_m;
      const int lx = static_cast<int>(std::floor((wx - live.origin_x_m) / live.resolution_m));
      const int ly = static_cast<int>(std::floor((wy - live.origin_y_m) / live.resolution_m));
      if (lx < 0 || ly < 0 || lx >= live.width || ly >= live.height) continue;
      ++compared;
      differ += std::abs(batch.at(x, y) - live.at(lx, ly)) > 1;
    }
  }
  EXPECT_GT(compared, batch.width * batch.height / 2);
  EXPECT_LT(differ, compared / 1000 + 1) << differ << " of " << compared;
  EXPECT_NEAR(live.occupied, batch.occupied, batch.occupied / 100 + 1);
  // A bound on the grid: a scan that would grow it too far is skipped.
  nav::OccupancyGridOptions small = options;
  small.max_cells = 100 * 100;
  nav::OccupancyGridBuilder bounded(small);
  EXPECT_FALSE(bounded.Insert(scans[0]));
  EXPECT_EQ(bounded.too_large(), 1);
}

TEST(MapFile, RosMapAndGridmapReadBack) {
  const nav::OccupancyCells c = MapOf(AsymmetricRoom(), 8, 6);
  const std::string dir = (std::filesystem::temp_directory_path() / "snapnav_mapfile_test").string();
  std::filesystem::remove_all(dir);
  const nav::OccupancyGridOptions options;
  map::WriteRosMap(c, options, dir, "m");
  map::WriteGridmap(nav::FromOccupancyCells(c), dir + "/m.gridmap");
  const nav::OccupancyCells ros = map::ReadMapFile(dir + "/m.yaml", options);
  ASSERT_EQ(ros.width, c.width);
  ASSERT_EQ(ros.height, c.height);
  EXPECT_NEAR(ros.origin_x_m, c.origin_x_m, 1e-6);
  EXPECT_NEAR(ros.origin_y_m, c.origin_y_m, 1e-6);
  int mismatched = 0;
  for (int y = 0; y < c.height; ++y) {
    for (int x = 0; x < c.width; ++x) {
      const int8_t v = c.at(x, y);
      const int8_t trinary = v < 0 ? -1 : v >= 65 ? 100 : v <= 19 ? 0 : -1;
      mismatched += ros.at(x, y) != trinary;
    }
  }
  EXPECT_EQ(mismatched, 0);
  EXPECT_EQ(ros.occupied, c.occupied);
  const nav::OccupancyCells grid = map::ReadMapFile(dir + "/m.gridmap", options);
  EXPECT_EQ(grid.width, c.width);
  EXPECT_NEAR(grid.occupied, c.occupied, c.occupied / 50 + 1);
  EXPECT_THROW(map::ReadMapFile(dir + "/nothing.yaml", options), std::runtime_error);
  EXPECT_THROW(map::ReadMapFile(dir + "/m.pgm", options), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(MapFile, SimplemapReadAsTheGridOfItsScans) {
  // MRPT's keyframes (icp-slam's and map-export's .simplemap) as a saved map: the grid of its scans
  // at their poses, as map-export builds it from the same scans.
  sim::LaserOptions laser;
  const sim::Scene room = AsymmetricRoom();  // (the world keeps a reference to it)
  sim::World world(room, {}, laser, 5);
  std::vector<GridScan> scans;
  for (double x = 0.7; x < 7.5; x += 1.0)
    for (double y = 0.7; y < 5.5; y += 1.0)
      for (double th : {0.0, 2.1, 4.2}) scans.push_back(ScanAt(world, laser, {x, y, th}));
  const nav::OccupancyGridOptions options;
  const nav::OccupancyCells built = nav::ToOccupancyCells(nav::BuildOccupancyGrid(scans, options), options);
  const std::string dir = (std::filesystem::temp_directory_path() / "snapnav_simplemap_test").string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  map::WriteSimplemap(nav::BuildSimpleMap(scans, 0), dir + "/m.simplemap");
  const nav::OccupancyCells read = map::ReadMapFile(dir + "/m.simplemap", options);
  EXPECT_NEAR(read.resolution_m, 0.05, 1e-9);
  // The same walls: nearly every occupied cell of the built grid is occupied in the read one, or its
  // neighbour (MRPT grows the read grid on its own cell lattice, up to a cell apart).
  int found = 0;
  const auto occupied_near = [&](int rx, int ry) {
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = rx + dx, y = ry + dy;
        if (x >= 0 && y >= 0 && x < read.width && y < read.height && read.at(x, y) >= 65) return true;
      }
    return false;
  };
  for (int y = 0; y < built.height; ++y) {
    for (int x = 0; x < built.width; ++x) {
      if (built.at(x, y) < 65) continue;
      const double wx = built.origin_x_m + (x + 0.5) * built.resolution_m, wy = built.origin_y_m + (y + 0.5) * built.resolution_m;
      found += occupied_near(static_cast<int>(std::floor((wx - read.origin_x_m) / read.resolution_m)),
                             static_cast<int>(std::floor((wy - read.origin_y_m) / read.resolution_m)));
    }
  }
  EXPECT_GT(found, built.occupied * 95 / 100) << found << " of " << built.occupied;
  EXPECT_NEAR(read.occupied, built.occupied, built.occupied / 10 + 1);
  // A file that is not a simple map, and one without scans, are named.
  std::ofstream(dir + "/bad.simplemap") << "not a map";
  try {
    map::ReadMapFile(dir + "/bad.simplemap", options);
    ADD_FAILURE() << "a text file read as a simple map";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.simplemap"), std::string::npos) << e.what();
  }
  map::WriteSimplemap(mrpt::maps::CSimpleMap(), dir + "/empty.simplemap");
  EXPECT_THROW(map::ReadMapFile(dir + "/empty.simplemap", options), std::runtime_error);
  // MRPT's own pf-localization demo map (Debian's mrpt-common), where present.
  const std::string demo = "/usr/share/mrpt/datasets/localization_demo.simplemap.gz";
  if (std::filesystem::exists(demo)) {
    const nav::OccupancyCells m = map::ReadMapFile(demo, options);
    EXPECT_GT(m.occupied, 1000);
    EXPECT_GT(m.free, 50000);
  }
  std::filesystem::remove_all(dir);
}

TEST(GlobalLocalizer, FindsThePoseFromNothingAndPrunes) {
  const nav::OccupancyCells map = MapOf(AsymmetricRoom(), 8, 6);
  const nav::GlobalSearchOptions options;
  const nav::GlobalLocalizer global(map, options);
  sim::LaserOptions laser;
  const sim::Scene scene = AsymmetricRoom();
  sim::World world(scene, {}, laser, 9);
  for (const Pose2& truth : {Pose2{1.3, 1.1, 0.4}, Pose2{6.2, 2.3, 2.9}, Pose2{3.4, 4.6, -1.7}, Pose2{4.0, 2.5, 1.0}}) {
    const nav::GlobalSearchResult r = global.Search(Points(ScanAt(world, laser, truth)));
    ASSERT_TRUE(r.found);
    EXPECT_LT(std::hypot(r.best.x_m - truth.x_m, r.best.y_m - truth.y_m), 0.15) << truth.x_m << "," << truth.y_m;
    EXPECT_LT(std::abs(nav::WrapAngle(r.best.theta_rad - truth.theta_rad)), 2 * kDeg);
    EXPECT_GT(r.score, 0.6);
    EXPECT_LT(r.ambiguity, 0.95);  // one scan of straight walls: other poses may score 0.85 of it
    // Branch and bound: far fewer nodes than poses.
    const double poses = static_cast<double>(global.free_cells()) * 360;
    EXPECT_LT(static_cast<double>(r.nodes), 0.2 * poses) << r.nodes << " nodes for " << poses << " poses";
  }
}

TEST(GlobalLocalizer, SymmetricRoomIsAmbiguous) {
  const nav::OccupancyCells map = MapOf(SymmetricRoom(), 6, 4);
  const nav::GlobalLocalizer global(map, {});
  sim::LaserOptions laser;
  const sim::Scene scene = SymmetricRoom();
  sim::World world(scene, {}, laser, 9);
  const nav::GlobalSearchResult r = global.Search(Points(ScanAt(world, laser, {1.5, 1.2, 0.3})));
  ASSERT_TRUE(r.found);
  ASSERT_TRUE(r.has_second);
  EXPECT_GT(r.ambiguity, 0.9);  // the half turn about the centre scores as well
  const Pose2 mirror{6 - 1.5, 4 - 1.2, 0.3 + M_PI};
  const auto near = [](const Pose2& a, const Pose2& b) {
    return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m) < 0.2 && std::abs(nav::WrapAngle(a.theta_rad - b.theta_rad)) < 3 * kDeg;
  };
  const Pose2 truth{1.5, 1.2, 0.3};
  EXPECT_TRUE((near(r.best, truth) && near(r.second, mirror)) || (near(r.best, mirror) && near(r.second, truth)));
}

TEST(MapLocalizer, FindsTracksNoticesAKidnappingAndFindsItAgain) {
  const nav::OccupancyCells map = MapOf(AsymmetricRoom(), 8, 6);
  nav::MapLocalizerOptions options;
  nav::MapLocalizer loc(map, options);
  sim::LaserOptions laser;
  const sim::Scene scene = AsymmetricRoom();
  sim::World world(scene, {}, laser, 11);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1);
  // A loop around the room's middle at about 0.03 m per scan, odometry with 2 % errors.
  std::vector<Pose2> path;
  for (int i = 0; i < 300; ++i) {
    const double a = i * 0.02;
    path.push_back({4.2 + 2.0 * std::cos(a), 3.0 + 1.0 * std::sin(a), a + M_PI / 2});
  }
  int64_t utime = 1'000'000;
  int first_localized = -1, kidnap_at = 150, relocalized = -1;
  bool lost_after_kidnap = false;
  for (int i = 0; i < static_cast<int>(path.size()); ++i) {
    Pose2 truth = path[static_cast<size_t>(i)];
    // Kidnapped: carried elsewhere in the room and turned a quarter turn (x' = 7 - y, y' = x - 1.2);
    // it drives on as before, so odometry still tells its motion. (Not a half turn about the middle:
    // the room's outer walls look the same then, the scans keep fitting and no fit collapses.)
    if (i >= kidnap_at) truth = Pose2{7, -1.2, M_PI / 2}.Compose(truth);
    if (i > 0) {
      Pose2 d = path[static_cast<size_t>(i - 1)].Between(path[static_cast<size_t>(i)]);
      d.x_m *= 1 + 0.02 * noise(rng);
      d.theta_rad += 0.01 * noise(rng);
      utime += 100'000;
      loc.Predict(d, utime);
    }
    const nav::LocalizationUpdate u = loc.Update(Points(ScanAt(world, laser, truth)), utime);
    const bool right = u.state == nav::LocalizationState::kLocalized &&
                       std::hypot(loc.pose().x_m - truth.x_m, loc.pose().y_m - truth.y_m) < 0.1 &&
                       std::abs(nav::WrapAngle(loc.pose().theta_rad - truth.theta_rad)) < 2 * kDeg;
    if (u.relocalized || u.lost_now || (u.searched && i % 10 == 0) || (i >= kidnap_at && i < kidnap_at + 8)) {
      std::cout << "scan " << i << (u.lost_now ? " lost" : "") << (u.relocalized ? " relocalized" : "")
                << (u.searched ? " searched" : "") << ": pose (" << loc.pose().x_m << ", " << loc.pose().y_m << ", "
                << loc.pose().theta_rad << "), truth (" << truth.x_m << ", " << truth.y_m << ", " << truth.theta_rad
                << "), global score " << u.global.score << " ambiguity " << u.global.ambiguity << " best ("
                << u.global.best.x_m << ", " << u.global.best.y_m << ", " << u.global.best.theta_rad << "), refined fit "
                << u.refined_fit << ", window " << u.window_scans << ", tracking fit " << u.fit << " ("
                << nav::MatchOutcomeName(u.tracking.outcome) << "), bad scans " << u.bad_scans << "\n";
    }
    if (first_localized < 0 && right) first_localized = i;
    // Lost after the kidnapping (the search may find the pose on the very scan that declared it).
    if (i >= kidnap_at && u.lost_now) lost_after_kidnap = true;
    if (i >= kidnap_at && relocalized < 0 && lost_after_kidnap && right) relocalized = i;
    if (first_localized >= 0 && i > first_localized && i < kidnap_at) {
      EXPECT_EQ(u.state, nav::LocalizationState::kLocalized) << "scan " << i;
      EXPECT_TRUE(right) << "scan " << i << ": " << loc.pose().x_m << ", " << loc.pose().y_m;
    }
    if (relocalized >= 0 && i > relocalized) {
      EXPECT_TRUE(right) << "scan " << i;
    }
  }
  EXPECT_GE(first_localized, 0);
  EXPECT_LE(first_localized, 3);  // an asymmetric room: the first scans suffice
  EXPECT_TRUE(lost_after_kidnap);
  ASSERT_GE(relocalized, 0);
  EXPECT_LE(relocalized - kidnap_at, options.lost_after_scans + 5);
  EXPECT_GE(loc.losses(), 1);
  EXPECT_GE(loc.relocalizations(), 2);
}

// Evidence over searches (accumulate_evidence) decides where each search is nearly, not quite, sure;
// a room symmetric about its middle is alike in every detail: however long the robot drives, its
// searches (ambiguity above 0.9) give no evidence and no pose is taken, the mirror's least of all.
TEST(MapLocalizer, EvidenceOverSearchesDoesNotDecideASymmetricRoom) {
  const nav::OccupancyCells map = MapOf(SymmetricRoom(), 6, 4);
  nav::MapLocalizerOptions options;
  ASSERT_TRUE(options.accumulate_evidence);
  nav::MapLocalizer loc(map, options);
  sim::LaserOptions laser;
  const sim::Scene scene = SymmetricRoom();
  sim::World world(scene, {}, laser, 5);
  int64_t utime = 1'000'000;
  Pose2 truth{1.5, 1.2, 0.3}, last = truth;
  int searches = 0;
  for (int i = 0; i < 120; ++i) {
    // Back and forth along a short line (the room's symmetry holds for every pose).
    truth = Pose2{1.5 + 0.4 * std::sin(i * 0.05), 1.2, 0.3};
    if (i > 0) {
      utime += 100'000;
      loc.Predict(last.Between(truth), utime);
    }
    last = truth;
    const nav::LocalizationUpdate u = loc.Update(Points(ScanAt(world, laser, truth)), utime);
    searches += u.searched;
    EXPECT_FALSE(u.relocalized) << "scan " << i << ": a pose taken in a symmetric room (ambiguity " << u.global.ambiguity
                                << ", evidence " << u.evidence << ")";
  }
  EXPECT_GE(searches, 100);
  EXPECT_EQ(loc.state(), nav::LocalizationState::kLost);
}

}  // namespace
}  // namespace snapnav
