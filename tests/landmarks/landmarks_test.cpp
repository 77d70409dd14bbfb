// Landmark matching, the rotation from matches, the landmark ALVs (unit, weighted, scale,
// top-N), the homer, and SIFT on panoramas (thesis 4.1-4.3).
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {
namespace {

Pose2 P(double x, double y, double theta) { return Pose2{x, y, theta}; }
double DegBetween(double a, double b) { return std::abs(WrapAngle(a - b)) * 180 / M_PI; }

// A world of point landmarks seen from two places: bearings -> panorama columns, keypoint
// scales inversely proportional to distance, and one random descriptor per landmark (with a
// little noise per view).
struct SyntheticWorld {
  PanoramaModel panorama;
  std::vector<Eigen::Vector2d> landmarks;
  cv::Mat descriptors;  // one row per landmark
  explicit SyntheticWorld(int n, uint64_t seed = 3) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> pos(-6, 6);
    descriptors.create(n, 32, CV_32F);
    cv::RNG cvrng(seed);
    cvrng.fill(descriptors, cv::RNG::UNIFORM, 0, 1);
    for (int i = 0; i < n; ++i) {
      Eigen::Vector2d p(pos(rng), pos(rng));
      if (p.norm() < 2.5) p *= 2.5 / std::max(p.norm(), 0.1);  // keep the landmarks off the robots' paths
      landmarks.push_back(p);
    }
  }
  LandmarkSet View(const Pose2& pose, double noise = 0.01, uint64_t seed = 5) const {
    cv::RNG rng(seed);
    LandmarkSet s;
    s.method = LandmarkMethod::kSift;
    s.width_px = panorama.width_px;
    s.height_px = panorama.height_px;
    s.descriptors = descriptors.clone();
    cv::Mat n(descriptors.size(), CV_32F);
    rng.fill(n, cv::RNG::NORMAL, 0, noise);
    s.descriptors += n;
    for (const auto& l : landmarks) {
      const Eigen::Vector2d d = l - Eigen::Vector2d(pose.x_m, pose.y_m);
      const double bearing = WrapAngle(std::atan2(d.y(), d.x()) - pose.theta_rad);
      Landmark lm;
      lm.x_px = static_cast<float>(panorama.ColumnOfBearing(bearing));
      lm.y_px = 60;
      lm.scale_px = static_cast<float>(20.0 / d.norm());
      lm.strength = 1;
      s.landmarks.push_back(lm);
    }
    return s;
  }
};

// The true homing direction in the current robot frame.
double TrueHomeDirection(const Pose2& current, const Eigen::Vector2d& home) {
  const Eigen::Vector2d d = home - Eigen::Vector2d(current.x_m, current.y_m);
  return WrapAngle(std::atan2(d.y(), d.x()) - current.theta_rad);
}

TEST(LandmarkAlv, ScaleCompensationIsExactOnPointLandmarks) {
  SyntheticWorld world(30);
  const Pose2 home = P(0, 0, 0), current = P(1.5, -1.0, 0.4);
  const LandmarkSet h = world.View(home), c = world.View(current);
  const auto matches = MatchLandmarks(h, c, MatchOptions{});
  ASSERT_EQ(matches.size(), 30u);
  for (const auto& m : matches) EXPECT_EQ(m.home, m.current);
  LandmarkAlvOptions alv;
  alv.variant = AlvVariant::kScale;
  const auto e = LandmarkAlvHoming(h, c, matches, 0.4, world.panorama, alv);
  ASSERT_TRUE(e);
  // s_home / s_current = d_current / d_home: each landmark gives (home - current) / d_home.
  EXPECT_LT(DegBetween(e->direction_rad, TrueHomeDirection(current, Eigen::Vector2d(home.x_m, home.y_m))), 1.0);
  EXPECT_EQ(e->bins_used, 30);
}

TEST(LandmarkAlv, UnitAndWeightedPointHomeWithinBound) {
  SyntheticWorld world(40);
  const Pose2 home = P(0, 0, 0);
  for (const Pose2 current : {P(1.0, 0.5, 0.0), P(-1.2, 1.0, -1.0), P(0.3, -1.5, 2.5)}) {
    const LandmarkSet h = world.View(home), c = world.View(current);
    const auto matches = MatchLandmarks(h, c, MatchOptions{});
    for (AlvVariant v : {AlvVariant::kUnit, AlvVariant::kWeighted}) {
      LandmarkAlvOptions alv;
      alv.variant = v;
      const auto e = LandmarkAlvHoming(h, c, matches, current.theta_rad, world.panorama, alv);
      ASSERT_TRUE(e);
      EXPECT_LT(DegBetween(e->direction_rad, TrueHomeDirection(current, Eigen::Vector2d(home.x_m, home.y_m))), 30.0)
          << AlvVariantName(v) << " at " << current.x_m << "," << current.y_m;
    }
  }
}

TEST(LandmarkAlv, WeightedAlvDiscountsBadMatches) {
  // Half of the matches are wrong (random pairs) but have poor scores: the weighted ALV points
  // home far better than the unit ALV.
  SyntheticWorld world(40);
  const Pose2 home = P(0, 0, 0), current = P(1.5, 1.0, 0.0);
  const LandmarkSet h = world.View(home), c = world.View(current);
  std::vector<LandmarkMatch> matches;
  std::mt19937 rng(1);
  for (int i = 0; i < 40; ++i) {
    if (i % 2 == 0) {
      matches.push_back(LandmarkMatch{i, i, 0.1f, 0.2f});
    } else {
      matches.push_back(LandmarkMatch{i, static_cast<int>((i * 7 + 3) % 40), 0.9f, 0.95f});
    }
  }
  const double truth = TrueHomeDirection(current, Eigen::Vector2d(home.x_m, home.y_m));
  LandmarkAlvOptions unit, weighted;
  weighted.variant = AlvVariant::kWeighted;
  const auto eu = LandmarkAlvHoming(h, c, matches, 0, world.panorama, unit);
  const auto ew = LandmarkAlvHoming(h, c, matches, 0, world.panorama, weighted);
  ASSERT_TRUE(eu && ew);
  EXPECT_LT(DegBetween(ew->direction_rad, truth), DegBetween(eu->direction_rad, truth));
  EXPECT_LT(DegBetween(ew->direction_rad, truth), 30.0);
  weighted.weight = MatchWeight::kDistance;
  const auto ed = LandmarkAlvHoming(h, c, matches, 0, world.panorama, weighted);
  ASSERT_TRUE(ed);
  EXPECT_LT(DegBetween(ed->direction_rad, truth), DegBetween(eu->direction_rad, truth));
}

TEST(LandmarkAlv, TopNKeepsTheSmallestDistances) {
  SyntheticWorld world(10);
  const LandmarkSet h = world.View(P(0, 0, 0)), c = world.View(P(1, 0, 0));
  std::vector<LandmarkMatch> matches;
  for (int i = 0; i < 10; ++i) matches.push_back(LandmarkMatch{i, i, static_cast<float>(10 - i), 0.5f});
  LandmarkAlvOptions alv;
  alv.top_n = 3;
  const auto e = LandmarkAlvHoming(h, c, matches, 0, world.panorama, alv);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->bins_used, 3);
  // The same as the ALV of landmarks 7, 8, 9 alone.
  const std::vector<LandmarkMatch> last(matches.end() - 3, matches.end());
  alv.top_n = 0;
  const auto e3 = LandmarkAlvHoming(h, c, last, 0, world.panorama, alv);
  ASSERT_TRUE(e3);
  EXPECT_NEAR(e->direction_rad, e3->direction_rad, 1e-9);
}

