// Masks everywhere: on a realistic render with the robot's struts and cable and their mask, the
// unwrap fills the masked pixels, and no landmark of any extractor (SIFT, SURF, vertical lines,
// the place views') lies on a masked pixel; the dense descriptors (HOG, the place view's signature,
// RatSLAM's view templates) do not depend on what the masked pixels hold.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <unistd.h>

#include "snapnav/glue/ini.hpp"

#include "realistic_render.hpp"
#include "snapnav/glue/frame_panoramas.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"
#include "snapnav/nav/homing/unwrap.hpp"

namespace snapnav::testing {
namespace {

struct Views {
  nav::sim::OmniCameraOptions camera;
  cv::Mat raw_mask;  // the renderer's parts, grown by 2 px
  cv::Mat home_raw, current_raw;
  cv::Mat home, current;              // panoramas, unwrapped with the mask (filled)
  cv::Mat home_plain, current_plain;  // unwrapped without it
  cv::Mat mask;                       // the panoramas' mask
};

const Views& Rendered() {
  static const Views v = [] {
    Views v;
    RenderCase c;
    c.seed = 21;
    v.camera = RealisticCamera(c);
    const auto& scene = SharedScene("indoor13");
    nav::sim::OmniRenderer r(scene, v.camera);
    v.raw_mask = nav::GrowMasked(r.PartsMask(), 2, false);
    r.RenderOmni({3.5, 3.0, 0.2}, {}, &v.home_raw);
    r.RenderOmni({3.1, 2.7, 1.1}, {}, &v.current_raw);
    nav::Unwrapper plain(v.camera.ReportedMirror(), v.camera.panorama, v.home_raw.size());
    nav::Unwrapper masked = plain;
    masked.SetMask(v.raw_mask);
    masked.Unwrap(v.home_raw, &v.home);
    masked.Unwrap(v.current_raw, &v.current);
    plain.Unwrap(v.home_raw, &v.home_plain);
    plain.Unwrap(v.current_raw, &v.current_plain);
    v.mask = masked.panorama_mask();
    return v;
  }();
  return v;
}

// `image` with random values in its masked pixels.
cv::Mat Scribbled(const cv::Mat& image, const cv::Mat& mask, uint64_t seed) {
  cv::Mat junk(image.size(), image.type());
  cv::RNG rng(seed);
  rng.fill(junk, cv::RNG::UNIFORM, 0, 256);
  cv::Mat out = image.clone();
  junk.copyTo(out, mask == 0);
  return out;
}

int OnMasked(const nav::LandmarkSet& set, const cv::Mat& mask) {
  int n = 0;
  for (const auto& l : set.landmarks) {
    const int x = std::clamp(static_cast<int>(std::lround(l.x_px)), 0, mask.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(l.y_px)), 0, mask.rows - 1);
    n += mask.at<uint8_t>(y, x) == 0;
  }
  return n;
}

TEST(Masks, TheRendersPartsAreMaskedInThePanorama) {
  const Views& v = Rendered();
  // Three struts, a cable: a few percent of the panorama, in whole columns at the struts' bearings.
  const double f = nav::MaskedFraction(v.mask);
  EXPECT_GT(f, 0.02);
  EXPECT_LT(f, 0.15);
  for (double bearing_deg : {60.0, 180.0, 300.0}) {
    const int col = static_cast<int>(std::lround(v.camera.panorama.ColumnOfBearing(bearing_deg * M_PI / 180))) %
                    v.camera.panorama.width_px;
    EXPECT_EQ(cv::countNonZero(v.mask.col(col)), 0) << "strut at " << bearing_deg << " deg, column " << col;
  }
  // The unwrap filled them: the panorama does not depend on what the masked raw pixels hold.
  nav::Unwrapper u(v.camera.ReportedMirror(), v.camera.panorama, v.home_raw.size());
  u.SetMask(v.raw_mask);
  cv::Mat again;
  u.Unwrap(Scribbled(v.home_raw, v.raw_mask, 5), &again);
  EXPECT_EQ(cv::norm(again, v.home, cv::NORM_INF), 0);
  EXPECT_THROW(u.SetMask(cv::Mat(10, 10, CV_8UC1)), std::invalid_argument);
}

TEST(Masks, TheImagesBorderIsMaskedWhereTheRimRunsPastIt) {
  // A 16:9 frame cuts the mirror at its top and bottom (as real cameras often do): the panorama's
  // pixels whose samples fall outside the image are masked, and only those.
  RenderCase c;
  c.width = 1280, c.height = 720, c.cx = 641.7, c.cy = 362.4, c.radius = 392, c.seed = 11;
  const nav::sim::OmniCameraOptions camera = RealisticCamera(c);
  nav::sim::OmniRenderer r(SharedScene("indoor13"), camera);
  cv::Mat raw;
  r.RenderOmni({3.5, 3.0, 0.2}, {}, &raw);
  const nav::MirrorModel mirror = camera.ReportedMirror();
  nav::Unwrapper u(mirror, camera.panorama, raw.size());
  const cv::Mat mask = u.panorama_mask().clone();
  ASSERT_FALSE(mask.empty());
  const double f = nav::MaskedFraction(mask);
  EXPECT_GT(f, 0.001);
  EXPECT_LT(f, 0.05);
  int outside = 0;
  for (int row = 0; row < mask.rows; ++row) {
    for (int col = 0; col < mask.cols; ++col) {
      const auto px = nav::MirrorPixel(mirror, camera.panorama.BearingOfColumn(col), camera.panorama.ElevationOfRow(row));
      ASSERT_TRUE(px.has_value());
      // Bilinear: usable when both pixels it reads along each axis lie inside (up to the remap's
      // fixed point, 1/32 px).
      const double e = 1.0 / 32;
      const bool in = px->x() >= -e && px->x() <= c.width - 1 + e && px->y() >= -e && px->y() <= c.height - 1 + e;
      const bool well_in = px->x() >= 1 && px->x() <= c.width - 2 && px->y() >= 1 && px->y() <= c.height - 2;
      outside += !in;
      if (!in) {
        EXPECT_EQ(mask.at<uint8_t>(row, col), 0) << "row " << row << " col " << col;
      }
      if (well_in) {
        EXPECT_NE(mask.at<uint8_t>(row, col), 0) << "row " << row << " col " << col;
      }
    }
  }
  EXPECT_GT(outside, 0);
  // The border's black does not reach the panorama (filled from the row), and no landmark lies on it.
  cv::Mat pano, grey;
  u.Unwrap(raw, &pano);
  cv::cvtColor(pano, grey, cv::COLOR_BGR2GRAY);
  const cv::Mat top = grey.rowRange(0, 20), top_mask = mask.rowRange(0, 20);
  ASSERT_GT(cv::countNonZero(top_mask == 0), 0);
  EXPECT_GT(cv::mean(top, top_mask == 0)[0], 0.5 * cv::mean(top, top_mask)[0]);
  for (auto method : {nav::LandmarkMethod::kSift, nav::LandmarkMethod::kSurf}) {
    nav::LandmarkExtractorConfig lc;
    lc.method = method;
    const auto set = nav::ExtractLandmarks(pano, lc, mask);
    EXPECT_GT(set.size(), 5) << nav::LandmarkMethodName(method);
    EXPECT_EQ(OnMasked(set, mask), 0) << nav::LandmarkMethodName(method);
  }
  // A raw mask adds to the border's; removing it leaves the border's.
  nav::Unwrapper with = u;
  with.SetMask(cv::Mat(raw.size(), CV_8UC1, cv::Scalar(255)));
  EXPECT_EQ(cv::countNonZero(with.panorama_mask() != mask), 0);
  cv::Mat parts = cv::Mat(raw.size(), CV_8UC1, cv::Scalar(255));
  cv::rectangle(parts, cv::Rect(0, 300, 1280, 40), cv::Scalar(0), cv::FILLED);
  with.SetMask(parts);
  EXPECT_GT(nav::MaskedFraction(with.panorama_mask()), f);
  EXPECT_EQ(cv::countNonZero(with.panorama_mask() & (mask == 0)), 0);
  with.SetMask(cv::Mat());
  EXPECT_EQ(cv::countNonZero(with.panorama_mask() != mask), 0);
  // A ring inside the image has no mask of its own, as before.
  const nav::sim::OmniCameraOptions inside = RealisticCamera(RenderCase{});
  EXPECT_TRUE(nav::Unwrapper(inside.ReportedMirror(), inside.panorama, cv::Size(640, 480)).panorama_mask().empty());
}

TEST(Masks, NoLandmarkOnTheRobotsParts) {
  const Views& v = Rendered();
  for (auto method : {nav::LandmarkMethod::kSift, nav::LandmarkMethod::kSurf, nav::LandmarkMethod::kVline}) {
    SCOPED_TRACE(nav::LandmarkMethodName(method));
    nav::LandmarkExtractorConfig c;
    c.method = method;
    // Without the mask, the cable and struts give landmarks (SIFT, SURF: blobs and corners on them).
    const auto unmasked = nav::ExtractLandmarks(v.home_plain, c);
    if (method != nav::LandmarkMethod::kVline) {
      EXPECT_GT(OnMasked(unmasked, v.mask), 0);
    }
    const auto set = nav::ExtractLandmarks(v.home, c, v.mask);
    EXPECT_GT(set.size(), 5);
    EXPECT_EQ(OnMasked(set, v.mask), 0);
    const cv::Mat clearance = nav::MaskClearance(v.mask);
    for (const auto& l : set.landmarks) {
      const double need = c.mask_margin_px + (method == nav::LandmarkMethod::kVline ? 0 : 0.5 * l.scale_px);
      EXPECT_GE(clearance.at<float>(static_cast<int>(std::lround(l.y_px)),
                                    std::clamp(static_cast<int>(std::lround(l.x_px)), 0, v.mask.cols - 1)),
                need - 1.0);
    }
    // And what the masked pixels hold does not matter.
    const auto scribbled = nav::ExtractLandmarks(Scribbled(v.home, v.mask, 7), c, v.mask);
    ASSERT_EQ(scribbled.size(), set.size());
    EXPECT_EQ(cv::norm(scribbled.descriptors, set.descriptors, cv::NORM_INF), 0);
  }
}

TEST(Masks, PlaceViewsIgnoreMaskedPixels) {
  const Views& v = Rendered();
  nav::PlaceViewOptions o;
  const auto view = nav::MakePlaceView(v.home, o, v.mask);
  EXPECT_EQ(OnMasked(view.landmarks, v.mask), 0);
  EXPECT_EQ(OnMasked(view.vlines, v.mask), 0);
  const auto again = nav::MakePlaceView(Scribbled(v.home, v.mask, 9), o, v.mask);
  EXPECT_EQ(cv::norm(again.signature, view.signature, cv::NORM_INF), 0);
  ASSERT_EQ(again.landmarks.size(), view.landmarks.size());
  ASSERT_EQ(again.vlines.size(), view.vlines.size());
  EXPECT_THROW(nav::MakePlaceView(v.home, o, cv::Mat(5, 5, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
}

// A caller with a fixed mask gives its clearance once: the same view as computing it per call; a
// clearance of another mask's size is refused, not read out of bounds.
TEST(Masks, AGivenClearanceGivesTheSameViewAndAWrongOneIsRefused) {
  const Views& v = Rendered();
  nav::PlaceViewOptions o;
  const cv::Mat clearance = nav::MaskClearance(v.mask);
  const auto computed = nav::MakePlaceView(v.home, o, v.mask);
  const auto given = nav::MakePlaceView(v.home, o, v.mask, clearance);
  ASSERT_GT(computed.landmarks.size(), 0);
  ASSERT_EQ(given.landmarks.size(), computed.landmarks.size());
  ASSERT_EQ(given.vlines.size(), computed.vlines.size());
  for (int i = 0; i < computed.landmarks.size(); ++i) {
    EXPECT_EQ(given.landmarks.landmarks[i].x_px, computed.landmarks.landmarks[i].x_px);
  }
  EXPECT_EQ(cv::norm(given.landmarks.descriptors, computed.landmarks.descriptors, cv::NORM_INF), 0);
  // Landmarks near the parts are dropped the same way: a clearance of all zeros drops every one.
  const cv::Mat none_clear(v.mask.size(), CV_32F, cv::Scalar(0));
  EXPECT_EQ(nav::MakePlaceView(v.home, o, v.mask, none_clear).landmarks.size(), 0);
  const cv::Mat small(v.mask.rows / 2, v.mask.cols, CV_32F, cv::Scalar(100));
  EXPECT_THROW(nav::MakePlaceView(v.home, o, v.mask, small), std::invalid_argument);
  nav::LandmarkExtractorConfig c;
  c.method = nav::LandmarkMethod::kSift;
  EXPECT_THROW(nav::ExtractLandmarks(v.home, c, v.mask, small), std::invalid_argument);
}

TEST(Masks, HogHomingIgnoresMaskedPixels) {
  const Views& v = Rendered();
  nav::HogHomingConfig c;
  c.hog.cell_size_px = 20;
  c.compass_hog.cell_size_px = 20;
  nav::HogHomer a(c, v.camera.panorama), b(c, v.camera.panorama);
  a.SetMask(v.mask);
  b.SetMask(v.mask);
  a.SetHome(v.home);
  b.SetHome(Scribbled(v.home, v.mask, 11));
  const auto ea = a.Home(v.current), eb = b.Home(Scribbled(v.current, v.mask, 13));
  ASSERT_TRUE(ea && eb);
  EXPECT_DOUBLE_EQ(ea->direction_rad, eb->direction_rad);
  EXPECT_DOUBLE_EQ(ea->compass_rotation_rad, eb->compass_rotation_rad);
  // The compass still finds the rotation between the views (1.1 - 0.2 rad), the robot's parts being
  // at the same columns in both.
  EXPECT_NEAR(nav::WrapAngle(ea->compass_rotation_rad - 0.9), 0, 0.12);
  // Cells whose pixels are mostly masked are left out.
  nav::Gradients g = nav::ComputeGradients([&] {
    cv::Mat gray;
    cv::cvtColor(v.home, gray, cv::COLOR_BGR2GRAY);
    return gray;
  }());
  auto left_out = [&](double max_masked_share) {
    nav::HogOptions o = c.hog;
    o.max_masked_share = max_masked_share;
    const nav::ColumnHistograms h(g, o, v.mask);
    EXPECT_DOUBLE_EQ(h.max_masked_share(), max_masked_share);
    const auto cells = nav::CellsAtShift(h, o.cell_size_px, 0);
    EXPECT_FALSE(cells.valid.empty());
    return static_cast<int>(std::count(cells.valid.begin(), cells.valid.end(), 0));
  };
  const int cells_total = (c.hog.band_height_px > 0 ? c.hog.band_height_px : v.home.rows) / c.hog.cell_size_px *
                          (v.home.cols / c.hog.cell_size_px);
  const int strict = left_out(0.1), shipped = left_out(0.9);
  EXPECT_GT(strict, 0);
  EXPECT_LT(strict, cells_total / 3);
  EXPECT_LT(shipped, strict);  // a partly masked cell counts, scaled up to the whole cell
  nav::HogOptions bad = c.hog;
  bad.max_masked_share = 1.0;  // a wholly masked cell cannot be scaled up
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

TEST(Masks, RatSlamTemplatesIgnoreMaskedPixels) {
  const Views& v = Rendered();
  cv::Mat gray, scribbled;
  cv::cvtColor(v.home, gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(Scribbled(v.home, v.mask, 3), scribbled, cv::COLOR_BGR2GRAY);
  scribbled.setTo(0, v.mask == 0);  // black bars where the parts are
  nav::LocalViewCells cells({});
  const auto t = cells.MakeTemplate(gray, v.mask);
  const auto u = cells.MakeTemplate(scribbled, v.mask);
  ASSERT_EQ(t.size(), u.size());
  for (size_t i = 0; i < t.size(); ++i) EXPECT_FLOAT_EQ(t[i], u[i]) << i;
  const auto black = cells.MakeTemplate(scribbled);  // without the mask the bars are in the template
  double diff = 0;
  for (size_t i = 0; i < t.size(); ++i) diff += std::abs(t[i] - black[i]);
  EXPECT_GT(diff, 0.5);
}

TEST(Masks, FramePanoramasCarryTheMask) {
  const Views& v = Rendered();
  glue::FramePanoramas frames(v.camera.panorama, v.camera.mirror);
  frames.SetMask(v.raw_mask);
  omni_frame_t f = glue::ImageToFrame(v.home_raw, omni_frame_t::RGB8);
  glue::SetMirror(v.camera.ReportedMirror(), &f);
  const auto pano = frames.Convert(f);
  ASSERT_TRUE(pano.has_value()) << frames.detail();
  // As the unwrap with the frame's calibration (floats on the bus) and the mask.
  nav::Unwrapper u(glue::MirrorOf(f), v.camera.panorama, v.home_raw.size());
  u.SetMask(v.raw_mask);
  cv::Mat expected;
  u.Unwrap(v.home_raw, &expected);
  EXPECT_EQ(cv::norm(*pano, expected, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(frames.mask(), u.panorama_mask(), cv::NORM_INF), 0);
  // The mask's clearance, computed with the unwrap map, is the mask's (and goes with a refused frame).
  ASSERT_FALSE(frames.mask_clearance().empty());
  EXPECT_EQ(cv::norm(frames.mask_clearance(), nav::MaskClearance(frames.mask()), cv::NORM_INF), 0);
  // A raw frame of another size than the mask is refused, by name.
  omni_frame_t small = glue::ImageToFrame(cv::Mat(240, 320, CV_8UC3, cv::Scalar(50, 50, 50)), omni_frame_t::RGB8);
  EXPECT_FALSE(frames.Convert(small).has_value());
  EXPECT_EQ(frames.reason(), "wrong mask size");
  EXPECT_TRUE(frames.mask().empty());
  EXPECT_TRUE(frames.mask_clearance().empty());
}

TEST(ImageMask, FillClearanceAndGrow) {
  cv::Mat img(1, 8, CV_8UC1);
  for (int x = 0; x < 8; ++x) img.at<uint8_t>(0, x) = static_cast<uint8_t>(10 * x);
  cv::Mat mask(1, 8, CV_8UC1, cv::Scalar(255));
  mask.at<uint8_t>(0, 3) = mask.at<uint8_t>(0, 4) = 0;
  mask.at<uint8_t>(0, 7) = 0;
  cv::Mat filled = img.clone();
  nav::FillMasked(mask, &filled);
  EXPECT_EQ(filled.at<uint8_t>(0, 3), 30);  // between 20 (x=2) and 50 (x=5)
  EXPECT_EQ(filled.at<uint8_t>(0, 4), 40);
  EXPECT_EQ(filled.at<uint8_t>(0, 7), 30);  // between 60 (x=6) and 0 (x=0, wrapping)
  const cv::Mat clearance = nav::MaskClearance(mask);
  EXPECT_FLOAT_EQ(clearance.at<float>(0, 0), 1.0f);  // next to x=7 across the seam
  EXPECT_FLOAT_EQ(clearance.at<float>(0, 1), 2.0f);
  const cv::Mat grown = nav::GrowMasked(mask, 1);
  EXPECT_EQ(grown.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(grown.at<uint8_t>(0, 1), 255);
  EXPECT_EQ(grown.at<uint8_t>(0, 2), 0);
}

// A config's [mirror] mask: relative to the config's folder; a missing file, a file that is no
// image or a mask of another size than the camera's is refused naming the config's file, line and key.
TEST(MaskConfig, ReadFromTheConfigsFolderAndRefusedWithFileLineAndKey) {
  const auto dir = std::filesystem::temp_directory_path() / ("mask_config_test." + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  cv::imwrite((dir / "mask.png").string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255)));
  std::ofstream((dir / "notimage.png").string()) << "plain text\n";
  const auto config = [&](const std::string& mask) {
    const std::string path = (dir / "c.ini").string();
    std::ofstream(path) << "[mirror]\nmask = " << mask << "\n";
    return glue::IniFile::Load(path);
  };
  const auto error = [&](const std::string& mask, cv::Size expected) {
    try {
      (void)glue::ReadMirrorMask(config(mask), expected);
    } catch (const glue::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const glue::MirrorMask m = glue::ReadMirrorMask(config("mask.png"), cv::Size(64, 48));
  EXPECT_EQ(m.path, (dir / "mask.png").string());
  EXPECT_EQ(m.mask.size(), cv::Size(64, 48));
  EXPECT_TRUE(glue::ReadMirrorMask(config("")).mask.empty());
  const std::string at = (dir / "c.ini").string() + ":2: [mirror] mask = ";
  EXPECT_EQ(error("nosuch.png", {}).rfind(at + "'nosuch.png': mask ", 0), 0u) << error("nosuch.png", {});
  EXPECT_NE(error("nosuch.png", {}).find("no such file"), std::string::npos);
  EXPECT_NE(error("notimage.png", {}).find("not an image"), std::string::npos);
  EXPECT_EQ(error("notimage.png", {}).rfind(at, 0), 0u);
  EXPECT_NE(error("mask.png", cv::Size(640, 480)).find("64x48, the camera's images are 640x480"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(MaskConfig, TheMaskFlagOverridesTheConfigsKeyOrNamesWhatIsWrong) {
  const auto dir = std::filesystem::temp_directory_path() / ("mask_flag_test." + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "configs");
  cv::imwrite((dir / "flag.png").string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(0)));
  const std::string path = (dir / "configs" / "c.ini").string();
  std::ofstream(path) << "[mirror]\nmask =\n";
  auto ini = glue::IniFile::Load(path);
  glue::ApplyMaskFlag("", &ini);  // no flag: the config's (none)
  EXPECT_TRUE(glue::ReadMirrorMask(ini).mask.empty());
  // A path relative to the working folder, not to the config's folder.
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  glue::ApplyMaskFlag("flag.png", &ini);
  std::filesystem::current_path(cwd);
  const glue::MirrorMask m = glue::ReadMirrorMask(ini, cv::Size(64, 48));
  EXPECT_EQ(m.path, (dir / "flag.png").string());
  EXPECT_EQ(cv::countNonZero(m.mask), 0);
  try {
    glue::ApplyMaskFlag((dir / "nosuch.png").string(), &ini);
    ADD_FAILURE() << "a missing mask file was taken";
  } catch (const glue::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "--mask " + (dir / "nosuch.png").string() + ": no such file");
  }
  std::ofstream(path) << "[mirror]\ncenter_x_px = 1\n";  // a config without the key
  auto no_key = glue::IniFile::Load(path);
  try {
    glue::ApplyMaskFlag((dir / "flag.png").string(), &no_key);
    ADD_FAILURE() << "a config without [mirror] mask took the flag";
  } catch (const glue::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--mask: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("has no key 'mask'"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace snapnav::testing
