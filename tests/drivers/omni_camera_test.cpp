// omni-camera: config parsing, cv::Mat -> omni_frame_t for every encoding, and the node
// on real files (images written by the test, a video written by the test, MRPT's sample
// video) with LCM memq:// and file:// logs.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>

#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "../support/config_errors.hpp"
#include "driver_test_util.hpp"
#include "omni_camera_node.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::processes {
namespace {

using snapnav::testing::ScratchDir;

const std::string kShippedConfig = std::string(SNAPNAV_CONFIG_DIR) + "/omni_camera.ini";

std::string ConfigText(const std::string& source, const std::string& encoding, bool loop, double rate_hz = 0,
                       int width_px = 0, int height_px = 0) {
  std::ostringstream s;
  s << "[channels]\nframe = OMNI_FRAME\n"
    << "[camera]\nsensor_name = testcam\nsource = " << source << "\nwidth_px = " << width_px
    << "\nheight_px = " << height_px << "\nrate_hz = " << rate_hz << "\nloop = " << (loop ? "true" : "false")
    << "\nencoding = " << encoding << "\njpeg_quality = 90\n"
    << "[mirror]\ncenter_x_px = 31.5\ncenter_y_px = 23.25\ninner_radius_px = 5\nouter_radius_px = 22.5\n"
    << "elevation_inner_deg = -30\nelevation_outer_deg = 15\nmask =\n";
  return s.str();
}

OmniCameraConfig ParseConfig(const std::string& text, const std::string& prefix = "") {
  return OmniCameraConfig::FromIni(glue::IniFile::Parse(text, "test.ini"), prefix);
}

// The text with the line that sets `key` removed.
std::string WithoutKey(const std::string& text, const std::string& key) {
  return std::regex_replace(text, std::regex("(^|\n)" + key + " *=[^\n]*"), "$1");
}

std::string ConfigErrorOf(const std::string& text) {
  try {
    ParseConfig(text);
  } catch (const glue::ConfigError& e) {
    return e.what();
  }
  return "";
}

// Collects the frames a node publishes on a memq:// bus.
struct Collector {
  Collector(glue::Bus& bus, const std::string& channel) {
    bus.Subscribe<omni_frame_t>(channel, [this](const omni_frame_t& f) { frames.push_back(f); });
  }
  std::vector<omni_frame_t> frames;
};

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

// A 64x48 gray test image whose pixels encode `id` (so the order can be checked) plus a gradient.
cv::Mat TestImage(int id, int width = 64, int height = 48) {
  cv::Mat image(height, width, CV_8UC1);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) image.at<uint8_t>(r, c) = static_cast<uint8_t>((id * 40 + r + c) % 256);
  }
  return image;
}

cv::Mat RandomImage(int rows, int cols, int type, int seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

// A smooth colour image (JPEG keeps it close).
cv::Mat SmoothColorImage(int rows, int cols) {
  cv::Mat m(rows, cols, CV_8UC3);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      m.at<cv::Vec3b>(r, c) =
          cv::Vec3b(static_cast<uint8_t>(2 * c), static_cast<uint8_t>(3 * r), static_cast<uint8_t>(100 + r + c));
    }
  }
  return m;
}

cv::Mat DecodeCompressed(const omni_frame_t& f) {
  return cv::imdecode(cv::Mat(1, static_cast<int>(f.data.size()), CV_8UC1, const_cast<uint8_t*>(f.data.data())),
                      cv::IMREAD_UNCHANGED);
}

OmniFrameOptions Options(int8_t encoding) {
  OmniFrameOptions o;
  o.sensor_name = "omni_test";
  o.encoding = encoding;
  o.jpeg_quality = 95;
  o.mirror = {160.5, 120.25, 30, 115, -0.7, 0.35};
  return o;
}