TEST(LandmarkAlv, NoMatchesIsNoEstimate) {
  SyntheticWorld world(5);
  const LandmarkSet h = world.View(P(0, 0, 0));
  EXPECT_FALSE(LandmarkAlvHoming(h, h, {}, 0, world.panorama, LandmarkAlvOptions{}));
  LandmarkAlvOptions alv;
  alv.min_landmarks = 6;
  std::vector<LandmarkMatch> five;
  for (int i = 0; i < 5; ++i) five.push_back(LandmarkMatch{i, i, 0.1f, 0.5f});
  EXPECT_FALSE(LandmarkAlvHoming(h, world.View(P(1, 0, 0)), five, 0, world.panorama, alv));
  // The same view: the ALVs are equal, the difference vanishes -> no direction.
  EXPECT_FALSE(LandmarkAlvHoming(h, h, five, 0, world.panorama, LandmarkAlvOptions{}));
  std::vector<LandmarkMatch> bad{LandmarkMatch{0, 9, 0.1f, 0.5f}};
  EXPECT_THROW(LandmarkAlvHoming(h, h, bad, 0, world.panorama, LandmarkAlvOptions{}), std::invalid_argument);
}

TEST(LandmarkMatching, RejectsAnUnrelatedScene) {
  SyntheticWorld a(60, 3), b(60, 11);  // different descriptors
  const auto ha = a.View(P(0, 0, 0)), cb = b.View(P(0, 0, 0));
  const auto same = MatchLandmarks(ha, a.View(P(0.5, 0, 0)), MatchOptions{});
  const auto wrong = MatchLandmarks(ha, cb, MatchOptions{});
  EXPECT_GE(same.size(), 55u);
  EXPECT_LE(wrong.size(), 6u) << "random descriptors should rarely pass the ratio test and the mutual check";
}

