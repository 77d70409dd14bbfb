// Occupancy grids from scans at known poses (libnav occupancy_grid, MRPT's COccupancyGridMap2D)
// and the map files (tools/map): walls occupied, the room free, the outside unknown; a beam's hit
// where the laser's geometry puts it; the files read back.
#include <gtest/gtest.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>

#include "../support/grid_scans.hpp"
#include "map_export.hpp"
#include "snapnav/nav/slam/occupancy_grid.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/sim/textures.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav {
namespace sim = nav::sim;
namespace {

using nav::GridScan;
using nav::Pose2;

sim::Scene Room() {  // 6 x 5 m, a 1 x 1 m box in it
  sim::Scene scene;
  scene.name = "room";
  scene.textures.push_back(sim::MakeTexture("plain", cv::Mat(4, 4, CV_8UC3, cv::Scalar(200, 200, 200)), 1, 1));
  scene.walls = {{{0, 0}, {6, 0}, 2.5, 0, 0, 0},     {{6, 0}, {6, 5}, 2.5, 0, 0, 0},
                 {{6, 5}, {0, 5}, 2.5, 0, 0, 0},     {{0, 5}, {0, 0}, 2.5, 0, 0, 0},
                 {{2.5, 2.0}, {3.5, 2.0}, 1.0, 0, 0, 0}, {{3.5, 2.0}, {3.5, 3.0}, 1.0, 0, 0, 0},
                 {{3.5, 3.0}, {2.5, 3.0}, 1.0, 0, 0, 0}, {{2.5, 3.0}, {2.5, 2.0}, 1.0, 0, 0, 0}};
  return scene;
}

std::vector<GridScan> RoomScans() {
  const sim::Scene scene = Room();
  sim::LaserOptions laser;
  sim::World world(scene, {}, laser, 3);
  std::vector<GridScan> scans;
  for (const Pose2& pose : {Pose2{1.0, 1.0, 0.3}, Pose2{5.0, 1.0, 2.0}, Pose2{5.0, 4.0, -2.5}, Pose2{1.0, 4.0, -0.8}}) {
    scans.push_back(test_support::SimGridScan(world, laser, pose));
  }
  return scans;
}

int8_t At(const nav::OccupancyCells& c, double x, double y) {
  const int cx = static_cast<int>(std::floor((x - c.origin_x_m) / c.resolution_m));
  const int cy = static_cast<int>(std::floor((y - c.origin_y_m) / c.resolution_m));
  if (cx < 0 || cy < 0 || cx >= c.width || cy >= c.height) return -1;
  return c.cells[static_cast<size_t>(cy) * static_cast<size_t>(c.width) + static_cast<size_t>(cx)];
}
// The highest occupancy within one cell of (x, y) (a wall's cell is on either side of its line).
int8_t Near(const nav::OccupancyCells& c, double x, double y) {
  int8_t best = -1;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy) best = std::max(best, At(c, x + dx * c.resolution_m, y + dy * c.resolution_m));
  return best;
}