void ExpectCalibration(const omni_frame_t& f, const nav::MirrorModel& m) {
  EXPECT_FLOAT_EQ(f.mirror_center_x_px, m.center_x_px);
  EXPECT_FLOAT_EQ(f.mirror_center_y_px, m.center_y_px);
  EXPECT_FLOAT_EQ(f.mirror_inner_radius_px, m.inner_radius_px);
  EXPECT_FLOAT_EQ(f.mirror_outer_radius_px, m.outer_radius_px);
  EXPECT_FLOAT_EQ(f.mirror_elevation_inner_rad, m.elevation_inner_rad);
  EXPECT_FLOAT_EQ(f.mirror_elevation_outer_rad, m.elevation_outer_rad);
  EXPECT_FLOAT_EQ(f.bearing_col0_rad, 0);
  EXPECT_FLOAT_EQ(f.elevation_top_rad, 0);
  EXPECT_FLOAT_EQ(f.elevation_bottom_rad, 0);
}

// --- config ---

TEST(OmniCameraConfig, ShippedConfigLoads) {
  const auto config = OmniCameraConfig::FromIni(glue::IniFile::Load(kShippedConfig), "P_");
  EXPECT_EQ(config.frame_channel, "P_OMNI_FRAME");
  EXPECT_EQ(config.capture.source.kind, SourceKind::kDevice);
  EXPECT_GT(config.frame.mirror.outer_radius_px, config.frame.mirror.inner_radius_px);
  std::ostringstream printed;
  config.Print(printed);
  // The printed effective config parses back to the same options.
  const auto again = OmniCameraConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  EXPECT_EQ(again.frame_channel, "P_OMNI_FRAME");
  EXPECT_EQ(again.capture.source.ToString(), config.capture.source.ToString());
  EXPECT_EQ(again.frame.encoding, config.frame.encoding);
  EXPECT_DOUBLE_EQ(again.frame.mirror.center_x_px, config.frame.mirror.center_x_px);
}

TEST(OmniCameraConfig, EveryShippedKeyIsRequired) {
  const std::string text = snapnav::testing::ReadTextFile(kShippedConfig);
  for (const char* key : {"frame", "sensor_name", "source", "width_px", "height_px", "rate_hz", "loop", "encoding",
                          "jpeg_quality", "center_x_px", "center_y_px", "inner_radius_px", "outer_radius_px",
                          "elevation_inner_deg", "elevation_outer_deg"}) {
    const std::string without = WithoutKey(text, key);
    ASSERT_NE(without, text) << key << " not found in the shipped config";
    EXPECT_NE(ConfigErrorOf(without).find("missing key '" + std::string(key) + "'"), std::string::npos) << key;
  }
}

TEST(OmniCameraConfig, UnknownKeyIsAnError) {
  const std::string text = snapnav::testing::ReadTextFile(kShippedConfig) + "\n[camera_extra]\nexposure_ms = 3\n";
  EXPECT_NE(ConfigErrorOf(text).find("exposure_ms"), std::string::npos);
}

TEST(OmniCameraConfig, BadValuesAreErrorsNamingTheFile) {
  const std::string good = ConfigText("folder:/tmp", "png", false);
  EXPECT_EQ(ConfigErrorOf(good), "");
  auto replace = [&](const std::string& from, const std::string& to) {
    return std::regex_replace(good, std::regex(from), to);
  };
  EXPECT_NE(ConfigErrorOf(replace("folder:/tmp", "camera:0")).find("test.ini"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("folder:/tmp", "device:x")).find("device index"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("folder:/tmp", "file:")).find("empty path"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("encoding = png", "encoding = bmp")).find("unknown encoding"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("jpeg_quality = 90", "jpeg_quality = 0")).find("jpeg_quality"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("outer_radius_px = 22.5", "outer_radius_px = 4")).find("outer_radius_px"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("height_px = 0", "height_px = 48")).find("width_px"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("elevation_outer_deg = 15", "elevation_outer_deg = -30")).find("elevation"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("elevation_outer_deg = 15", "elevation_outer_deg = 95")).find("elevation"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("rate_hz = 0", "rate_hz = -1")).find("rate_hz"), std::string::npos);
  EXPECT_NE(ConfigErrorOf(replace("loop = false", "loop = maybe")).find("true or false"), std::string::npos);
  // Mirror centre (31.5, 23.25) outside a 20x20 image.
  EXPECT_NE(ConfigErrorOf(replace("width_px = 0\nheight_px = 0", "width_px = 20\nheight_px = 20")).find("outside"),
            std::string::npos);
}

