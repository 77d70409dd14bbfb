// Image-folder importer: images written by the test with OpenCV, plus a positions CSV.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "importer_test_util.hpp"
#include "importers.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::importers {
namespace {

using testing::Errors;
using testing::HasError;
using testing::TempDir;
using testing::VectorSink;

constexpr char kFrames[] = "OMNI_FRAME";
constexpr char kTruth[] = "POSE_GROUND_TRUTH";

// A deterministic pattern, different per seed.
cv::Mat TestImage(int width, int height, int channels, int seed) {
  cv::Mat image(height, width, channels == 1 ? CV_8UC1 : CV_8UC3);
  for (int r = 0; r < height; ++r) {
    auto* row = image.ptr<uint8_t>(r);
    for (int c = 0; c < width * channels; ++c) row[c] = static_cast<uint8_t>((r * 7 + c * seed * 13 + seed) % 256);
  }
  return image;
}

class ImageFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(cv::imwrite(dir_.File("a.png"), TestImage(64, 48, 3, 1)));
    ASSERT_TRUE(cv::imwrite(dir_.File("b.png"), TestImage(32, 16, 1, 2)));
    ASSERT_TRUE(cv::imwrite(dir_.File("c.jpg"), TestImage(40, 30, 3, 3)));
  }
  TempDir dir_;
};

TEST_F(ImageFolder, FramesKeepTheFileBytesAndPosesComeFromTheCsv) {
  testing::WriteFile(dir_.File("positions.csv"),
                     "file,x_m,y_m,heading_rad,utime\n"
                     "a.png,1.0,2.0,0.5,1000000\n"
                     "b.png,1.5,2.5,-0.25,1200000\n"
                     "c.jpg,2.0,3.0,3.0,1400000\n");
  ImageOptions options;
  options.mirror_center_x_px = 32;
  options.mirror_center_y_px = 24;
  options.mirror_inner_radius_px = 5;
  options.mirror_outer_radius_px = 20;
  options.mirror_elevation_inner_rad = -0.5;
  options.mirror_elevation_outer_rad = 0.25;
  VectorSink sink;
  const auto report = ImportImages(dir_.path(), dir_.File("positions.csv"), sink, options);
  ASSERT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.Count(kFrames), 3);
  EXPECT_EQ(report.Count(kTruth), 3);
  EXPECT_EQ(report.synthesized_utimes, 0);

  const auto frames = sink.Decoded<omni_frame_t>(kFrames);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].utime, 1000000);
  EXPECT_EQ(frames[0].kind, omni_frame_t::RAW_OMNI);
  EXPECT_EQ(frames[0].encoding, omni_frame_t::PNG);
  EXPECT_EQ(frames[0].width, 64);
  EXPECT_EQ(frames[0].height, 48);
  EXPECT_EQ(frames[0].row_stride, 0);
  EXPECT_EQ(frames[0].sensor_name, "omni");
  EXPECT_FLOAT_EQ(frames[0].mirror_center_x_px, 32.0f);
  EXPECT_FLOAT_EQ(frames[0].mirror_outer_radius_px, 20.0f);
  EXPECT_FLOAT_EQ(frames[0].mirror_elevation_inner_rad, -0.5f);
  EXPECT_FLOAT_EQ(frames[0].mirror_elevation_outer_rad, 0.25f);
  EXPECT_FLOAT_EQ(frames[0].bearing_col0_rad, 0.0f);
  EXPECT_FLOAT_EQ(frames[0].elevation_top_rad, 0.0f);
  const std::string a = testing::ReadFile(dir_.File("a.png"));
  ASSERT_EQ(frames[0].data_size, static_cast<int32_t>(a.size()));
  EXPECT_EQ(std::string(frames[0].data.begin(), frames[0].data.end()), a);
  EXPECT_EQ(frames[1].width, 32);
  EXPECT_EQ(frames[1].height, 16);
  EXPECT_EQ(frames[2].encoding, omni_frame_t::JPEG);
  EXPECT_EQ(frames[2].width, 40);
  EXPECT_EQ(frames[2].height, 30);
  EXPECT_EQ(std::string(frames[2].data.begin(), frames[2].data.end()), testing::ReadFile(dir_.File("c.jpg")));
  // The bytes decode to the image written.
  const cv::Mat decoded = cv::imdecode(frames[1].data, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(decoded, TestImage(32, 16, 1, 2), cv::NORM_INF), 0.0);

  const auto poses = sink.Decoded<pose_t>(kTruth);
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses[1].utime, 1200000);
  EXPECT_DOUBLE_EQ(poses[1].x_m, 1.5);
  EXPECT_DOUBLE_EQ(poses[1].y_m, 2.5);
  EXPECT_DOUBLE_EQ(poses[1].theta_rad, -0.25);
  EXPECT_EQ(poses[1].estimator, "ground_truth");
}

