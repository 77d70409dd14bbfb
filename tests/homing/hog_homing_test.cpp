#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/hog_homing.hpp"
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

// A room with blurred random textures rendered by the simulator: homing from displaced
// positions at arbitrary headings points home once the compass has aligned the views.
// Approaching a wall magnifies its blurred texture, so its cells hold weaker gradients:
// here current - home points home (the thesis' home - current points away, ~180 degrees).
TEST(HogHoming, DisplacedRobotPointsHome) {
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
  sim::OmniCameraOptions cam;
  cam.panorama.width_px = 720;
  cam.panorama.height_px = 120;
  cam.panorama.elevation_top_rad = 20 * M_PI / 180;
  cam.panorama.elevation_bottom_rad = -20 * M_PI / 180;
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
