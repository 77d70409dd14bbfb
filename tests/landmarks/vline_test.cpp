#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/landmarks/vline.hpp"

namespace snapnav::nav {
namespace {

constexpr int kWidth = 720, kHeight = 120;

double ColumnDistance(double a, double b, double width = kWidth) {
  double d = std::fmod(std::abs(a - b), width);
  return std::min(d, width - d);
}

// Columns rolled right by k (numpy's roll along axis 1): output column x shows input column x - k.
cv::Mat RollColumns(const cv::Mat& img, int k) {
  k = ((k % img.cols) + img.cols) % img.cols;
  if (k == 0) return img.clone();
  cv::Mat out;
  cv::hconcat(img.colRange(img.cols - k, img.cols), img.colRange(0, img.cols - k), out);
  return out;
}

// Lines within `tolerance` of `column` (wrapping).
int LinesNear(const std::vector<VerticalLine>& lines, double column, double tolerance = 2.0) {
  return static_cast<int>(std::count_if(lines.begin(), lines.end(), [&](const VerticalLine& l) {
    return ColumnDistance(l.column_px, column) <= tolerance;
  }));
}

// Fills the quadrilateral between two straight edges from the top to the bottom row:
// x_left(y) = left_top + y * tan(tilt), the right edge parallel.
void FillSlantedBand(cv::Mat* img, double left_top, double right_top, double tilt_deg, uint8_t value) {
  const double slope = std::tan(tilt_deg * M_PI / 180);
  const double h = img->rows;
  std::vector<cv::Point> poly = {{static_cast<int>(std::lround(left_top)), 0},
                                 {static_cast<int>(std::lround(right_top)), 0},
                                 {static_cast<int>(std::lround(right_top + slope * h)), img->rows},
                                 {static_cast<int>(std::lround(left_top + slope * h)), img->rows}};
  cv::fillConvexPoly(*img, poly, cv::Scalar(value));
}

// Vertical bands at known columns, a horizontal stripe, a short wide box and two slanted bands.
struct BandScene {
  cv::Mat image;
  std::vector<double> vertical_edges;  // columns of the true vertical edges (between pixels)
  double shallow_edge_centre = 0;      // centre-row column of the 5-degree edge
  std::vector<double> steep_edges;     // centre-row columns of the 25-degree edges
};

BandScene MakeBandScene() {
  BandScene s;
  s.image = cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(110));
  // A dark horizontal stripe across the whole panorama: horizontal edges only.
  s.image.rowRange(20, 28).setTo(40);
  // Vertical bands (full height), drawn over the stripe.
  s.image.colRange(100, 140).setTo(210);
  s.image.colRange(300, 330).setTo(20);
  s.image.colRange(405, 420).setTo(230);
  s.vertical_edges = {99.5, 139.5, 299.5, 329.5, 404.5, 419.5};
  // A short, wide box: long horizontal edges, vertical sides of 10 rows only.
  s.image(cv::Rect(440, 80, 110, 10)).setTo(240);
  // Steep bands: 25 degrees from vertical, beyond max_tilt.
  FillSlantedBand(&s.image, 560, 590, 25, 230);
  const double slope25 = std::tan(25 * M_PI / 180) * kHeight / 2;
  s.steep_edges = {559.5 + slope25, 589.5 + slope25};
  // A 5-degree band: its left edge is detected (the right one is detected too).
  FillSlantedBand(&s.image, 200, 240, 5, 20);
  s.shallow_edge_centre = 199.5 + std::tan(5 * M_PI / 180) * kHeight / 2;
  return s;
}

TEST(VlineDetect, FindsVerticalEdgesAtTheirColumnsAndNothingElse) {
  const BandScene s = MakeBandScene();
  const VlineOptions o;
  const auto lines = DetectVerticalLines(s.image, o);
  for (const double edge : s.vertical_edges) {
    EXPECT_EQ(LinesNear(lines, edge), 1) << "vertical edge at column " << edge;
    for (const auto& l : lines) {
      if (ColumnDistance(l.column_px, edge) <= 2) {
        EXPECT_NEAR(l.column_px, edge, 0.5) << "sub-pixel column";
        EXPECT_GE(l.length_px, 0.9 * kHeight);
        EXPECT_LE(l.length_px, kHeight);
        EXPECT_LE(l.top_px, 0.1 * kHeight);
        EXPECT_GE(l.bottom_px, 0.9 * kHeight);
      }
    }
  }
  EXPECT_EQ(LinesNear(lines, s.shallow_edge_centre), 1) << "5-degree edge, within max_tilt";
  for (const double edge : s.steep_edges) EXPECT_EQ(LinesNear(lines, edge, 15), 0) << "25-degree edge";
  // Nothing along the short box (440..550) nor elsewhere: the band edges, the 5-degree band's two edges.
  EXPECT_EQ(lines.size(), s.vertical_edges.size() + 2);
  for (const auto& l : lines) {
    EXPECT_FALSE(l.column_px > 430 && l.column_px < 555) << "line at " << l.column_px << " along the short box";
    EXPECT_GE(l.column_px, 0);
    EXPECT_LT(l.column_px, kWidth);
  }
  for (size_t i = 1; i < lines.size(); ++i) EXPECT_LT(lines[i - 1].column_px, lines[i].column_px) << "sorted";

  // With a wider tilt threshold the 25-degree edges appear (the threshold is what removes them).
  VlineOptions wide = o;
  wide.max_tilt_deg = 30;
  const auto wide_lines = DetectVerticalLines(s.image, wide);
  for (const double edge : s.steep_edges) EXPECT_EQ(LinesNear(wide_lines, edge, 4), 1) << "25-degree edge, tilt 30";
}

TEST(VlineDetect, EdgeAcrossTheSeamIsFoundOnce) {
  // A bright block over columns 690..719 and 0..29: its edges lie at 689.5 and 29.5, and
  // a vertical edge between column 719 and column 0 (the seam) separates it from a dark block.
  cv::Mat img(kHeight, kWidth, CV_8UC1, cv::Scalar(110));
  img.colRange(0, 30).setTo(30);
  img.colRange(690, 720).setTo(220);
  const auto lines = DetectVerticalLines(img, VlineOptions{});
  EXPECT_EQ(LinesNear(lines, 719.5), 1) << "seam edge";
  EXPECT_EQ(LinesNear(lines, 689.5), 1);
  EXPECT_EQ(LinesNear(lines, 29.5), 1);
  EXPECT_EQ(lines.size(), 3u);
  for (const auto& l : lines) EXPECT_LE(l.length_px, kHeight) << "the two copies in the padding count once";

  // A 6-degree edge that crosses the middle column at the centre row, rolled so that it
  // crosses the seam: found once, over its whole height.
  for (const int roll : {0, 360}) {
    cv::Mat tilted(kHeight, kWidth, CV_8UC1, cv::Scalar(60));
    FillSlantedBand(&tilted, 354, 600, 6, 200);
    tilted = RollColumns(tilted, roll);
    const auto t = DetectVerticalLines(tilted, VlineOptions{});
    const double edge = std::fmod(360.0 + roll, kWidth);
    EXPECT_EQ(LinesNear(t, edge, 2.0), 1) << "roll " << roll;
    for (const auto& l : t) {
      if (ColumnDistance(l.column_px, edge) <= 2) {
        EXPECT_GE(l.length_px, 0.9 * kHeight) << "roll " << roll;
        EXPECT_LE(l.length_px, kHeight) << "roll " << roll;
      }
    }
  }
}

TEST(VlineDetect, FeaturelessImageGivesAnEmptySet) {
  const cv::Mat flat(kHeight, kWidth, CV_8UC1, cv::Scalar(128));
  EXPECT_TRUE(DetectVerticalLines(flat, VlineOptions{}).empty());
  const LandmarkSet set = DetectVlineLandmarks(flat, VlineOptions{});
  EXPECT_TRUE(set.empty());
  EXPECT_EQ(set.method, LandmarkMethod::kVline);
  EXPECT_EQ(set.width_px, kWidth);
  EXPECT_EQ(set.height_px, kHeight);
  EXPECT_TRUE(set.descriptors.empty());
}

TEST(VlineDetect, BadImagesThrow) {
  const VlineOptions o;
  EXPECT_THROW(DetectVerticalLines(cv::Mat(), o), std::invalid_argument);
  EXPECT_THROW(DetectVerticalLines(cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar::all(0)), o), std::invalid_argument);
  EXPECT_THROW(DetectVerticalLines(cv::Mat(kHeight, kWidth, CV_32FC1, cv::Scalar(0)), o), std::invalid_argument);
  EXPECT_THROW(DetectVerticalLines(cv::Mat(kHeight, 30, CV_8UC1, cv::Scalar(0)), o), std::invalid_argument)
      << "narrower than the window";
  EXPECT_THROW(DetectVlineLandmarks(cv::Mat(kHeight, kWidth, CV_16UC1, cv::Scalar(0)), o), std::invalid_argument);
  EXPECT_THROW(DescribeVerticalLines(cv::Mat(), {}, o), std::invalid_argument);
  const cv::Mat img = MakeBandScene().image;
  VerticalLine outside;
  outside.column_px = kWidth;
  EXPECT_THROW(DescribeVerticalLines(img, {outside}, o), std::invalid_argument);
}