TEST(OccupancyGrid, WallsOccupiedRoomFreeOutsideUnknown) {
  nav::OccupancyGridOptions options;
  const auto grid = nav::BuildOccupancyGrid(RoomScans(), options);
  const nav::OccupancyCells c = nav::ToOccupancyCells(grid, options);
  EXPECT_NEAR(c.resolution_m, 0.05, 1e-6);
  EXPECT_LE(c.origin_x_m, 0.0);
  EXPECT_LE(c.origin_y_m, 0.0);
  EXPECT_GE(c.origin_x_m + c.width * c.resolution_m, 6.0);
  EXPECT_GE(c.origin_y_m + c.height * c.resolution_m, 5.0);
  int wall = 0, wall_occupied = 0;
  for (double t = 0.3; t <= 4.7; t += 0.1) {
    for (const auto& [x, y] : {std::pair{0.0, t}, std::pair{6.0, t}, std::pair{t * 1.2, 0.0}, std::pair{t * 1.2, 5.0}}) {
      ++wall;
      wall_occupied += Near(c, x, y) >= 65;
    }
  }
  EXPECT_GE(wall_occupied, 0.9 * wall) << wall_occupied << " of " << wall << " wall samples occupied";
  EXPECT_GE(Near(c, 2.5, 2.5), 65) << "the box's side";
  EXPECT_GE(Near(c, 3.0, 2.0), 65);
  for (const auto& [x, y] : {std::pair{1.5, 1.5}, std::pair{4.5, 2.5}, std::pair{3.0, 4.2}, std::pair{1.0, 2.5}}) {
    const int8_t v = At(c, x, y);
    EXPECT_GE(v, 0) << x << "," << y << " was seen";
    EXPECT_LE(v, 20) << x << "," << y << " is free";
  }
  EXPECT_EQ(At(c, 3.0, 2.5), -1) << "inside the box: never seen";
  EXPECT_EQ(At(c, -2.0, 2.0), -1) << "outside the room";
  EXPECT_GT(c.occupied, 300);
  EXPECT_GT(c.free, 5000);
  EXPECT_GT(c.unknown, 0);
}

// A laser mounted turned and off-centre, its beams not symmetric about its axis: each hit lands
// where robot pose * mount * (range, bearing) puts it (free space is the room test's: MRPT fills
// the fan between neighbouring beams, which 5 sparse beams hardly have).
TEST(OccupancyGrid, HitsWhereTheLasersGeometrySaysAsymmetricBeamsAndATurnedMount) {
  GridScan s;
  s.robot_pose = {1.0, 2.0, 0.5};
  s.sensor_on_robot = {0.2, -0.1, 0.4};
  s.angle_min_rad = 0.3f;
  s.angle_increment_rad = 0.25f;
  s.range_min_m = 0.05f;
  s.range_max_m = 10.0f;
  s.ranges_m = {2.0f, 2.5f, 3.0f, 10.0f, 1.5f};  // the 4th: no return
  nav::OccupancyGridOptions options;
  const auto c = nav::ToOccupancyCells(nav::BuildOccupancyGrid({s}, options), options);
  const Pose2 sensor = s.robot_pose.Compose(s.sensor_on_robot);
  for (size_t i = 0; i < s.ranges_m.size(); ++i) {
    const double a = s.angle_min_rad + s.angle_increment_rad * static_cast<double>(i), r = s.ranges_m[i];
    const Eigen::Vector2d hit = sensor.Transform(Eigen::Vector2d(r * std::cos(a), r * std::sin(a)));
    const Eigen::Vector2d half = sensor.Transform(Eigen::Vector2d(0.5 * r * std::cos(a), 0.5 * r * std::sin(a)));
    if (i == 3) {
      EXPECT_LT(Near(c, hit.x(), hit.y()), 65) << "no return: no hit";
    } else {
      EXPECT_GE(Near(c, hit.x(), hit.y()), 65) << "beam " << i;
      EXPECT_LT(At(c, half.x(), half.y()), 50) << "beam " << i << ": no hit half-way";
    }
  }
  // MRPT's symmetric beams (its documented spacing, aperture / (N - 1)): the first at -aperture / 2
  // about the turned sensor, each at its bearing.
  const auto obs = nav::ToMrptScan(s);
  EXPECT_NEAR(obs.aperture, 1.0, 1e-6);
  EXPECT_NEAR(obs.sensorPose.yaw(), 0.4 + 0.3 + 0.5, 1e-6);
  for (size_t i = 0; i < s.ranges_m.size(); ++i) {
    EXPECT_NEAR(obs.sensorPose.yaw() + obs.getScanAngle(i), 0.4 + s.angle_min_rad + s.angle_increment_rad * i, 1e-6);
  }
  EXPECT_FALSE(obs.getScanRangeValidity(3));
}