TEST(FrameSourceSpec, ParsesTheThreeKinds) {
  EXPECT_EQ(FrameSourceSpec::Parse("device:3").device_index, 3);
  EXPECT_EQ(FrameSourceSpec::Parse("file:/a/b.avi").kind, SourceKind::kVideoFile);
  EXPECT_EQ(FrameSourceSpec::Parse("file:/a/b.avi").path, "/a/b.avi");
  EXPECT_EQ(FrameSourceSpec::Parse("folder:rel/imgs").kind, SourceKind::kImageFolder);
  EXPECT_EQ(FrameSourceSpec::Parse("folder:rel/imgs").ToString(), "folder:rel/imgs");
  EXPECT_THROW(FrameSourceSpec::Parse("device:-1"), std::invalid_argument);
  EXPECT_THROW(FrameSourceSpec::Parse("/dev/video0"), std::invalid_argument);
}

// --- cv::Mat -> omni_frame_t ---

TEST(MatToOmniFrame, Gray8KeepsEveryPixelAndTheCalibration) {
  const cv::Mat gray = RandomImage(23, 37, CV_8UC1, 1);  // odd width: no padding assumptions
  const auto options = Options(omni_frame_t::GRAY8);
  const omni_frame_t f = MatToOmniFrame(gray, 123456789, options);
  EXPECT_EQ(f.utime, 123456789);
  EXPECT_EQ(f.sensor_name, "omni_test");
  EXPECT_EQ(f.kind, omni_frame_t::RAW_OMNI);
  EXPECT_EQ(f.encoding, omni_frame_t::GRAY8);
  EXPECT_EQ(f.width, 37);
  EXPECT_EQ(f.height, 23);
  EXPECT_EQ(f.row_stride, 37);
  ASSERT_EQ(f.data_size, 37 * 23);
  ASSERT_EQ(f.data.size(), 37u * 23u);
  ExpectCalibration(f, options.mirror);
  for (int r = 0; r < 23; ++r) {
    for (int c = 0; c < 37; ++c) ASSERT_EQ(f.data[r * 37 + c], gray.at<uint8_t>(r, c)) << r << "," << c;
  }
  // A sub-image (rows with padding between them) packs the same way.
  const cv::Mat roi = gray(cv::Rect(3, 2, 11, 7));
  const omni_frame_t g = MatToOmniFrame(roi, 0, options);
  ASSERT_EQ(g.data.size(), 77u);
  EXPECT_EQ(g.data[12], roi.at<uint8_t>(1, 1));
  // It survives the wire.
  std::string error;
  const std::string wire = glue::Encode(f);
  const auto decoded = glue::Decode<omni_frame_t>(wire.data(), wire.size(), &error);
  ASSERT_TRUE(decoded) << error;
  EXPECT_EQ(decoded->data, f.data);
}

TEST(MatToOmniFrame, Gray8FromColourIsTheGrayConversion) {
  const cv::Mat bgr = RandomImage(10, 12, CV_8UC3, 2);
  cv::Mat expected;
  cv::cvtColor(bgr, expected, cv::COLOR_BGR2GRAY);
  const omni_frame_t f = MatToOmniFrame(bgr, 0, Options(omni_frame_t::GRAY8));
  ASSERT_EQ(f.data.size(), 120u);
  for (int i = 0; i < 120; ++i) ASSERT_EQ(f.data[i], expected.at<uint8_t>(i / 12, i % 12));
}