TEST(VlineOptions, ValidateRejectsBadOptions) {
  EXPECT_NO_THROW(VlineOptions{}.Validate());
  auto expect_bad = [](auto change, const char* what) {
    VlineOptions o;
    change(o);
    EXPECT_THROW(o.Validate(), std::invalid_argument) << what;
    EXPECT_THROW(DetectVerticalLines(MakeBandScene().image, o), std::invalid_argument) << what;
  };
  expect_bad([](VlineOptions& o) { o.canny_low = 200; }, "canny_low > canny_high");
  expect_bad([](VlineOptions& o) { o.canny_low = -1; }, "canny_low < 0");
  expect_bad([](VlineOptions& o) { o.blur_sigma_px = -1; }, "blur");
  expect_bad([](VlineOptions& o) { o.hough_rho_px = 0; }, "rho");
  expect_bad([](VlineOptions& o) { o.hough_theta_deg = 0; }, "theta");
  expect_bad([](VlineOptions& o) { o.hough_threshold = 0; }, "threshold");
  expect_bad([](VlineOptions& o) { o.min_segment_px = 0; }, "min_segment");
  expect_bad([](VlineOptions& o) { o.max_gap_px = -1; }, "max_gap");
  expect_bad([](VlineOptions& o) { o.max_tilt_deg = 0; }, "max_tilt 0");
  expect_bad([](VlineOptions& o) { o.max_tilt_deg = 80; }, "max_tilt 80");
  expect_bad([](VlineOptions& o) { o.cluster_px = -1; }, "cluster");
  expect_bad([](VlineOptions& o) { o.min_line_px = -1; }, "min_line");
  expect_bad([](VlineOptions& o) { o.window_px = 1; }, "window");
  expect_bad([](VlineOptions& o) { o.bins = 1; }, "bins");
  expect_bad([](VlineOptions& o) { o.max_tilt_deg = std::nan(""); }, "NaN tilt");
}

