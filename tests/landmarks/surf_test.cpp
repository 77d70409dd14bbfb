// SURF (libnav/surf): integral image, blob position and size (with sub-sample interpolation),
// invariance to rotation and scale (ratio-test matches checked against the known transform),
// U-SURF, options and bad input. Synthetic images only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/landmarks/surf.hpp"

namespace snapnav::nav {
namespace {

// A bright Gaussian blob of standard deviation sigma_px at (cx, cy) on a dark image
// (or a dark one on a bright image).
cv::Mat Blob(int size, double cx, double cy, double sigma_px, bool bright = true) {
  cv::Mat image(size, size, CV_8UC1);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double g = std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * sigma_px * sigma_px));
      image.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(bright ? 30 + 200 * g : 230 - 200 * g);
    }
  }
  return image;
}

// A procedural texture: random filled ellipses and rectangles of random grey levels, smoothed.
cv::Mat Texture(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0, 1);
  cv::Mat image(height, width, CV_8UC1, cv::Scalar(128));
  for (int k = 0; k < width * height / 250; ++k) {
    const cv::Point center(static_cast<int>(uni(rng) * width), static_cast<int>(uni(rng) * height));
    const int grey = static_cast<int>(uni(rng) * 255);
    const int a = 3 + static_cast<int>(uni(rng) * 18), b = 3 + static_cast<int>(uni(rng) * 18);
    if (uni(rng) < 0.5) {
      cv::ellipse(image, center, cv::Size(a, b), uni(rng) * 180, 0, 360, cv::Scalar(grey), cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(image, cv::Rect(center.x - a, center.y - b, 2 * a, 2 * b), cv::Scalar(grey), cv::FILLED);
    }
  }
  cv::GaussianBlur(image, image, cv::Size(), 1.0);
  return image;
}

cv::Point2f Apply(const cv::Mat& affine, float x, float y) {
  return {static_cast<float>(affine.at<double>(0, 0) * x + affine.at<double>(0, 1) * y + affine.at<double>(0, 2)),
          static_cast<float>(affine.at<double>(1, 0) * x + affine.at<double>(1, 1) * y + affine.at<double>(1, 2))};
}

struct MatchStats {
  int matches = 0, correct = 0;
  double precision() const { return matches > 0 ? static_cast<double>(correct) / matches : 0.0; }
  std::vector<std::pair<int, int>> correct_pairs;  // (a, b) indices of the correct matches
};