TEST(MatToOmniFrame, Rgb8IsInRedGreenBlueOrder) {
  const cv::Mat red(4, 5, CV_8UC3, cv::Scalar(0, 0, 255));  // OpenCV stores B,G,R
  const omni_frame_t f = MatToOmniFrame(red, 0, Options(omni_frame_t::RGB8));
  EXPECT_EQ(f.encoding, omni_frame_t::RGB8);
  EXPECT_EQ(f.row_stride, 15);
  ASSERT_EQ(f.data.size(), 60u);
  for (size_t i = 0; i < 60; i += 3) {
    EXPECT_EQ(f.data[i], 255);
    EXPECT_EQ(f.data[i + 1], 0);
    EXPECT_EQ(f.data[i + 2], 0);
  }
  const cv::Mat bgr = RandomImage(9, 7, CV_8UC3, 3);
  const omni_frame_t g = MatToOmniFrame(bgr, 0, Options(omni_frame_t::RGB8));
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 7; ++c) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(r, c);
      const size_t i = (r * 7 + c) * 3;
      ASSERT_EQ(g.data[i], p[2]);
      ASSERT_EQ(g.data[i + 1], p[1]);
      ASSERT_EQ(g.data[i + 2], p[0]);
    }
  }
  // Gray input becomes R = G = B.
  const omni_frame_t h = MatToOmniFrame(cv::Mat(2, 2, CV_8UC1, cv::Scalar(77)), 0, Options(omni_frame_t::RGB8));
  EXPECT_EQ(h.data, std::vector<uint8_t>(12, 77));
}

TEST(MatToOmniFrame, JpegDecodesBackCloseToTheImage) {
  const cv::Mat bgr = SmoothColorImage(48, 64);
  const auto options = Options(omni_frame_t::JPEG);
  const omni_frame_t f = MatToOmniFrame(bgr, 5, options);
  EXPECT_EQ(f.encoding, omni_frame_t::JPEG);
  EXPECT_EQ(f.row_stride, 0);
  EXPECT_EQ(f.width, 64);
  EXPECT_EQ(f.height, 48);
  ExpectCalibration(f, options.mirror);
  ASSERT_GT(f.data.size(), 2u);
  EXPECT_EQ(f.data_size, static_cast<int32_t>(f.data.size()));
  EXPECT_EQ(f.data[0], 0xFF);
  EXPECT_EQ(f.data[1], 0xD8);  // JPEG start of image
  const cv::Mat back = DecodeCompressed(f);
  ASSERT_EQ(back.type(), CV_8UC3);
  ASSERT_EQ(back.size(), bgr.size());
  EXPECT_LT(cv::norm(back, bgr, cv::NORM_L1) / (64.0 * 48 * 3), 3.0);
  // Pure red stays red (the JPEG holds the colours in the right order).
  const omni_frame_t red = MatToOmniFrame(cv::Mat(16, 16, CV_8UC3, cv::Scalar(0, 0, 255)), 0, options);
  const cv::Vec3b p = DecodeCompressed(red).at<cv::Vec3b>(8, 8);
  EXPECT_GT(p[2], 240);
  EXPECT_LT(p[0], 15);
  EXPECT_LT(p[1], 15);
  // The quality setting is used: noise at quality 10 compresses much smaller than at 95.
  const cv::Mat noise = RandomImage(64, 64, CV_8UC3, 4);
  auto low = options;
  low.jpeg_quality = 10;
  EXPECT_LT(MatToOmniFrame(noise, 0, low).data.size() * 2, MatToOmniFrame(noise, 0, options).data.size());
}

TEST(MatToOmniFrame, PngDecodesBackExactly) {
  const cv::Mat bgr = RandomImage(31, 45, CV_8UC3, 5);
  const omni_frame_t f = MatToOmniFrame(bgr, 0, Options(omni_frame_t::PNG));
  EXPECT_EQ(f.encoding, omni_frame_t::PNG);
  EXPECT_EQ(f.row_stride, 0);
  const cv::Mat back = DecodeCompressed(f);
  ASSERT_EQ(back.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(back, bgr, cv::NORM_INF), 0);
  const cv::Mat gray = RandomImage(13, 17, CV_8UC1, 6);
  const cv::Mat gray_back = DecodeCompressed(MatToOmniFrame(gray, 0, Options(omni_frame_t::PNG)));
  ASSERT_EQ(gray_back.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(gray_back, gray, cv::NORM_INF), 0);
  // BGRA loses its alpha, keeps its colours.
  cv::Mat bgra;
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  const cv::Mat no_alpha = DecodeCompressed(MatToOmniFrame(bgra, 0, Options(omni_frame_t::PNG)));
  ASSERT_EQ(no_alpha.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(no_alpha, bgr, cv::NORM_INF), 0);
}