TEST(VlineDescribe, DividedWindowHas48DimsAndOneHistogramHas8) {
  const BandScene s = MakeBandScene();
  VlineOptions o;
  const auto lines = DetectVerticalLines(s.image, o);
  ASSERT_FALSE(lines.empty());
  for (const bool divided : {true, false}) {
    o.divided = divided;
    const cv::Mat d = DescribeVerticalLines(s.image, lines, o);
    EXPECT_EQ(d.type(), CV_32F);
    EXPECT_EQ(d.rows, static_cast<int>(lines.size()));
    EXPECT_EQ(d.cols, divided ? 48 : 8);
    for (int i = 0; i < d.rows; ++i) {
      EXPECT_NEAR(cv::norm(d.row(i)), 1.0, 1e-4) << "unit L2 norm";
      double min_v = 0;
      cv::minMaxLoc(d.row(i), &min_v);
      EXPECT_GE(min_v, 0.0);
    }
    const LandmarkSet set = DetectVlineLandmarks(s.image, o);
    EXPECT_EQ(set.descriptors.cols, divided ? 48 : 8);
    ASSERT_EQ(set.size(), static_cast<int>(lines.size()));
    for (int i = 0; i < set.size(); ++i) {
      EXPECT_FLOAT_EQ(set.landmarks[i].x_px, static_cast<float>(lines[i].column_px));
      EXPECT_FLOAT_EQ(set.landmarks[i].strength, static_cast<float>(lines[i].length_px));
      EXPECT_FLOAT_EQ(set.landmarks[i].y_px, static_cast<float>(0.5 * (lines[i].top_px + lines[i].bottom_px)));
      EXPECT_EQ(set.landmarks[i].scale_px, o.window_px);
      EXPECT_EQ(set.landmarks[i].angle_deg, -1);
    }
  }
  o.bins = 12;
  o.divided = true;
  EXPECT_EQ(DescribeVerticalLines(s.image, lines, o).cols, 72);
  EXPECT_EQ(DescribeVerticalLines(s.image, {}, o).cols, 72);
  EXPECT_EQ(DescribeVerticalLines(s.image, {}, o).rows, 0);
}

