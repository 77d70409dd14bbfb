#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/homing/unwrap.hpp"

namespace snapnav::nav {
namespace {

TEST(Unwrap, KnownRingMapsToExpectedRow) {
  MirrorModel m;  // centre (320, 240), radii 40..230, elevations -40..20 deg
  m.elevation_inner_rad = -40 * M_PI / 180;
  m.elevation_outer_rad = 20 * M_PI / 180;
  PanoramaModel p;
  p.width_px = 720;
  p.height_px = 120;
  p.elevation_top_rad = 20 * M_PI / 180;
  p.elevation_bottom_rad = -40 * M_PI / 180;
  cv::Mat raw(480, 640, CV_8UC1, cv::Scalar(0));
  const double radius = 135;  // elevation -40 + 60 * 95/190 = -10 deg
  cv::circle(raw, {320, 240}, static_cast<int>(radius), cv::Scalar(255), 1, cv::LINE_AA);
  Unwrapper u(m, p, raw.size());
  cv::Mat pano;
  u.Unwrap(raw, &pano);
  ASSERT_EQ(pano.cols, 720);
  ASSERT_EQ(pano.rows, 120);
  const double expected_row = p.RowOfElevation(-10 * M_PI / 180);
  for (int c = 0; c < pano.cols; c += 45) {
    cv::Point max_loc;
    cv::minMaxLoc(pano.col(c), nullptr, nullptr, nullptr, &max_loc);
    EXPECT_NEAR(max_loc.y, expected_row, 1.0) << "column " << c;
  }
}

TEST(Unwrap, MatchesThePanoramaTheSimulatorRendersDirectly) {
  sim::Scene scene;
  scene.name = "room";
  cv::Mat tex(64, 64, CV_8UC3);
  cv::randu(tex, 0, 255);
  cv::GaussianBlur(tex, tex, {5, 5}, 1.5);
  scene.textures.push_back(sim::MakeTexture("t", tex, 1.0, 1.0));
  scene.walls = {{{-3, -3}, {3, -3}, 2.6, 0, 0, 0}, {{3, -3}, {3, 3}, 2.6, 0, 0, 0},
                 {{3, 3}, {-3, 3}, 2.6, 0, 0, 0}, {{-3, 3}, {-3, -3}, 2.6, 0, 0, 0}};
  sim::OmniCameraOptions o;
  o.panorama.width_px = 720;
  o.panorama.height_px = 120;
  o.panorama.elevation_top_rad = 15 * M_PI / 180;
  o.panorama.elevation_bottom_rad = -25 * M_PI / 180;
  sim::OmniRenderer r(scene, o);
  cv::Mat raw, direct, unwrapped;
  r.RenderOmni({0.3, -0.2, 0.4}, {}, &raw);
  r.RenderPanorama({0.3, -0.2, 0.4}, {}, &direct);
  Unwrapper u(o.mirror, o.panorama, raw.size());
  u.Unwrap(raw, &unwrapped);
  cv::Mat a, b;
  cv::cvtColor(direct, a, cv::COLOR_BGR2GRAY);
  cv::cvtColor(unwrapped, b, cv::COLOR_BGR2GRAY);
  cv::GaussianBlur(a, a, {5, 5}, 1.5);
  cv::GaussianBlur(b, b, {5, 5}, 1.5);
  // The two are the same view (up to resampling): far closer than a misaligned copy.
  const double same = cv::norm(a, b, cv::NORM_L1) / a.total();
  cv::Mat shifted;
  cv::hconcat(b.colRange(10, b.cols), b.colRange(0, 10), shifted);
  const double misaligned = cv::norm(a, shifted, cv::NORM_L1) / a.total();
  EXPECT_LT(same, 8.0);
  EXPECT_LT(same, 0.5 * misaligned);
}

TEST(Unwrap, BadInputIsAClearError) {
  MirrorModel m;
  PanoramaModel p;
  EXPECT_THROW(Unwrapper(m, p, cv::Size(100, 100)), std::invalid_argument);  // centre (320, 240) outside
  Unwrapper u(m, p, cv::Size(640, 480));
  cv::Mat pano;
  EXPECT_THROW(u.Unwrap(cv::Mat(), &pano), std::invalid_argument);
  EXPECT_THROW(u.Unwrap(cv::Mat(240, 320, CV_8UC1), &pano), std::invalid_argument);
  PanoramaModel too_high = p;
  too_high.elevation_top_rad = 1.2;  // above the mirror's 20 degrees
  EXPECT_THROW(Unwrapper(m, too_high, cv::Size(640, 480)), std::invalid_argument);
}

TEST(CalibrateMirror, FindsTheMirrorCircleOfARenderedImage) {
  sim::Scene scene;
  scene.name = "room";
  cv::Mat tex(32, 32, CV_8UC3);
  cv::randu(tex, 60, 255);
  scene.textures.push_back(sim::MakeTexture("t", tex, 1.0, 1.0));
  scene.walls = {{{-3, -3}, {3, -3}, 2.6, 0, 0, 0}, {{3, -3}, {3, 3}, 2.6, 0, 0, 0},
                 {{3, 3}, {-3, 3}, 2.6, 0, 0, 0}, {{-3, 3}, {-3, -3}, 2.6, 0, 0, 0}};
  scene.floor_bgr = {150, 150, 150};
  sim::OmniCameraOptions o;
  o.mirror.center_x_px = 330;
  o.mirror.center_y_px = 235;
  o.mirror.outer_radius_px = 220;
  o.mirror.inner_radius_px = 45;
  sim::OmniRenderer r(scene, o);
  cv::Mat raw;
  r.RenderOmni({0, 0, 0}, {}, &raw);
  const MirrorProfile profile = MirrorProfile::FromMirror(o.mirror);
  const auto found = CalibrateMirror(raw, profile);
  ASSERT_TRUE(found.has_value());
  EXPECT_NEAR(found->mirror.center_x_px, 330, 1.0);
  EXPECT_NEAR(found->mirror.center_y_px, 235, 1.0);
  EXPECT_NEAR(found->mirror.outer_radius_px, 220, 2.0);
  EXPECT_NEAR(found->mirror.inner_radius_px, 45, 3.0);
  std::string why;
  EXPECT_FALSE(CalibrateMirror(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)), profile, {}, &why).has_value());
  EXPECT_NE(why.find("no edges"), std::string::npos) << why;
}

}  // namespace
}  // namespace snapnav::nav
