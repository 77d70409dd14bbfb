// Fusing several frames of a still view: persistent landmarks and the median panorama, on
// synthetic landmark sets and images with known static and moving parts.
#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/landmarks/view_fusion.hpp"

namespace snapnav::nav {
namespace {

constexpr int kWidth = 720, kHeight = 120;

LandmarkSet EmptySet(LandmarkMethod method = LandmarkMethod::kSift) {
  LandmarkSet s;
  s.method = method;
  s.width_px = kWidth;
  s.height_px = kHeight;
  return s;
}

void Add(LandmarkSet* s, float x, float y, const cv::Mat& descriptor) {
  s->landmarks.push_back({x, y, 1.0f, 8.0f, 0.0f});
  if (s->descriptors.empty()) {
    s->descriptors = descriptor.clone();
  } else {
    cv::vconcat(s->descriptors, descriptor, s->descriptors);
  }
}

// Nine frames: twenty static landmarks, each hidden in three of the frames (a person in front),
// plus five walkers per frame at new places with new descriptors. At min_fraction 0.6 (six of
// nine) exactly the static ones are kept, with the number of frames they were found in; the
// walkers never are, whatever their descriptors.
TEST(PersistentLandmarks, KeepsStaticLandmarksAndDropsWalkers) {
  cv::RNG rng(3);
  cv::Mat statics(20, 128, CV_32F);
  rng.fill(statics, cv::RNG::UNIFORM, 0.0f, 100.0f);
  std::vector<cv::Point2f> where;
  for (int i = 0; i < 20; ++i) where.push_back({18.0f + 36 * i, static_cast<float>(20 + (i * 7) % 80)});
  std::vector<LandmarkSet> frames;
  for (int k = 0; k < 9; ++k) {
    LandmarkSet s = EmptySet();
    for (int w = 0; w < 5; ++w) {
      cv::Mat d(1, 128, CV_32F);
      rng.fill(d, cv::RNG::UNIFORM, 0.0f, 100.0f);
      Add(&s, rng.uniform(0.0f, 720.0f), rng.uniform(0.0f, 120.0f), d);
    }
    for (int i = 0; i < 20; ++i) {
      if ((i + k) % 3 == 0) continue;  // hidden in three of the nine frames
      cv::Mat d = statics.row(i) + rng.uniform(-1.0f, 1.0f);  // a little sensor noise
      Add(&s, where[i].x + rng.uniform(-0.5f, 0.5f), where[i].y + rng.uniform(-0.5f, 0.5f), d);
    }
    frames.push_back(s);
  }
  PersistenceOptions o;
  o.min_fraction = 0.6;
  std::vector<int> seen;
  const LandmarkSet fused = PersistentLandmarks(frames, o, &seen);
  ASSERT_EQ(fused.size(), 20);
  ASSERT_EQ(fused.descriptors.rows, 20);
  ASSERT_EQ(seen.size(), 20u);
  for (int j = 0; j < fused.size(); ++j) {
    EXPECT_EQ(seen[j], 6);
    double best = 1e9;
    for (const auto& p : where) best = std::min<double>(best, std::hypot(fused.landmarks[j].x_px - p.x, fused.landmarks[j].y_px - p.y));
    EXPECT_LT(best, 1.0);
  }
  // Asking for seven of nine keeps none of them.
  o.min_fraction = 0.75;
  EXPECT_EQ(PersistentLandmarks(frames, o).size(), 0);
}

// A walker whose descriptor stays the same (the same coat) but who moves more than the gate
// between frames is not persistent; a landmark at the seam (column 719 vs 1) is.
TEST(PersistentLandmarks, PositionGateAndSeam) {
  cv::Mat coat(1, 64, CV_32F, cv::Scalar(3.0f)), post(1, 64, CV_32F);
  cv::randu(post, 0.0f, 10.0f);
  std::vector<LandmarkSet> frames;
  for (int k = 0; k < 4; ++k) {
    LandmarkSet s = EmptySet(LandmarkMethod::kSurf);
    Add(&s, 100.0f + 20 * k, 60.0f, coat);
    Add(&s, k % 2 ? 719.5f : 0.5f, 60.0f, post);
    frames.push_back(s);
  }
  PersistenceOptions o;
  o.min_fraction = 0.5;
  const LandmarkSet fused = PersistentLandmarks(frames, o);
  ASSERT_EQ(fused.size(), 1);
  EXPECT_LT(std::min(fused.landmarks[0].x_px, 720.0f - fused.landmarks[0].x_px), 1.0f);
}

// Vertical lines: a line's middle row moves when a person hides part of it; only columns count.
TEST(PersistentLandmarks, VerticalLinesCompareColumnsOnly) {
  cv::Mat d(1, 48, CV_32F);
  cv::randu(d, 0.0f, 1.0f);
  std::vector<LandmarkSet> frames;
  for (int k = 0; k < 3; ++k) {
    LandmarkSet s = EmptySet(LandmarkMethod::kVline);
    Add(&s, 300.0f, 40.0f + 15 * k, d);
    frames.push_back(s);
  }
  PersistenceOptions o;
  o.min_fraction = 1.0;
  EXPECT_EQ(PersistentLandmarks(frames, o).size(), 1);
  for (auto& f : frames) f.method = LandmarkMethod::kSift;
  EXPECT_EQ(PersistentLandmarks(frames, o).size(), 0);
}

TEST(PersistentLandmarks, OneFrameAndBadInput) {
  cv::Mat d(1, 128, CV_32F, cv::Scalar(1.0f));
  LandmarkSet a = EmptySet();
  Add(&a, 10, 10, d);
  EXPECT_EQ(PersistentLandmarks({a}, {}).size(), 1);
  EXPECT_EQ(PersistentLandmarks({EmptySet(), EmptySet()}, {}).size(), 0);
  EXPECT_THROW(PersistentLandmarks({}, {}), std::invalid_argument);
  LandmarkSet b = a;
  b.method = LandmarkMethod::kSurf;
  EXPECT_THROW(PersistentLandmarks({a, b}, {}), std::invalid_argument);
  LandmarkSet c = a;
  c.width_px = 360;
  EXPECT_THROW(PersistentLandmarks({a, c}, {}), std::invalid_argument);
  PersistenceOptions bad;
  bad.min_fraction = 0;
  EXPECT_THROW(PersistentLandmarks({a, a}, bad), std::invalid_argument);
}

// The median of five frames in which a block (a person) covers each pixel at most twice is the
// background exactly; where it stands in three of five it stays.
TEST(MedianImage, RemovesWhatCoversAPixelInFewerThanHalfTheFrames) {
  cv::Mat background(kHeight, kWidth, CV_8UC3);
  cv::randu(background, 0, 255);
  std::vector<cv::Mat> frames;
  for (int k = 0; k < 5; ++k) {
    cv::Mat f = background.clone();
    cv::rectangle(f, cv::Rect(100 + 40 * k, 10, 60, 100), cv::Scalar(255, 0, 255), cv::FILLED);  // walks right
    if (k < 3) cv::rectangle(f, cv::Rect(600, 10, 40, 100), cv::Scalar(0, 255, 0), cv::FILLED);  // stands for three
    frames.push_back(f);
  }
  const cv::Mat m = MedianImage(frames);
  ASSERT_EQ(m.size(), background.size());
  EXPECT_EQ(cv::norm(m(cv::Rect(0, 0, 500, kHeight)), background(cv::Rect(0, 0, 500, kHeight)), cv::NORM_INF), 0);
  EXPECT_EQ(m.at<cv::Vec3b>(50, 620), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(cv::norm(MedianImage({background}), background, cv::NORM_INF), 0);
  EXPECT_THROW(MedianImage({}), std::invalid_argument);
  EXPECT_THROW(MedianImage({background, cv::Mat(10, 10, CV_8UC3)}), std::invalid_argument);
  EXPECT_THROW(MedianImage({cv::Mat(10, 10, CV_32F)}), std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::nav