TEST(MatToOmniFrame, RejectsWhatItCannotEncode) {
  const auto options = Options(omni_frame_t::GRAY8);
  EXPECT_THROW(MatToOmniFrame(cv::Mat(), 0, options), std::invalid_argument);
  EXPECT_THROW(MatToOmniFrame(cv::Mat(4, 4, CV_16UC1, cv::Scalar(1)), 0, options), std::invalid_argument);
  EXPECT_THROW(MatToOmniFrame(cv::Mat(4, 4, CV_8UC2, cv::Scalar(1)), 0, options), std::invalid_argument);
}

// --- the node on files ---

TEST(OmniCameraNode, PublishesAFolderOfImagesInFileNameOrder) {
  ScratchDir dir;
  // Written out of order, with a non-image file and a sub-folder that must be ignored.
  for (int id : {3, 0, 4, 1, 2}) {
    const std::string ext = id == 4 ? ".bmp" : (id == 1 ? ".PGM" : ".png");
    ASSERT_TRUE(cv::imwrite(dir / ("img_" + std::to_string(id) + ext), TestImage(id)));
  }
  snapnav::testing::WriteTextFile(dir / "notes.txt", "not an image");
  std::filesystem::create_directory(dir.path() / "sub.png");

  glue::Bus bus("memq://");
  const auto config = ParseConfig(ConfigText("folder:" + dir.path().string(), "gray8", false), "F1_");
  Collector out(bus, "F1_OMNI_FRAME");
  std::ostringstream log;
  OmniCameraNode node(bus, config, &log);
  EXPECT_NE(node.source_description().find("5 images"), std::string::npos);
  const int64_t before = glue::WallUtime();
  EXPECT_EQ(node.Run(0), OmniCameraNode::StopReason::kEndOfSource);
  const int64_t after = glue::WallUtime();
  HandleAll(bus);

  EXPECT_EQ(node.published(), 5);
  EXPECT_EQ(node.read_failures() + node.size_mismatches() + node.conversion_errors(), 0);
  EXPECT_EQ(log.str(), "");
  ASSERT_EQ(out.frames.size(), 5u);
  int64_t last_utime = 0;
  for (int i = 0; i < 5; ++i) {
    const omni_frame_t& f = out.frames[i];
    EXPECT_EQ(f.width, 64);
    EXPECT_EQ(f.height, 48);
    EXPECT_EQ(f.encoding, omni_frame_t::GRAY8);
    EXPECT_EQ(f.kind, omni_frame_t::RAW_OMNI);
    EXPECT_EQ(f.sensor_name, "testcam");
    EXPECT_FLOAT_EQ(f.mirror_center_x_px, 31.5f);
    EXPECT_FLOAT_EQ(f.mirror_center_y_px, 23.25f);
    EXPECT_FLOAT_EQ(f.mirror_inner_radius_px, 5.f);
    EXPECT_FLOAT_EQ(f.mirror_outer_radius_px, 22.5f);
    EXPECT_FLOAT_EQ(f.mirror_elevation_inner_rad, static_cast<float>(-30 * M_PI / 180));
    EXPECT_FLOAT_EQ(f.mirror_elevation_outer_rad, static_cast<float>(15 * M_PI / 180));
    ASSERT_EQ(f.data.size(), 64u * 48u);
    // Lossless formats: the pixels are exactly the image with id i (file-name order).
    const cv::Mat expected = TestImage(i);
    EXPECT_TRUE(std::equal(f.data.begin(), f.data.end(), expected.data)) << "frame " << i;
    EXPECT_GE(f.utime, std::max(before, last_utime));
    EXPECT_LE(f.utime, after);
    last_utime = f.utime;
  }
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("published 5 frames on F1_OMNI_FRAME"), std::string::npos) << report.str();
}