TEST(VlineDescribe, SignedOrientationSeparatesRisingFromFallingEdges) {
  // The two edges of a bright band are mirror images: one histogram each, in opposite bins.
  cv::Mat img(kHeight, kWidth, CV_8UC1, cv::Scalar(50));
  img.colRange(300, 360).setTo(200);
  VlineOptions o;
  o.divided = false;
  const LandmarkSet set = DetectVlineLandmarks(img, o);
  ASSERT_EQ(set.size(), 2);
  const cv::Mat& d = set.descriptors;
  cv::Point rising, falling;
  cv::minMaxLoc(d.row(0), nullptr, nullptr, nullptr, &rising);
  cv::minMaxLoc(d.row(1), nullptr, nullptr, nullptr, &falling);
  EXPECT_EQ(rising.x, 0) << "dark to bright: gradient points right, 0 degrees";
  EXPECT_EQ(falling.x, 4) << "bright to dark: 180 degrees";
  EXPECT_GT(cv::norm(d.row(0), d.row(1)), 1.0);
}

// A textured panorama: blurred noise with bands of random width and brightness.
cv::Mat TexturedBands(int seed) {
  cv::RNG rng(seed);
  cv::Mat img(kHeight, kWidth, CV_8UC1);
  rng.fill(img, cv::RNG::UNIFORM, 60, 160);
  cv::GaussianBlur(img, img, {0, 0}, 3.0);
  int x = rng.uniform(0, 30);
  while (x < kWidth - 20) {
    const int w = rng.uniform(8, 40);
    const int top = rng.uniform(0, 30), bottom = rng.uniform(90, kHeight + 1);
    cv::Mat band = img(cv::Rect(x, top, std::min(w, kWidth - x), bottom - top));
    band += cv::Scalar(rng.uniform(0, 2) ? 80 : -50);
    x += w + rng.uniform(15, 60);
  }
  return img;
}