// Brute-force nearest neighbour of each landmark of `a` in `b` with Lowe's ratio test (0.8); a
// match is correct when `affine` takes a's position within 3 px of b's. Only a-landmarks that
// land at least `margin_px` inside b count.
MatchStats MatchWithTruth(const LandmarkSet& a, const LandmarkSet& b, const cv::Mat& affine, float margin_px) {
  MatchStats stats;
  for (int i = 0; i < a.size(); ++i) {
    const cv::Point2f truth = Apply(affine, a.landmarks[i].x_px, a.landmarks[i].y_px);
    if (truth.x < margin_px || truth.y < margin_px || truth.x > b.width_px - 1 - margin_px ||
        truth.y > b.height_px - 1 - margin_px)
      continue;
    double best = 1e30, second = 1e30;
    int best_j = -1;
    for (int j = 0; j < b.size(); ++j) {
      const double d = cv::norm(a.descriptors.row(i), b.descriptors.row(j), cv::NORM_L2);
      if (d < best) {
        second = best, best = d, best_j = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j < 0 || !(best < 0.8 * second)) continue;
    ++stats.matches;
    const Landmark& m = b.landmarks[best_j];
    if (std::hypot(m.x_px - truth.x, m.y_px - truth.y) <= 3.0) {
      ++stats.correct;
      stats.correct_pairs.push_back({i, best_j});
    }
  }
  return stats;
}

// The image turned by angle_deg (counter-clockwise on screen) about its centre, and the transform.
cv::Mat Rotate(const cv::Mat& image, double angle_deg, cv::Mat* affine) {
  const cv::Point2f center((image.cols - 1) * 0.5f, (image.rows - 1) * 0.5f);
  *affine = cv::getRotationMatrix2D(center, angle_deg, 1.0);
  cv::Mat out;
  cv::warpAffine(image, out, *affine, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  return out;
}

TEST(SurfOptions, ValidateRejectsBadOptions) {
  EXPECT_NO_THROW(SurfOptions{}.Validate());
  const auto rejects = [](auto change) {
    SurfOptions o;
    change(o);
    EXPECT_THROW(o.Validate(), std::invalid_argument);
  };
  rejects([](SurfOptions& o) { o.hessian_threshold = -1; });
  rejects([](SurfOptions& o) { o.hessian_threshold = std::nan(""); });
  rejects([](SurfOptions& o) { o.octaves = 0; });
  rejects([](SurfOptions& o) { o.octaves = 9; });
  rejects([](SurfOptions& o) { o.intervals = 2; });
  rejects([](SurfOptions& o) { o.init_sample = 0; });
  rejects([](SurfOptions& o) { o.max_keypoints = -1; });
  // DetectSurf checks them too.
  SurfOptions bad;
  bad.intervals = 1;
  EXPECT_THROW(DetectSurf(Blob(64, 32, 32, 3), bad), std::invalid_argument);
}

TEST(SurfIntegralImage, BoxSumsMatchBruteForce) {
  const cv::Mat image = Texture(37, 23, 5);
  const IntegralImage ii(image);
  ASSERT_EQ(ii.width(), 37);
  ASSERT_EQ(ii.height(), 23);
  std::mt19937 rng(1);
  for (int k = 0; k < 200; ++k) {
    int x0 = static_cast<int>(rng() % 38), x1 = static_cast<int>(rng() % 38);
    int y0 = static_cast<int>(rng() % 24), y1 = static_cast<int>(rng() % 24);
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    const int expected = static_cast<int>(cv::sum(image(cv::Rect(x0, y0, x1 - x0, y1 - y0)))[0]);
    EXPECT_EQ(ii.BoxSum(x0, y0, x1, y1), expected);
    // Clipping: a box reaching outside sums the part inside.
    const int cx0 = std::max(x0 - 10, 0), cy0 = std::max(y0 - 10, 0);
    const int clipped = static_cast<int>(cv::sum(image(cv::Rect(cx0, cy0, x1 - cx0, 23 - cy0)))[0]);
    EXPECT_EQ(ii.ClippedBoxSum(x0 - 10, y0 - 10, x1, y1 + 50), clipped);
  }
  // Sums of a large bright image stay exact (entries wrap modulo 2^32, box sums do not).
  const cv::Mat white(3000, 3000, CV_8UC1, cv::Scalar(255));
  const IntegralImage big(white);
  EXPECT_EQ(big.BoxSum(2900, 2900, 3000, 3000), 255 * 100 * 100);
}

TEST(SurfDetect, BadInputThrows) {
  SurfOptions o;
  EXPECT_THROW(DetectSurf(cv::Mat(), o), std::invalid_argument);
  EXPECT_THROW(DetectSurf(cv::Mat(64, 64, CV_8UC3, cv::Scalar::all(100)), o), std::invalid_argument);
  EXPECT_THROW(DetectSurf(cv::Mat(64, 64, CV_32FC1, cv::Scalar(0.5)), o), std::invalid_argument);
  EXPECT_THROW(IntegralImage(cv::Mat(64, 64, CV_16UC1, cv::Scalar(0))), std::invalid_argument);
  std::vector<Landmark> bad(1);
  bad[0].scale_px = 0;
  EXPECT_THROW(DescribeSurf(Blob(64, 32, 32, 3), &bad, o), std::invalid_argument);
}

TEST(SurfDetect, ConstantAndTinyImagesGiveEmptySets) {
  SurfOptions o;
  o.hessian_threshold = 0;  // even at threshold 0: no response at all
  for (const cv::Mat& image : {cv::Mat(120, 720, CV_8UC1, cv::Scalar(0)), cv::Mat(120, 720, CV_8UC1, cv::Scalar(255)),
                               cv::Mat(5, 5, CV_8UC1, cv::Scalar(17)), cv::Mat(1, 1, CV_8UC1, cv::Scalar(3))}) {
    const LandmarkSet set = DetectSurf(image, o);
    EXPECT_EQ(set.method, LandmarkMethod::kSurf);
    EXPECT_EQ(set.width_px, image.cols);
    EXPECT_EQ(set.height_px, image.rows);
    EXPECT_TRUE(set.empty());
    EXPECT_TRUE(set.descriptors.empty());
  }
  // Structure smaller than the smallest filter fits: nothing either, and no crash.
  EXPECT_TRUE(DetectSurf(Texture(8, 8, 2), o).empty());
}

TEST(SurfDetect, BlobFoundAtItsCentreWithAScaleThatGrowsWithIt) {
  // The smallest size with a maximum (L = 15, the second filter) finds blobs of sigma >= ~2.7 px.
  const double cx = 80.3, cy = 71.6;
  float previous_scale = 0;
  std::vector<double> size_per_sigma;
  for (const double sigma : {3.0, 4.5, 6.5, 9.0}) {
    std::vector<int8_t> signs;
    const LandmarkSet set = DetectSurf(Blob(160, cx, cy, sigma), SurfOptions{}, &signs);
    ASSERT_FALSE(set.empty()) << "sigma " << sigma;
    ASSERT_EQ(signs.size(), set.landmarks.size());
    const Landmark& kp = set.landmarks.front();  // the strongest
    EXPECT_NEAR(kp.x_px, cx, 1.5) << "sigma " << sigma;
    EXPECT_NEAR(kp.y_px, cy, 1.5) << "sigma " << sigma;
    EXPECT_GT(kp.strength, 0);
    EXPECT_GT(kp.scale_px, previous_scale * 1.2f) << "sigma " << sigma;
    EXPECT_EQ(signs.front(), -1) << "a bright blob has a negative Laplacian";
    EXPECT_GE(kp.angle_deg, 0);
    EXPECT_LT(kp.angle_deg, 360);
    EXPECT_NEAR(cv::norm(set.descriptors.row(0)), 1.0, 1e-4);
    previous_scale = kp.scale_px;
    size_per_sigma.push_back(kp.scale_px / sigma);
  }
  // The size is proportional to the blob's sigma (L ~ 5.5 sigma: s = 1.2 L / 9 ~ 0.73 sigma).
  for (const double r : size_per_sigma) {
    EXPECT_GT(r, 4.5);
    EXPECT_LT(r, 6.5);
  }
  std::vector<int8_t> signs;
  const LandmarkSet dark = DetectSurf(Blob(160, cx, cy, 3.0, false), SurfOptions{}, &signs);
  ASSERT_FALSE(dark.empty());
  EXPECT_NEAR(dark.landmarks.front().x_px, cx, 1.5);
  EXPECT_EQ(signs.front(), 1) << "a dark blob has a positive Laplacian";
}

// Interpolation: positions between the samples (also exactly midway, where two samples tie, and
// in the third octave, sampled every 4 px) and sizes between the filter sizes.
TEST(SurfDetect, SubPixelPositionsAndContinuousSizes) {
  for (const double sigma : {3.0, 9.0}) {
    for (int k = 0; k <= 8; ++k) {
      const double cx = 80 + 0.25 * k, cy = 70.6;
      const LandmarkSet set = DetectSurf(Blob(160, cx, cy, sigma), SurfOptions{});
      ASSERT_FALSE(set.empty()) << "sigma " << sigma << " at x " << cx;
      EXPECT_NEAR(set.landmarks.front().x_px, cx, 0.2) << "sigma " << sigma;
      EXPECT_NEAR(set.landmarks.front().y_px, cy, 0.2) << "sigma " << sigma;
    }
  }
  for (double sigma = 3.0; sigma <= 12.0; sigma += 0.5) {
    const LandmarkSet set = DetectSurf(Blob(200, 100.2, 99.7, sigma), SurfOptions{});
    ASSERT_FALSE(set.empty()) << "sigma " << sigma;
    EXPECT_NEAR(set.landmarks.front().scale_px / sigma, 5.5, 0.5) << "sigma " << sigma;
  }
}

TEST(SurfDetect, StrongestFirstAndMaxKeypoints) {
  const cv::Mat image = Texture(320, 240, 3);
  const LandmarkSet all = DetectSurf(image, SurfOptions{});
  ASSERT_GT(all.size(), 50);
  for (int k = 1; k < all.size(); ++k) EXPECT_GE(all.landmarks[k - 1].strength, all.landmarks[k].strength);
  for (const Landmark& kp : all.landmarks) EXPECT_GE(kp.strength, 100);
  SurfOptions o;
  o.max_keypoints = 20;
  const LandmarkSet top = DetectSurf(image, o);
  ASSERT_EQ(top.size(), 20);
  EXPECT_EQ(top.descriptors.rows, 20);
  EXPECT_EQ(top.descriptors.cols, kSurfDescriptorSize);
  for (int k = 0; k < 20; ++k) EXPECT_EQ(top.landmarks[k].x_px, all.landmarks[k].x_px);
  // A higher threshold keeps fewer keypoints.
  o.max_keypoints = 0;
  o.hessian_threshold = 2000;
  EXPECT_LT(DetectSurf(image, o).size(), all.size());
}

TEST(SurfDescribe, KeypointsFromElsewhereGetTheSameDescriptors) {
  const cv::Mat image = Texture(200, 160, 4);
  const LandmarkSet set = DetectSurf(image, SurfOptions{});
  ASSERT_GT(set.size(), 5);
  std::vector<Landmark> keypoints = set.landmarks;
  for (Landmark& kp : keypoints) kp.angle_deg = 123;  // overwritten by the orientation
  const cv::Mat descriptors = DescribeSurf(image, &keypoints, SurfOptions{});
  ASSERT_EQ(descriptors.rows, set.size());
  EXPECT_LT(cv::norm(descriptors, set.descriptors, cv::NORM_INF), 1e-6);
  for (int k = 0; k < set.size(); ++k) EXPECT_FLOAT_EQ(keypoints[k].angle_deg, set.landmarks[k].angle_deg);
  std::vector<Landmark> none;
  EXPECT_TRUE(DescribeSurf(image, &none, SurfOptions{}).empty());
}

// Rotation invariance: the texture turned by 30 and 90 degrees matches the original, and the
// keypoint orientations turn with it (an image turned counter-clockwise on screen turns
// orientations measured in the image frame, y down, by -angle).
TEST(SurfInvariance, RotatedTextureMatchesTheOriginal) {
  const cv::Mat image = Texture(320, 320, 7);
  const LandmarkSet original = DetectSurf(image, SurfOptions{});
  ASSERT_GT(original.size(), 100);
  for (const double angle : {30.0, 90.0}) {
    cv::Mat affine;
    const LandmarkSet turned = DetectSurf(Rotate(image, angle, &affine), SurfOptions{});
    const MatchStats stats = MatchWithTruth(original, turned, affine, 10);
    EXPECT_GE(stats.matches, 50) << angle << " deg";
    EXPECT_GE(stats.precision(), 0.8) << angle << " deg: " << stats.correct << " of " << stats.matches;
    int consistent = 0;
    for (const auto& [a, b] : stats.correct_pairs) {
      const double expected = std::fmod(original.landmarks[a].angle_deg - angle + 720.0, 360.0);
      const double diff = std::abs(std::remainder(turned.landmarks[b].angle_deg - expected, 360.0));
      if (diff < 15) ++consistent;
    }
    EXPECT_GE(consistent, 0.8 * stats.correct) << angle << " deg";
  }
}

// U-SURF: no orientation; it matches a shifted copy, but not one turned by 90 degrees, where
// SURF does.
TEST(SurfInvariance, UprightWorksUnturnedButNotTurned) {
  const cv::Mat image = Texture(320, 320, 9);
  SurfOptions upright;
  upright.upright = true;
  const LandmarkSet original = DetectSurf(image, upright);
  ASSERT_GT(original.size(), 100);
  for (const Landmark& kp : original.landmarks) ASSERT_EQ(kp.angle_deg, -1);

  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 7, 0, 1, -5);
  cv::Mat shifted;
  cv::warpAffine(image, shifted, shift, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  const MatchStats same = MatchWithTruth(original, DetectSurf(shifted, upright), shift, 10);
  EXPECT_GE(same.matches, 50);
  EXPECT_GE(same.precision(), 0.9) << same.correct << " of " << same.matches;

  cv::Mat affine;
  const cv::Mat turned = Rotate(image, 90, &affine);
  const MatchStats upright_turned = MatchWithTruth(original, DetectSurf(turned, upright), affine, 10);
  EXPECT_LT(upright_turned.correct, 0.2 * same.correct)
      << upright_turned.correct << " of " << upright_turned.matches << " upright matches correct at 90 deg";
  const MatchStats oriented =
      MatchWithTruth(DetectSurf(image, SurfOptions{}), DetectSurf(turned, SurfOptions{}), affine, 10);
  EXPECT_GT(oriented.correct, 3 * upright_turned.correct);
}

// Scale: the texture at twice the size still matches (looser bound than rotation).
TEST(SurfInvariance, ScaledTextureMatchesTheOriginal) {
  const cv::Mat image = Texture(240, 240, 11);
  cv::Mat bigger;
  cv::resize(image, bigger, cv::Size(), 2.0, 2.0, cv::INTER_LINEAR);
  const cv::Mat affine = (cv::Mat_<double>(2, 3) << 2, 0, 0.5, 0, 2, 0.5);  // pixel centres
  const MatchStats stats =
      MatchWithTruth(DetectSurf(image, SurfOptions{}), DetectSurf(bigger, SurfOptions{}), affine, 10);
  EXPECT_GE(stats.matches, 30);
  EXPECT_GE(stats.precision(), 0.8) << stats.correct << " of " << stats.matches;
}

}  // namespace
}  // namespace snapnav::nav