TEST(OmniCameraNode, CountsUnreadableAndWrongSizeImagesAndGoesOn) {
  ScratchDir dir;
  ASSERT_TRUE(cv::imwrite(dir / "a.png", TestImage(0)));
  snapnav::testing::WriteTextFile(dir / "b.png", "this is not a png");
  ASSERT_TRUE(cv::imwrite(dir / "c.png", TestImage(1, 32, 32)));
  ASSERT_TRUE(cv::imwrite(dir / "d.png", TestImage(2)));
  ASSERT_TRUE(cv::imwrite(dir / "e.jpg", TestImage(3)));

  glue::Bus bus("memq://");
  const auto config = ParseConfig(ConfigText("folder:" + dir.path().string(), "png", false), "F2_");
  Collector out(bus, "F2_OMNI_FRAME");
  std::ostringstream log;
  OmniCameraNode node(bus, config, &log);
  EXPECT_EQ(node.Run(0), OmniCameraNode::StopReason::kEndOfSource);
  HandleAll(bus);
  EXPECT_EQ(node.published(), 3);
  EXPECT_EQ(node.read_failures(), 1);
  EXPECT_EQ(node.size_mismatches(), 1);
  ASSERT_EQ(out.frames.size(), 3u);
  EXPECT_NE(log.str().find("b.png"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("32x32, expected 64x48"), std::string::npos) << log.str();
  // PNG frames decode to the images exactly.
  EXPECT_EQ(cv::norm(DecodeCompressed(out.frames[1]), TestImage(2), cv::NORM_INF), 0);
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("1 unreadable, 1 wrong size"), std::string::npos) << report.str();
}

TEST(OmniCameraNode, LoopsAFolderUntilMaxFrames) {
  ScratchDir dir;
  ASSERT_TRUE(cv::imwrite(dir / "0.png", TestImage(0)));
  ASSERT_TRUE(cv::imwrite(dir / "1.png", TestImage(1)));
  glue::Bus bus("memq://");
  Collector out(bus, "F3_OMNI_FRAME");
  OmniCameraNode node(bus, ParseConfig(ConfigText("folder:" + dir.path().string(), "rgb8", true), "F3_"));
  EXPECT_EQ(node.Run(5), OmniCameraNode::StopReason::kMaxFrames);
  HandleAll(bus);
  ASSERT_EQ(out.frames.size(), 5u);
  // 0,1,0,1,0: gray images published as rgb8 have R = G = B = the gray value.
  for (int i = 0; i < 5; ++i) EXPECT_EQ(out.frames[i].data[0], TestImage(i % 2).at<uint8_t>(0, 0)) << i;
  EXPECT_EQ(out.frames[0].row_stride, 3 * 64);
}

TEST(OmniCameraNode, PacesFilesAtRateHz) {
  ScratchDir dir;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(cv::imwrite(dir / (std::to_string(i) + ".png"), TestImage(i)));
  glue::Bus bus("memq://");
  OmniCameraNode node(bus, ParseConfig(ConfigText("folder:" + dir.path().string(), "gray8", false, 20), "F4_"));
  const auto start = std::chrono::steady_clock::now();
  node.Run(0);
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(node.published(), 3);
  EXPECT_GE(elapsed_s, 0.095);  // frames at 0, 50 and 100 ms
  EXPECT_LT(elapsed_s, 2.0);
}

TEST(OmniCameraNode, ConfiguredSizeRejectsOtherFrames) {
  ScratchDir dir;
  ASSERT_TRUE(cv::imwrite(dir / "a.png", TestImage(0, 64, 48)));
  ASSERT_TRUE(cv::imwrite(dir / "b.png", TestImage(1, 80, 60)));
  glue::Bus bus("memq://");
  OmniCameraNode node(bus, ParseConfig(ConfigText("folder:" + dir.path().string(), "gray8", false, 0, 80, 60)));
  node.Run(0);
  EXPECT_EQ(node.published(), 1);
  EXPECT_EQ(node.size_mismatches(), 1);
}

