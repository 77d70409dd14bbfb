#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace snapnav::nav {
namespace {

cv::Mat RollColumns(const cv::Mat& img, int k) {
  k = ((k % img.cols) + img.cols) % img.cols;
  if (k == 0) return img.clone();
  cv::Mat out;
  cv::hconcat(img.colRange(img.cols - k, img.cols), img.colRange(0, img.cols - k), out);
  return out;
}

cv::Mat RandomPanorama(int seed) {
  cv::Mat pano(120, 720, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(pano, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(pano, pano, {7, 7}, 2.0);
  return pano;
}

TEST(VisualCompass, RecoversAKnownColumnShift) {
  HogOptions o;
  o.cell_size_px = 40;
  const cv::Mat home = RandomPanorama(3);
  const ColumnHistograms h(home, o);
  for (const int k : {0, 1, 17, 90, 359, -45}) {
    const ColumnHistograms c(RollColumns(home, k), o);
    const CompassResult r = VisualCompass(h, c, o.cell_size_px);
    EXPECT_NEAR(r.shift_px, k, 0.5) << "shift " << k;
    EXPECT_NEAR(r.rotation_rad, WrapAngle(k * 2 * M_PI / 720), 0.01);
    EXPECT_EQ(r.distance_by_shift.size(), 720u);
  }
}

TEST(HogAlv, SymmetricSceneHasZeroAlv) {
  // The same quarter repeated four times around: every bin's ALV cancels.
  const cv::Mat quarter = RandomPanorama(5).colRange(0, 180).clone();
  cv::Mat pano;
  cv::hconcat(std::vector<cv::Mat>{quarter, quarter, quarter, quarter}, pano);
  HogOptions o;
  o.cell_size_px = 20;
  const ColumnHistograms h(pano, o);
  PanoramaModel p;
  const auto alvs = BinAlvs(CellsAtShift(h, o.cell_size_px, 0), o.cell_size_px, p);
  double total = 0;
  for (const auto& v : alvs) total += v.norm();
  const auto cells = CellsAtShift(h, o.cell_size_px, 0);
  double mass = 0;
  for (double v : cells.values) mass += v;
  EXPECT_LT(total, 1e-9 * mass);
}

// A 5 x 4 m room with blurred random textures on the walls and plain floor and ceiling.
sim::Scene TexturedRoom() {
  sim::Scene scene;
  scene.name = "room";
  cv::RNG rng(11);
  for (int i = 0; i < 4; ++i) {
    cv::Mat tex(128, 128, CV_8UC3);
    rng.fill(tex, cv::RNG::UNIFORM, 0, 255);
    cv::GaussianBlur(tex, tex, {9, 9}, 3.0);
    scene.textures.push_back(sim::MakeTexture("t" + std::to_string(i), tex, 1.5, 1.5));
  }
  scene.walls = {{{-2.5, -2}, {2.5, -2}, 2.6, 0, 0, 0}, {{2.5, -2}, {2.5, 2}, 2.6, 0, 1, 0},
                 {{2.5, 2}, {-2.5, 2}, 2.6, 0, 2, 0}, {{-2.5, 2}, {-2.5, -2}, 2.6, 0, 3, 0}};
  return scene;
}

sim::OmniCameraOptions Camera() {
  sim::OmniCameraOptions cam;
  cam.panorama.width_px = 720;
  cam.panorama.height_px = 120;
  cam.panorama.elevation_top_rad = 20 * M_PI / 180;
  cam.panorama.elevation_bottom_rad = -20 * M_PI / 180;
  return cam;
}

// Homing from displaced positions at arbitrary headings points home once the compass has
// aligned the views (landmark vectors from the robot to the landmarks: current - home).
TEST(HogHoming, DisplacedRobotPointsHome) {
  const sim::Scene scene = TexturedRoom();
  const sim::OmniCameraOptions cam = Camera();
  sim::OmniRenderer r(scene, cam);
  HogOptions hog;
  hog.cell_size_px = 40;
  hog.band_top_px = 20;
  hog.band_height_px = 80;
  cv::Mat home_img, img;
  r.RenderPanorama({0, 0, 0}, {}, &home_img);
  const ColumnHistograms home(home_img, hog);
  int good = 0, total = 0;
  for (const Eigen::Vector2d& offset : {Eigen::Vector2d(0.6, 0), Eigen::Vector2d(-0.6, 0), Eigen::Vector2d(0, 0.6),
                                       Eigen::Vector2d(0, -0.6), Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(-0.5, 0.4)}) {
    const double heading = 0.7 * total - 1.0;  // arbitrary headings: the compass must align them
    r.RenderPanorama({offset.x(), offset.y(), heading}, {}, &img);
    const ColumnHistograms cur(img, hog);
    HogAlvOptions alv;
    alv.difference = AlvDifference::kCurrentMinusHome;
    const auto e = HogHoming(home, cur, hog, alv, cam.panorama);
    ASSERT_TRUE(e.has_value());
    EXPECT_NEAR(e->compass_rotation_rad, heading, 0.2);  // parallax of a 0.6 m displacement in a 5 m room
    // True direction home in the robot frame.
    const double truth = WrapAngle(std::atan2(-offset.y(), -offset.x()) - heading);
    const double error = std::abs(WrapAngle(e->direction_rad - truth));
    if (error < M_PI / 4) ++good;
    ++total;
  }
  EXPECT_GE(good, total - 1) << good << "/" << total << " within 45 degrees";
}

// Pure rotations at one spot: the compass recovers the heading with sub-column precision
// (the bound: median error at most 2 degrees).
TEST(VisualCompass, PureRotationsOfARenderedViewWithinTwoDegrees) {
  const sim::Scene scene = TexturedRoom();
  const sim::OmniCameraOptions cam = Camera();
  sim::OmniRenderer r(scene, cam);
  HogHomingConfig config;
  config.hog.cell_size_px = 20;
  config.hog.band_top_px = 10;
  config.hog.band_height_px = 60;
  config.compass_hog.cell_size_px = 40;
  HogHomer homer(config, cam.panorama);
  cv::Mat img;
  r.RenderPanorama({0.3, -0.2, 0}, {}, &img);
  homer.SetHome(img);
  std::vector<double> errors;
  for (int k = 0; k < 24; ++k) {
    const double heading = WrapAngle(0.2718 + k * 2 * M_PI / 24 + 0.013 * k);  // not on whole columns
    r.RenderPanorama({0.3, -0.2, heading}, {}, &img);
    const auto e = homer.Home(img);
    ASSERT_TRUE(e.has_value());
    errors.push_back(std::abs(WrapAngle(e->compass_rotation_rad - heading)) * 180 / M_PI);
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LE(errors[errors.size() / 2], 2.0);
  EXPECT_LE(errors.back(), 5.0);
}

TEST(HogHomer, KnownRotationSkipsTheCompassAndBadUseIsAnError) {
  const sim::Scene scene = TexturedRoom();
  const sim::OmniCameraOptions cam = Camera();
  sim::OmniRenderer r(scene, cam);
  HogHomingConfig config;
  config.hog.band_top_px = 20;
  config.hog.band_height_px = 80;
  config.alv.weight = CellWeight::kLog;
  HogHomer homer(config, cam.panorama);
  cv::Mat home_img, img;
  r.RenderPanorama({0, 0, 0}, {}, &home_img);
  EXPECT_THROW(homer.Home(home_img), std::logic_error);  // no home yet
  homer.SetHome(home_img);
  r.RenderPanorama({0.7, 0.0, 1.0}, {}, &img);
  const auto e = homer.Home(img, 1.0);
  ASSERT_TRUE(e.has_value());
  EXPECT_DOUBLE_EQ(e->compass_rotation_rad, 1.0);
  EXPECT_LT(std::abs(WrapAngle(e->direction_rad - WrapAngle(M_PI - 1.0))), M_PI / 4);
  EXPECT_THROW(homer.Home(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(homer.Home(cv::Mat(60, 720, CV_8UC3, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(homer.SetHome(cv::Mat(120, 700, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
}

TEST(CellEntropy, UniformHistogramHasLog2BinsAndASingleBinHasNone) {
  HogCells c;
  c.cell_rows = 1;
  c.cell_cols = 2;
  c.bins = 8;
  c.values.assign(16, 0.0);
  for (int q = 0; q < 8; ++q) c.values[q] = 3.0;  // cell 0: uniform
  EXPECT_NEAR(CellEntropyBits(c), 3.0, 1e-12);
  c.values[8 + 5] = 24.0;                        // cell 1: one bin, same energy
  EXPECT_NEAR(CellEntropyBits(c), 1.5, 1e-12);
}

// Warping compensation (3.1.6): in a room with a plain floor the bottom edge of the walls
// gives their distance; the compensated panorama shows heights, so a wall's top edge
// lands on the same row whatever its distance.
TEST(WarpCompensation, EstimatesWallDistanceAndMapsHeightsToRows) {
  sim::Scene scene;
  scene.name = "plain room";
  cv::Mat white(8, 8, CV_8UC3, cv::Scalar(230, 230, 230));
  scene.textures.push_back(sim::MakeTexture("wall", white, 1.0, 1.0));
  scene.floor_bgr = {60, 60, 60};
  scene.ceiling_height_m = 0;  // open sky
  scene.sky_bgr = {20, 20, 20};
  // Walls 1.2 m high: the dark sky above them gives a top edge at height 1.2 m.
  scene.walls = {{{-3, -2}, {3, -2}, 1.2, 0, 0, 0}, {{3, -2}, {3, 2}, 1.2, 0, 0, 0},
                 {{3, 2}, {-3, 2}, 1.2, 0, 0, 0}, {{-3, 2}, {-3, -2}, 1.2, 0, 0, 0}};
  sim::OmniCameraOptions cam = Camera();
  cam.panorama.elevation_top_rad = 35 * M_PI / 180;
  cam.panorama.elevation_bottom_rad = -35 * M_PI / 180;
  sim::OmniRenderer r(scene, cam);
  cv::Mat img, gray;
  r.RenderPanorama({0, 0, 0}, {}, &img);
  cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
  WarpCompensationOptions o;
  o.camera_height_m = cam.height_m;
  o.height_bottom_m = 0.0;
  o.height_top_m = 2.0;
  std::vector<double> distance;
  const cv::Mat out = CompensateWarping(gray, cam.panorama, o, &distance);
  ASSERT_EQ(out.size(), gray.size());
  ASSERT_EQ(distance.size(), 720u);
  // Forward (bearing 0, column 360) the wall is 3 m away, to the left (bearing 90 deg) 2 m.
  const int forward = static_cast<int>(cam.panorama.ColumnOfBearing(0.0));
  const int left = static_cast<int>(cam.panorama.ColumnOfBearing(M_PI / 2));
  EXPECT_NEAR(distance[forward], 3.0, 0.3);
  EXPECT_NEAR(distance[left], 2.0, 0.2);
  // The wall top (1.2 m) is at row (2.0 - 1.2) / 2.0 * (rows - 1) in both directions.
  const double expected = (2.0 - 1.2) / 2.0 * (out.rows - 1);
  for (const int col : {forward, left}) {
    int edge = -1;
    for (int y = 1; y < out.rows; ++y) {
      if (std::abs(out.at<uint8_t>(y, col) - out.at<uint8_t>(y - 1, col)) > 60) {
        edge = y;
        break;
      }
    }
    EXPECT_NEAR(edge, expected, 4.0) << "column " << col;
  }
  EXPECT_THROW(CompensateWarping(cv::Mat(), cam.panorama, o), std::invalid_argument);
  o.height_top_m = -1;
  EXPECT_THROW(CompensateWarping(gray, cam.panorama, o), std::invalid_argument);
}

TEST(HogHoming, BadInputIsAClearError) {
  HogOptions o;
  EXPECT_THROW(ColumnHistograms(cv::Mat(), o), std::invalid_argument);
  EXPECT_THROW(ColumnHistograms(cv::Mat(10, 720, CV_8UC1, cv::Scalar(0)), o), std::invalid_argument);  // band < cell
  o.bins = 1;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  HogOptions a, b;
  b.cell_size_px = 20;
  const ColumnHistograms ha(RandomPanorama(1), a), hb(RandomPanorama(1).rowRange(0, 100), b);
  EXPECT_THROW(VisualCompass(ha, hb, 40), std::invalid_argument);
  // A blank panorama has no gradients: no answer, not a bogus vector.
  const ColumnHistograms blank(cv::Mat(120, 720, CV_8UC1, cv::Scalar(90)), a);
  EXPECT_FALSE(HogHoming(blank, blank, a, HogAlvOptions{}, PanoramaModel{}).has_value());
}

}  // namespace
}  // namespace snapnav::nav