TEST(LandmarkMatching, MutualRelaxedAndDisplacementRules) {
  // Hand-made 2-D descriptors. Home: H0=(0,0), H1=(10,0). Current: C0=(1,0), C1=(0,1.2), C2=(10,0).
  // C0 and C1 both prefer H0; H0 prefers C0 (best) then C1 (second).
  LandmarkSet home, cur;
  home.width_px = cur.width_px = 720;
  home.height_px = cur.height_px = 120;
  home.descriptors = (cv::Mat_<float>(2, 2) << 0, 0, 10, 0);
  cur.descriptors = (cv::Mat_<float>(3, 2) << 1, 0, 0, 1.2f, 10, 0);
  home.landmarks = {Landmark{100, 60, 1, 10, -1}, Landmark{300, 60, 1, 10, -1}};
  cur.landmarks = {Landmark{110, 60, 1, 10, -1}, Landmark{95, 60, 1, 10, -1}, Landmark{500, 60, 1, 10, -1}};
  MatchOptions o;
  o.ratio = 1.0;  // off
  auto m = MatchLandmarks(home, cur, o);
  ASSERT_EQ(m.size(), 2u);  // C0-H0 (mutual), C2-H1 (mutual); C1 is H0's second: rejected
  EXPECT_EQ(m[0].current, 0);
  EXPECT_EQ(m[1].current, 2);
  o.relaxed_second_best = true;
  m = MatchLandmarks(home, cur, o);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[1].current, 1);
  EXPECT_EQ(m[1].home, 0);
  o.max_x_displacement_px = 60;  // C2 at column 500 vs H1 at 300: 200 px apart
  m = MatchLandmarks(home, cur, o);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[1].current, 1);
  // With a known shift of +200 px, C2 - H1 fits and C0, C1 (near H0) do not.
  m = MatchLandmarks(home, cur, o, 200);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].current, 2);
  // Different descriptor lengths are an error, not garbage.
  LandmarkSet other = cur;
  other.descriptors = cv::Mat::zeros(3, 4, CV_32F);
  EXPECT_THROW(MatchLandmarks(home, other, o), std::invalid_argument);
  EXPECT_TRUE(MatchLandmarks(home, LandmarkSet{}, o).empty());
}

TEST(LandmarkRotation, RecoversTheHeadingDespiteOutliers) {
  SyntheticWorld world(40);
  const Pose2 home = P(0, 0, 0);
  for (double theta : {0.0, 0.7, -2.0, 3.0}) {
    const Pose2 current = P(0.3, 0.2, theta);
    const LandmarkSet h = world.View(home), c = world.View(current);
    auto matches = MatchLandmarks(h, c, MatchOptions{});
    for (int i = 0; i < 8; ++i) matches.push_back(LandmarkMatch{i, (i * 13 + 5) % 40, 1, 0.9f});  // outliers
    const auto r = RotationFromMatches(h, c, matches, world.panorama);
    ASSERT_TRUE(r);
    EXPECT_LT(DegBetween(*r, theta), 5.0) << theta;
  }
  EXPECT_FALSE(RotationFromMatches(world.View(home), world.View(home), {}, world.panorama));
}