TEST(VlineMatch, ShiftedSceneMatchesEveryLineToItsCounterpart) {
  const cv::Mat home_img = TexturedBands(7);
  const VlineOptions o;
  const LandmarkSet home = DetectVlineLandmarks(home_img, o);
  ASSERT_GE(home.size(), 10);
  for (const int k : {37, -150, 359}) {
    const LandmarkSet cur = DetectVlineLandmarks(RollColumns(home_img, k), o);
    ASSERT_EQ(cur.size(), home.size()) << "shift " << k;
    const auto matches = MatchVerticalLines(home, cur, VlineMatchOptions{}, k);
    EXPECT_EQ(static_cast<int>(matches.size()), home.size()) << "shift " << k;
    for (const auto& m : matches) {
      EXPECT_LT(ColumnDistance(cur.landmarks[m.current].x_px, home.landmarks[m.home].x_px + k), 0.5)
          << "shift " << k << ": home " << home.landmarks[m.home].x_px << " -> " << cur.landmarks[m.current].x_px;
      EXPECT_LT(m.distance, 0.05);
    }
  }
}

TEST(VlineMatch, DifferentSceneGivesFewMatches) {
  const VlineOptions o;
  const LandmarkSet home = DetectVlineLandmarks(TexturedBands(7), o);
  const LandmarkSet other = DetectVlineLandmarks(TexturedBands(8), o);
  ASSERT_GE(home.size(), 10);
  ASSERT_GE(other.size(), 10);
  VlineMatchOptions strict;
  strict.relaxed_second_best = false;
  const auto matches = MatchVerticalLines(home, other, strict);
  const size_t fewest = static_cast<size_t>(std::min(home.size(), other.size()));
  EXPECT_LE(matches.size() * 4, fewest) << matches.size() << " matches of " << home.size() << " and " << other.size()
                                        << " lines";
  EXPECT_LE(MatchVerticalLines(home, other, VlineMatchOptions{}).size() * 4, fewest) << "loosened rule";
  // Without the displacement threshold, the descriptors alone: some pairs are always mutual
  // (the closest pair is), but fewer than half, and none as close as true correspondences.
  strict.max_x_displacement_px = 0;
  const auto ungated = MatchVerticalLines(home, other, strict);
  EXPECT_LT(ungated.size() * 2, fewest);
  for (const auto& m : ungated) EXPECT_GT(m.distance, 0.05);
}

// A hand-made landmark set with the given columns and 2-D descriptors.
LandmarkSet HandMade(const std::vector<float>& columns, const std::vector<cv::Vec2f>& descriptors) {
  LandmarkSet s;
  s.method = LandmarkMethod::kVline;
  s.width_px = kWidth;
  s.height_px = kHeight;
  s.descriptors = cv::Mat(static_cast<int>(descriptors.size()), 2, CV_32F);
  for (size_t i = 0; i < columns.size(); ++i) {
    Landmark l;
    l.x_px = columns[i];
    s.landmarks.push_back(l);
    s.descriptors.at<float>(static_cast<int>(i), 0) = descriptors[i][0];
    s.descriptors.at<float>(static_cast<int>(i), 1) = descriptors[i][1];
  }
  return s;
}

TEST(VlineMatch, DisplacementThresholdRejectsFarMatches) {
  const LandmarkSet home = HandMade({100, 10}, {{1, 0}, {0, 1}});
  const LandmarkSet cur = HandMade({300, 700}, {{1, 0}, {0, 1}});
  VlineMatchOptions o;
  o.max_x_displacement_px = 60;
  // 100 -> 300 moves 200 columns; 10 -> 700 moves -30 across the seam.
  auto m = MatchVerticalLines(home, cur, o);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].home, 1);
  EXPECT_EQ(m[0].current, 1);
  EXPECT_FLOAT_EQ(m[0].distance, 0);
  // Removing the expected shift: 100 + 200 = 300 fits, 10 + 200 = 210 is 230 from 700... wrapped 210.
  m = MatchVerticalLines(home, cur, o, 200);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].home, 0);
  o.max_x_displacement_px = 0;  // off
  EXPECT_EQ(MatchVerticalLines(home, cur, o).size(), 2u);
}

