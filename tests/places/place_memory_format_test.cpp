// The place-cell memory's binary form: round trip, and clear errors on corrupt input.

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "snapnav/nav/places/place_cells.hpp"

namespace snapnav::nav {
namespace {

PlaceCellMemory SmallMemory() {
  PlaceViewOptions options;
  PanoramaModel panorama;
  PlaceCellMemory memory(options, panorama);
  cv::RNG rng(3);
  for (int i = 0; i < 3; ++i) {
    cv::Mat pano(panorama.height_px, panorama.width_px, CV_8UC1);
    rng.fill(pano, cv::RNG::UNIFORM, 0, 255);
    cv::GaussianBlur(pano, pano, cv::Size(0, 0), 2.0);
    memory.Add(Pose2{0.5 * i, -0.25 * i, 0.1 * i}, 1000 + i, MakePlaceView(pano, options));
  }
  return memory;
}

TEST(PlaceMemoryFormat, RoundTripKeepsEverything) {
  const PlaceCellMemory a = SmallMemory();
  ASSERT_GT(a.cell(0).view.landmarks.size(), 10);
  const auto bytes = a.Serialize();
  const PlaceCellMemory b = PlaceCellMemory::Parse(bytes);
  ASSERT_EQ(b.size(), a.size());
  for (int i = 0; i < a.size(); ++i) {
    const auto& x = a.cell(i);
    const auto& y = b.cell(i);
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.utime, y.utime);
    EXPECT_DOUBLE_EQ(x.pose.theta_rad, y.pose.theta_rad);
    ASSERT_EQ(x.view.landmarks.size(), y.view.landmarks.size());
    EXPECT_EQ(x.view.landmarks.descriptors.type(), y.view.landmarks.descriptors.type());
    EXPECT_EQ(cv::norm(x.view.landmarks.descriptors, y.view.landmarks.descriptors, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(x.view.windows, y.view.windows, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(x.view.signature, y.view.signature, cv::NORM_INF), 0);
    EXPECT_EQ(x.view.vlines.size(), y.view.vlines.size());
    EXPECT_FLOAT_EQ(x.view.landmarks.landmarks.back().x_px, y.view.landmarks.landmarks.back().x_px);
  }
  EXPECT_EQ(b.Serialize(), bytes);
}

std::string ParseError(const std::vector<uint8_t>& bytes) {
  try {
    PlaceCellMemory::Parse(bytes);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(PlaceMemoryFormat, CorruptInputIsRejectedWithTheOffset) {
  const auto bytes = SmallMemory().Serialize();
  for (size_t cut : {size_t{0}, size_t{10}, size_t{30}, bytes.size() / 2, bytes.size() - 9, bytes.size() - 1}) {
    const std::string e = ParseError(std::vector<uint8_t>(bytes.begin(), bytes.begin() + cut));
    EXPECT_NE(e.find("at byte"), std::string::npos) << cut << ": " << e;
  }
  auto foreign = bytes;
  foreign[0] = 'X';
  EXPECT_NE(ParseError(foreign).find("not a snapnav place-cell memory"), std::string::npos);
  auto version = bytes;
  version[18] = 99;
  EXPECT_NE(ParseError(version).find("format version 99"), std::string::npos);
  auto flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  EXPECT_FALSE(ParseError(flipped).empty());
  auto absurd = bytes;
  // The cell count sits right after the fixed header: make it huge.
  const size_t count_at = 18 + 4 + 1 + 4 + 4 + 8 + 4 + 4 + 1 + 4 + 1 + 4 + 4 + 8 + 8 + 8 + 4 + 4;
  absurd[count_at + 3] = 0x7f;
  EXPECT_NE(ParseError(absurd).find("cell count"), std::string::npos) << ParseError(absurd);
}

}  // namespace
}  // namespace snapnav::nav