TEST_F(ImageFolder, PanoramasWithoutUtimeGetSynthesizedTimes) {
  testing::WriteFile(dir_.File("list.csv"),
                     "heading_rad, x_m, y_m, file, note\n"
                     "0, 0, 0, a.png, start\n"
                     "0, 1, 0, b.png, \n");
  ImageOptions options;
  options.panorama = true;
  options.bearing_col0_rad = 0.5;
  options.elevation_top_rad = 0.3;
  options.elevation_bottom_rad = -0.2;
  options.rate_hz = 4;
  options.channels = ChannelNames::WithPrefix("SIM_");
  VectorSink sink;
  const auto report = ImportImages(dir_.path(), dir_.File("list.csv"), sink, options);
  ASSERT_TRUE(report.ok()) << Errors(report);
  const auto frames = sink.Decoded<omni_frame_t>("SIM_OMNI_FRAME");
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].kind, omni_frame_t::PANORAMA);
  EXPECT_FLOAT_EQ(frames[0].bearing_col0_rad, 0.5f);
  EXPECT_FLOAT_EQ(frames[0].elevation_top_rad, 0.3f);
  EXPECT_FLOAT_EQ(frames[0].elevation_bottom_rad, -0.2f);
  EXPECT_FLOAT_EQ(frames[0].mirror_center_x_px, 0.0f);
  EXPECT_FLOAT_EQ(frames[0].mirror_elevation_outer_rad, 0.0f);
  EXPECT_EQ(frames[1].utime - frames[0].utime, 250000);
  EXPECT_EQ(report.synthesized_utimes, 4);  // 2 frames, 2 poses
  EXPECT_EQ(sink.Decoded<pose_t>("SIM_POSE_GROUND_TRUTH").size(), 2u);
}

TEST_F(ImageFolder, BadRowsAreReportedWithTheirLineAndTheRestImported) {
  const std::string png = testing::ReadFile(dir_.File("a.png"));
  testing::WriteFile(dir_.File("cut.png"), png.substr(0, png.size() / 2));
  testing::WriteFile(dir_.File("text.png"), "not an image");
  testing::WriteFile(dir_.File("positions.csv"),
                     "file,x_m,y_m,heading_rad,utime\n"
                     "a.png,1,2,0,1000\n"        // 2 ok
                     "missing.png,1,2,0,2000\n"  // 3 no such file
                     "cut.png,1,2,0,3000\n"      // 4 truncated PNG
                     "text.png,1,2,0,4000\n"     // 5 not an image
                     "b.png,one,2,0,5000\n"      // 6 not a number
                     "b.png,1,2,0\n"             // 7 field missing
                     "b.png,1,2,0,-1\n"          // 8 negative utime
                     "# a comment\n"
                     "\n"
                     "c.jpg,1,2,0,9000\n");  // 11 ok
  VectorSink sink;
  const std::string csv = dir_.File("positions.csv");
  const auto report = ImportImages(dir_.path(), csv, sink, {});
  EXPECT_EQ(report.Count(kFrames), 2);
  EXPECT_EQ(report.error_count, 6) << Errors(report);
  for (int line : {3, 4, 5, 6, 7, 8}) {
    EXPECT_TRUE(HasError(report, csv + ":" + std::to_string(line) + ": ")) << line << "\n" << Errors(report);
  }
  EXPECT_TRUE(HasError(report, csv + ":4: image '" + dir_.File("cut.png") + "' cannot be decoded")) << Errors(report);
  EXPECT_TRUE(HasError(report, "neither PNG nor JPEG")) << Errors(report);
}

TEST_F(ImageFolder, CsvWithoutRequiredColumnOrMissingCsv) {
  testing::WriteFile(dir_.File("positions.csv"), "file,x_m,heading_rad\na.png,1,0\n");
  VectorSink sink;
  auto report = ImportImages(dir_.path(), dir_.File("positions.csv"), sink, {});
  EXPECT_TRUE(HasError(report, "positions.csv:1: header lacks column 'y_m'")) << Errors(report);
  report = ImportImages(dir_.path(), dir_.File("none.csv"), sink, {});
  EXPECT_TRUE(HasError(report, "none.csv: cannot open")) << Errors(report);
  EXPECT_TRUE(sink.events.empty());

  ImageOptions bad;
  bad.panorama = true;
  bad.mirror_center_x_px = 3;
  EXPECT_THROW(ImportImages(dir_.path(), dir_.File("positions.csv"), sink, bad), std::invalid_argument);
  ImageOptions raw_with_panorama_geometry;
  raw_with_panorama_geometry.elevation_top_rad = 0.1;
  EXPECT_THROW(ImportImages(dir_.path(), dir_.File("positions.csv"), sink, raw_with_panorama_geometry),
               std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::importers