// A scan with one return among 361 (open space, a SICK's 81.9 m no-return readings): MRPT 2.5
// crashed inserting such scans with no-return beams as free space; they clear nothing now.
TEST(OccupancyGrid, ScanWithFewReturnsIsInserted) {
  GridScan s;
  s.angle_min_rad = static_cast<float>(-M_PI / 2);
  s.angle_increment_rad = static_cast<float>(M_PI / 360);
  s.range_min_m = 0.1f;
  s.range_max_m = 81.91f;
  s.ranges_m.assign(361, 81.91f);
  s.ranges_m[180] = 4.0f;
  nav::OccupancyGridOptions options;
  const auto c = nav::ToOccupancyCells(nav::BuildOccupancyGrid({s, s}, options), options);
  EXPECT_GE(Near(c, 4.0, 0.0), 65);
  EXPECT_EQ(c.occupied, 1);
}

// The cells and counts of MRPT's grid, as each cell's probability of being free says (getCell): every
// log-odds value the grid can hold, at cells scattered over a grid that is not square.
TEST(OccupancyGrid, CellsAndCountsAreWhatEachCellsProbabilitySays) {
  using Grid = mrpt::maps::COccupancyGridMap2D;
  struct Writable : Grid {  // MRPT keeps its raw cell setter protected
    using Grid::Grid;
    using Grid::setRawCell;
  };
  Writable grid(-3.0f, 4.0f, -1.0f, 1.5f, 0.05f);
  const int w = static_cast<int>(grid.getSizeX()), h = static_cast<int>(grid.getSizeY());
  const int lo = std::numeric_limits<Grid::cellType>::min(), hi = std::numeric_limits<Grid::cellType>::max();
  for (int i = 0, l = lo; i < w * h; ++i, l = l == hi ? lo : l + 1) {
    grid.setRawCell(static_cast<unsigned>((i * 7919) % (w * h)), static_cast<Grid::cellType>(i % 3 == 0 ? 0 : l));
  }
  nav::OccupancyGridOptions o;
  o.occupied_threshold = 0.6;
  o.free_threshold = 0.3;
  const nav::OccupancyCells c = nav::ToOccupancyCells(grid, o);
  ASSERT_EQ(c.width, w);
  ASSERT_EQ(c.height, h);
  int unknown = 0, occupied = 0, free = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float free_p = grid.getCell(x, y);
      const double occ = 1.0 - free_p;
      const int expected = free_p == 0.5f ? -1 : static_cast<int>(std::lround(100.0 * occ));
      ASSERT_EQ(c.at(x, y), expected) << "cell " << x << ", " << y;
      if (free_p == 0.5f) ++unknown;
      else if (occ >= o.occupied_threshold) ++occupied;
      else if (occ <= o.free_threshold) ++free;
    }
  }
  EXPECT_EQ(c.unknown, unknown);
  EXPECT_EQ(c.occupied, occupied);
  EXPECT_EQ(c.free, free);
  EXPECT_GT(unknown, 0);
  EXPECT_GT(occupied, 0);
  EXPECT_GT(free, 0);
  EXPECT_LT(unknown + occupied + free, w * h);  // some cells between the thresholds
}

TEST(OccupancyGrid, BadOptionsAndScansAreRefused) {
  nav::OccupancyGridOptions o;
  o.resolution_m = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = {};
  o.free_threshold = 0.7;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  GridScan one;
  one.ranges_m = {1.0f};
  one.range_max_m = 5;
  EXPECT_THROW(nav::BuildOccupancyGrid({one}, {}), std::invalid_argument);
}