TEST(OmniCameraNode, AFolderWithNoUsableImageIsAnErrorNotAnEndlessLoop) {
  ScratchDir dir;
  snapnav::testing::WriteTextFile(dir / "a.png", "junk");
  snapnav::testing::WriteTextFile(dir / "b.jpg", "junk");
  glue::Bus bus("memq://");
  OmniCameraNode node(bus, ParseConfig(ConfigText("folder:" + dir.path().string(), "gray8", true)));
  try {
    node.Run(0);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("2 frames in a row unusable"), std::string::npos) << e.what();
  }
  EXPECT_EQ(node.published(), 0);
}

std::string OpenError(const std::string& source) {
  glue::Bus bus("memq://");
  try {
    OmniCameraNode node(bus, ParseConfig(ConfigText(source, "gray8", false)));
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(OmniCameraNode, MissingSourcesAreNamedExactly) {
  ScratchDir dir;
  EXPECT_EQ(OpenError("folder:" + dir.path().string()),
            "image folder " + dir.path().string() + " contains no images (*.png, *.jpg, *.jpeg, *.bmp, *.pgm)");
  EXPECT_EQ(OpenError("folder:" + (dir / "nope")),
            "cannot open image folder " + (dir / "nope") + " (folder does not exist)");
  EXPECT_EQ(OpenError("file:" + (dir / "nope.avi")),
            "cannot open video file " + (dir / "nope.avi") + " (file does not exist)");
  snapnav::testing::WriteTextFile(dir / "fake.avi", "not a video");
  EXPECT_NE(OpenError("file:" + (dir / "fake.avi")).find("cannot open video file " + (dir / "fake.avi")),
            std::string::npos);
  if (!std::filesystem::exists("/dev/video57")) {
    EXPECT_EQ(OpenError("device:57"), "cannot open camera device 57 (/dev/video57 does not exist)");
  }
}

TEST(OmniCameraNode, PublishesAVideoFileAndLoopsIt) {
  ScratchDir dir;
  const std::string video = dir / "clip.avi";
  {
    cv::VideoWriter writer(video, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10,
                           cv::Size(64, 48), true);
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 8; ++i) {
      cv::Mat bgr;
      cv::cvtColor(TestImage(i), bgr, cv::COLOR_GRAY2BGR);
      writer.write(bgr);
    }
  }
  {
    glue::Bus bus("memq://");
    Collector out(bus, "V1_OMNI_FRAME");
    OmniCameraNode node(bus, ParseConfig(ConfigText("file:" + video, "jpeg", false), "V1_"));
    EXPECT_EQ(node.Run(0), OmniCameraNode::StopReason::kEndOfSource);
    HandleAll(bus);
    ASSERT_EQ(out.frames.size(), 8u);
    for (int i = 0; i < 8; ++i) {
      const cv::Mat back = DecodeCompressed(out.frames[i]);
      ASSERT_EQ(back.size(), cv::Size(64, 48));
      cv::Mat gray;
      cv::cvtColor(back, gray, cv::COLOR_BGR2GRAY);
      // Two JPEG generations: close to the written image, far from the neighbouring ones.
      const double err = cv::norm(gray, TestImage(i), cv::NORM_L1) / (64.0 * 48);
      EXPECT_LT(err, 6.0) << i;
      EXPECT_GT(cv::norm(gray, TestImage((i + 1) % 8), cv::NORM_L1) / (64.0 * 48), 3 * err + 5) << i;
    }
  }
  {
    glue::Bus bus("memq://");
    OmniCameraNode node(bus, ParseConfig(ConfigText("file:" + video, "gray8", true), "V2_"));
    EXPECT_EQ(node.Run(19), OmniCameraNode::StopReason::kMaxFrames);
    EXPECT_EQ(node.published(), 19);
  }
}

// --- the binary ---

TEST(OmniCameraBinary, HelpAndMissingDevice) {
  const auto help = snapnav::testing::RunCommand(snapnav::testing::BinDir() + "/omni-camera --help");
  EXPECT_EQ(help.exit_status, 0);
  EXPECT_NE(help.output.find("--max-frames"), std::string::npos);
  if (std::filesystem::exists("/dev/video0")) GTEST_SKIP() << "a camera is plugged in";
  const auto r = snapnav::testing::RunCommand(snapnav::testing::BinDir() + "/omni-camera --lcm-url memq://");
  EXPECT_EQ(r.exit_status, 1);
  EXPECT_NE(r.output.find("omni-camera: error: cannot open camera device 0 (/dev/video0 does not exist)"),
            std::string::npos)
      << r.output;
}

// MRPT's sample video through the real binary into an LCM log, read back with lcm::LogFile.
TEST(OmniCameraBinary, MrptSampleVideoToLogFile) {
  const std::string video = "/usr/share/mrpt/datasets/dummy_video.avi";
  if (!std::filesystem::exists(video)) GTEST_SKIP() << video << " not installed (package mrpt-common)";
  ScratchDir dir;
  snapnav::testing::WriteTextFile(dir / "cam.ini", ConfigText("file:" + video, "png", false));
  const std::string log = dir / "frames.lcmlog";
  const auto r =
      snapnav::testing::RunCommand(snapnav::testing::BinDir() + "/omni-camera --config " + (dir / "cam.ini") +
                                   " --channel-prefix T_ --lcm-url 'file://" + log + "?mode=w' --max-frames 7");
  ASSERT_EQ(r.exit_status, 0) << r.output;
  EXPECT_NE(r.output.find("published 7 frames on T_OMNI_FRAME"), std::string::npos) << r.output;
  lcm::LogFile file(log, "r");
  ASSERT_TRUE(file.good());
  int frames = 0;
  int64_t last_utime = 0;
  while (const lcm::LogEvent* event = file.readNextEvent()) {
    EXPECT_EQ(event->channel, "T_OMNI_FRAME");
    std::string error;
    const auto f = glue::Decode<omni_frame_t>(event->data, event->datalen, &error);
    ASSERT_TRUE(f) << error;
    EXPECT_EQ(f->width, 320);
    EXPECT_EQ(f->height, 240);
    EXPECT_EQ(f->encoding, omni_frame_t::PNG);
    EXPECT_FLOAT_EQ(f->mirror_outer_radius_px, 22.5f);
    EXPECT_GE(f->utime, last_utime);
    last_utime = f->utime;
    EXPECT_EQ(DecodeCompressed(*f).size(), cv::Size(320, 240));
    ++frames;
  }
  EXPECT_EQ(frames, 7);
}

// SIGINT stops a looping, paced source; the process reports what it published and exits 0.
TEST(OmniCameraBinary, SigintStopsCleanly) {
  ScratchDir dir;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(cv::imwrite(dir / (std::to_string(i) + ".png"), TestImage(i)));
  snapnav::testing::WriteTextFile(dir / "cam.ini", ConfigText("folder:" + dir.path().string(), "gray8", true, 50));
  // A background job of a non-interactive shell starts with SIGINT ignored until the program installs
  // its handler, so the signal is sent only once the camera has started capturing (slow on a loaded
  // machine), not after a fixed delay.
  const std::string err = dir / "err.txt";
  const std::string command = snapnav::testing::BinDir() + "/omni-camera --config " + (dir / "cam.ini") +
                              " --lcm-url memq:// 2>" + err + " & pid=$!; for i in $(seq 600); do grep -q " +
                              "\"capturing from\" " + err + " && break; sleep 0.1; done; sleep 0.7; kill -INT $pid; " +
                              "wait $pid; echo \"rc=$?\"; cat " + err;
  const auto r = snapnav::testing::RunCommand("sh -c '" + command + "'");
  EXPECT_NE(r.output.find("rc=0"), std::string::npos) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("published ([0-9]+) frames on OMNI_FRAME"))) << r.output;
  EXPECT_GE(std::stoi(m[1]), 5) << r.output;  // ~35 at 50 Hz in 0.7 s
  EXPECT_NE(r.output.find("OMNI_FRAME               received 0, published"), std::string::npos) << r.output;
}

// Every number of the shipped omni_camera.ini made negative or NaN: each error names the file, the line
// and the key.
TEST(OmniCameraConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(kShippedConfig,
                                                [](const glue::IniFile& ini) { OmniCameraConfig::FromIni(ini, ""); }),
            0);
}

}  // namespace
}  // namespace snapnav::processes