TEST(LandmarkHomer, HomesFromSetsWithAndWithoutKnownRotation) {
  SyntheticWorld world(50);
  LandmarkHomingConfig cfg;
  cfg.alv.variant = AlvVariant::kScale;
  LandmarkHomer homer(cfg, world.panorama);
  EXPECT_THROW(homer.Home(world.View(P(0, 0, 0))), std::logic_error);
  homer.SetHome(world.View(P(0, 0, 0)));
  // Near home the bearing differences cluster around the rotation (far from it, parallax
  // spreads them: the rotation from matches assumes distant landmarks, like any compass).
  const Pose2 current = P(-0.6, 0.8, 1.2);
  const auto r = homer.Home(world.View(current));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->matches, 50);
  EXPECT_LT(DegBetween(r->estimate.direction_rad, TrueHomeDirection(current, Eigen::Vector2d::Zero())), 6.0);
  EXPECT_LT(DegBetween(r->estimate.compass_rotation_rad, 1.2), 6.0);
  const auto k = homer.Home(world.View(current), 1.2);
  ASSERT_TRUE(k);
  EXPECT_LT(DegBetween(k->estimate.direction_rad, TrueHomeDirection(current, Eigen::Vector2d::Zero())), 1.0);
  // No landmarks: no estimate. A set from another panorama size: an error.
  LandmarkSet empty;
  empty.width_px = world.panorama.width_px;
  empty.height_px = world.panorama.height_px;
  EXPECT_FALSE(homer.Home(empty));
  LandmarkSet wrong = world.View(current);
  wrong.width_px = 360;
  EXPECT_THROW(homer.Home(wrong), std::invalid_argument);
}

// A panorama with a few bright blobs, one across the seam.
cv::Mat BlobPanorama(const std::vector<cv::Point2f>& centres) {
  cv::Mat img(120, 720, CV_8UC1, cv::Scalar(40));
  for (const auto& c : centres) {
    for (int dx : {-720, 0, 720}) cv::circle(img, cv::Point(c.x + dx, c.y), 6, cv::Scalar(220), cv::FILLED, cv::LINE_AA);
  }
  cv::GaussianBlur(img, img, {0, 0}, 1.5);
  return img;
}

TEST(Sift, FindsBlobsAtTheirColumnsAndAcrossTheSeam) {
  const std::vector<cv::Point2f> centres{{100, 60}, {360, 40}, {540, 80}, {718, 60}};
  const LandmarkSet s = DetectSift(BlobPanorama(centres), SiftOptions{});
  EXPECT_EQ(s.method, LandmarkMethod::kSift);
  EXPECT_EQ(s.width_px, 720);
  EXPECT_EQ(s.descriptors.rows, s.size());
  EXPECT_EQ(s.descriptors.cols, 128);
  // SIFT gives an isotropic blob several orientations: count keypoints per blob, and expect
  // the blob on the seam to get as many as the same blob at column 100 (not twice as many).
  std::vector<int> near(centres.size(), 0);
  for (size_t i = 0; i < centres.size(); ++i) {
    for (const auto& l : s.landmarks) {
      const double dx = std::abs(std::remainder(l.x_px - centres[i].x, 720.0));
      if (dx < 2.0 && std::abs(l.y_px - centres[i].y) < 2.0) ++near[i];
    }
    EXPECT_GE(near[i], 1) << "blob at " << centres[i].x << "," << centres[i].y;
  }
  EXPECT_EQ(near[3], near[0]) << "the blob across the seam is reported a different number of times";
  for (const auto& l : s.landmarks) {
    EXPECT_GE(l.x_px, 0);
    EXPECT_LT(l.x_px, 720);
  }
}

TEST(Sift, FeaturelessImageHasNoLandmarksAndBadInputThrows) {
  EXPECT_TRUE(DetectSift(cv::Mat(120, 720, CV_8UC1, cv::Scalar(90)), SiftOptions{}).empty());
  EXPECT_THROW(DetectSift(cv::Mat(), SiftOptions{}), std::invalid_argument);
  EXPECT_THROW(DetectSift(cv::Mat(120, 720, CV_8UC3), SiftOptions{}), std::invalid_argument);
  SiftOptions bad;
  bad.octave_layers = 0;
  EXPECT_THROW(DetectSift(BlobPanorama({}), bad), std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::nav