// The files: map.pgm + map.yaml as ROS's map_server reads them (trinary, row 0 the top), the
// .gridmap read back by MRPT equal to the grid, the .simplemap with every scan.
TEST(MapExport, RosAndMrptFilesReadBack) {
  const std::string dir = (std::filesystem::temp_directory_path() / "snapnav_map_export_test").string();
  std::filesystem::remove_all(dir);
  nav::OccupancyGridOptions options;
  const auto scans = RoomScans();
  const auto grid = nav::BuildOccupancyGrid(scans, options);
  const auto c = nav::ToOccupancyCells(grid, options);
  map::WriteRosMap(c, options, dir, "room");
  map::WriteGridmap(grid, dir + "/room.gridmap");
  map::WriteSimplemap(nav::BuildSimpleMap(scans), dir + "/room.simplemap");
  map::WriteMapPng(c, options, {scans[0].robot_pose, scans[1].robot_pose}, dir + "/room.png");

  std::ifstream pgm(dir + "/room.pgm", std::ios::binary);
  std::string magic, comment;
  int w = 0, h = 0, maxval = 0;
  pgm >> magic;
  pgm.get();
  std::getline(pgm, comment);
  pgm >> w >> h >> maxval;
  pgm.get();
  ASSERT_EQ(magic, "P5");
  EXPECT_EQ(comment[0], '#');
  ASSERT_EQ(w, c.width);
  ASSERT_EQ(h, c.height);
  EXPECT_EQ(maxval, 255);
  std::vector<unsigned char> pixels(static_cast<size_t>(w) * static_cast<size_t>(h));
  pgm.read(reinterpret_cast<char*>(pixels.data()), static_cast<std::streamsize>(pixels.size()));
  ASSERT_TRUE(pgm.good());
  const auto pixel = [&](double x, double y) {  // row 0 is the top
    const int cx = static_cast<int>(std::floor((x - c.origin_x_m) / c.resolution_m));
    const int cy = static_cast<int>(std::floor((y - c.origin_y_m) / c.resolution_m));
    return pixels[static_cast<size_t>(h - 1 - cy) * static_cast<size_t>(w) + static_cast<size_t>(cx)];
  };
  EXPECT_EQ(pixel(1.5, 1.5), 254);   // free
  EXPECT_EQ(pixel(3.0, 2.5), 205);   // unknown (inside the box)
  int dark = 0;
  for (double y = 0.5; y < 4.5; y += 0.1) dark += pixel(6.0 - 0.01, y) == 0 || pixel(6.0 + 0.01, y) == 0;
  EXPECT_GE(dark, 36) << "the east wall black";

  std::ifstream yaml(dir + "/room.yaml");
  std::stringstream ys;
  ys << yaml.rdbuf();
  const std::string y = ys.str();
  EXPECT_NE(y.find("image: room.pgm\n"), std::string::npos) << y;
  EXPECT_NE(y.find("resolution: 0.05\n"), std::string::npos) << y;
  std::ostringstream origin;
  origin << "origin: [" << std::setprecision(9) << c.origin_x_m << ", " << c.origin_y_m << ", 0.0]";
  EXPECT_NE(y.find(origin.str()), std::string::npos) << y;
  EXPECT_NE(y.find("occupied_thresh: 0.65\n"), std::string::npos) << y;
  EXPECT_NE(y.find("free_thresh: 0.196\n"), std::string::npos) << y;
  EXPECT_NE(y.find("negate: 0\n"), std::string::npos) << y;

  const auto back = map::ReadGridmap(dir + "/room.gridmap");
  ASSERT_EQ(back.getSizeX(), grid.getSizeX());
  ASSERT_EQ(back.getSizeY(), grid.getSizeY());
  EXPECT_FLOAT_EQ(back.getXMin(), grid.getXMin());
  for (unsigned yy = 0; yy < grid.getSizeY(); yy += 7)
    for (unsigned xx = 0; xx < grid.getSizeX(); xx += 7) ASSERT_FLOAT_EQ(back.getCell(xx, yy), grid.getCell(xx, yy));
  EXPECT_GT(std::filesystem::file_size(dir + "/room.simplemap"), 1000u);
  EXPECT_GT(std::filesystem::file_size(dir + "/room.png"), 1000u);

  // Not a grid: the file is named.
  std::ofstream(dir + "/bad.gridmap") << "not a gridmap";
  try {
    map::ReadGridmap(dir + "/bad.gridmap");
    ADD_FAILURE() << "a text file read as a grid";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.gridmap"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace snapnav