TEST(VlineMatch, RelaxedRuleAcceptsTheSecondBestButNotTheThird) {
  // Home H0 = (1, 0), H1 = (0, 1). Current C0 equals H0; C1 and C2 are nearest to H0 too,
  // C1 being H0's second-nearest current line and C2 its third.
  const LandmarkSet home = HandMade({100, 400}, {{1, 0}, {0, 1}});
  const LandmarkSet cur = HandMade({100, 110, 120}, {{1, 0}, {0.95f, 0.31f}, {0.8f, 0.6f}});
  VlineMatchOptions o;
  o.relaxed_second_best = false;
  auto m = MatchVerticalLines(home, cur, o);
  ASSERT_EQ(m.size(), 1u) << "mutual only";
  EXPECT_EQ(m[0].home, 0);
  EXPECT_EQ(m[0].current, 0);

  o.relaxed_second_best = true;
  m = MatchVerticalLines(home, cur, o);
  ASSERT_EQ(m.size(), 2u) << "loosened rule";
  EXPECT_EQ(m[1].home, 0);
  EXPECT_EQ(m[1].current, 1);
  EXPECT_NEAR(m[1].distance, std::hypot(0.05, 0.31), 1e-5);

  o.mutual = false;
  m = MatchVerticalLines(home, cur, o);
  ASSERT_EQ(m.size(), 3u) << "plain nearest neighbours";
  for (const auto& x : m) EXPECT_EQ(x.home, 0);

  // Empty sets match nothing; descriptors of different widths are an error.
  EXPECT_TRUE(MatchVerticalLines(LandmarkSet{}, cur, o).empty());
  LandmarkSet wide = home;
  wide.descriptors = cv::Mat(2, 3, CV_32F, cv::Scalar(0));
  EXPECT_THROW(MatchVerticalLines(wide, cur, o), std::invalid_argument);
  LandmarkSet missing_rows = home;
  missing_rows.descriptors = cv::Mat(1, 2, CV_32F, cv::Scalar(0));
  EXPECT_THROW(MatchVerticalLines(missing_rows, cur, o), std::invalid_argument);
}

// A 6 x 5 m room with mildly textured walls and boxes (cabinets, desks) whose vertical
// corners are the landmarks; every box surface has its own brightness.
struct BoxRoom {
  sim::Scene scene;
  std::vector<Eigen::Vector2d> corners;  // vertical edges in the world (box and room corners)
};

BoxRoom MakeBoxRoom() {
  BoxRoom room;
  sim::Scene& scene = room.scene;
  scene.name = "box room";
  cv::RNG rng(21);
  auto add_texture = [&](double mean) {
    cv::Mat tex(64, 64, CV_8UC3);
    rng.fill(tex, cv::RNG::UNIFORM, cv::Scalar::all(mean - 25), cv::Scalar::all(mean + 25));
    cv::GaussianBlur(tex, tex, {0, 0}, 2.0);
    scene.textures.push_back(sim::MakeTexture("t" + std::to_string(scene.textures.size()), tex, 1.0, 1.0));
    return static_cast<int>(scene.textures.size()) - 1;
  };
  const Eigen::Vector2d room_corners[4] = {{-3, -2.5}, {3, -2.5}, {3, 2.5}, {-3, 2.5}};
  const double wall_grey[4] = {150, 185, 120, 200};
  for (int i = 0; i < 4; ++i) {
    scene.walls.push_back({room_corners[i], room_corners[(i + 1) % 4], 2.6, 0, add_texture(wall_grey[i]), 0});
    room.corners.push_back(room_corners[i]);
  }
  // Boxes: centre, size, height, grey.
  struct Box {
    Eigen::Vector2d c, size;
    double height, grey;
  };
  const Box boxes[] = {{{2.2, -1.2}, {0.6, 1.0}, 1.9, 60},  {{2.3, 1.3}, {0.5, 0.8}, 1.2, 230},
                       {{-0.5, 2.1}, {1.4, 0.5}, 2.0, 40},  {{-2.4, 0.6}, {0.5, 0.7}, 1.5, 240},
                       {{-1.6, -2.1}, {0.9, 0.5}, 1.8, 70}, {{0.9, -2.2}, {0.6, 0.4}, 0.9, 225}};
  for (const Box& b : boxes) {
    const int tex = add_texture(b.grey);
    const Eigen::Vector2d h = b.size / 2;
    const Eigen::Vector2d p[4] = {b.c + Eigen::Vector2d(-h.x(), -h.y()), b.c + Eigen::Vector2d(h.x(), -h.y()),
                                  b.c + Eigen::Vector2d(h.x(), h.y()), b.c + Eigen::Vector2d(-h.x(), h.y())};
    for (int i = 0; i < 4; ++i) {
      scene.walls.push_back({p[i], p[(i + 1) % 4], b.height, 0, tex, 0});
      room.corners.push_back(p[i]);
    }
  }
  return room;
}

sim::OmniCameraOptions Camera() {
  sim::OmniCameraOptions cam;
  cam.panorama.width_px = kWidth;
  cam.panorama.height_px = kHeight;
  cam.panorama.elevation_top_rad = 20 * M_PI / 180;
  cam.panorama.elevation_bottom_rad = -20 * M_PI / 180;
  return cam;
}

cv::Mat RenderGray(const sim::OmniRenderer& r, const Pose2& pose) {
  cv::Mat bgr, gray;
  r.RenderPanorama(pose, {}, &bgr);
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

// Column at which `robot` sees the world point `p`.
double ColumnOf(const PanoramaModel& model, const Pose2& robot, const Eigen::Vector2d& p) {
  const double world = std::atan2(p.y() - robot.y_m, p.x() - robot.x_m);
  return model.ColumnOfBearing(WrapAngle(world - robot.theta_rad));
}

TEST(VlineRendered, LinesSitOnCornersAndMatchesAcrossHalfAMetreAgree) {
  const BoxRoom room = MakeBoxRoom();
  const sim::OmniCameraOptions cam = Camera();
  const sim::OmniRenderer r(room.scene, cam);
  const Pose2 home_pose{0, 0, 0}, cur_pose{0.35, -0.35, 0.6};  // 0.5 m away, turned
  const VlineOptions o;
  const LandmarkSet home = DetectVlineLandmarks(RenderGray(r, home_pose), o);
  const LandmarkSet cur = DetectVlineLandmarks(RenderGray(r, cur_pose), o);
  ASSERT_GE(home.size(), 10);
  ASSERT_GE(cur.size(), 10);
  // Corner whose column is within `tol` of a landmark's, or -1.
  auto corner_of = [&](const Pose2& pose, double column, double tol) {
    for (size_t i = 0; i < room.corners.size(); ++i) {
      if (ColumnDistance(ColumnOf(cam.panorama, pose, room.corners[i]), column) <= tol) return static_cast<int>(i);
    }
    return -1;
  };
  int on_corner = 0;
  for (const auto& l : home.landmarks) on_corner += corner_of(home_pose, l.x_px, 2.0) >= 0;
  EXPECT_GE(on_corner, 0.8 * home.size()) << on_corner << " of " << home.size() << " home lines on a corner";

  // The current view is turned by 0.6 rad counter-clockwise: the scene moves to higher columns.
  const double shift_px = 0.6 * kWidth / (2 * M_PI);
  const auto matches = MatchVerticalLines(home, cur, VlineMatchOptions{}, shift_px);
  int consistent = 0;
  for (const auto& m : matches) {
    const double xh = home.landmarks[m.home].x_px, xc = cur.landmarks[m.current].x_px;
    for (size_t i = 0; i < room.corners.size(); ++i) {
      if (ColumnDistance(ColumnOf(cam.panorama, home_pose, room.corners[i]), xh) <= 2.5 &&
          ColumnDistance(ColumnOf(cam.panorama, cur_pose, room.corners[i]), xc) <= 2.5) {
        ++consistent;
        break;
      }
    }
  }
  EXPECT_GE(matches.size(), 8u) << "mutual matches";
  EXPECT_GE(consistent, 0.8 * matches.size())
      << consistent << " of " << matches.size() << " matches pair the same world corner";
}

}  // namespace
}  // namespace snapnav::nav
