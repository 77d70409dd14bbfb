// Place cells on views rendered from the indoor scene: the measures grow with distance, the
// right cell is found, the distance filter rejects a look-alike far cell, the vocabulary index
// finds the cell it was given, exploration stores fewer cells at a higher threshold.

#include <cmath>

#include <gtest/gtest.h>

#include "scene_file.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace snapnav::nav {
namespace {

class PlaceCellsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new sim::Scene(processes::LoadSceneFile(processes::SceneFilePath("indoor13")));
    renderer_ = new sim::OmniRenderer(*scene_, sim::OmniCameraOptions{});
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete scene_;
  }
  static cv::Mat Render(double x, double y, double theta = 0) {
    cv::Mat pano;
    renderer_->RenderPanorama(Pose2{x, y, theta}, {}, &pano);
    return pano;
  }
  static PlaceView View(double x, double y, double theta = 0) { return MakePlaceView(Render(x, y, theta), options_); }
  static Eigen::Vector2d Grid(int ix, int iy) { return scene_->grid.Position(ix, iy); }
  // A memory of the grid's cells every `step` positions.
  static PlaceCellMemory GridMemory(int step) {
    PlaceCellMemory memory(options_, renderer_->options().panorama);
    for (int iy = 0; iy < scene_->grid.ny; iy += step) {
      for (int ix = 0; ix < scene_->grid.nx; ix += step) {
        const auto p = Grid(ix, iy);
        memory.Add(Pose2{p.x(), p.y(), 0}, 0, View(p.x(), p.y()));
      }
    }
    return memory;
  }
  static inline sim::Scene* scene_ = nullptr;
  static inline sim::OmniRenderer* renderer_ = nullptr;
  static inline PlaceViewOptions options_ = [] {
    PlaceViewOptions o;
    o.features.sift.max_features = 300;
    return o;
  }();
};

TEST_F(PlaceCellsTest, ViewHasLandmarksWindowsLinesAndSignature) {
  const auto p = Grid(6, 6);
  const PlaceView v = View(p.x(), p.y());
  EXPECT_GT(v.landmarks.size(), 50);
  EXPECT_EQ(v.windows.rows, v.landmarks.size());
  EXPECT_EQ(v.windows.cols, options_.window_px * options_.window_px);
  EXPECT_GT(v.vlines.size(), 3);
  EXPECT_EQ(v.signature.cols, options_.signature_width_px);
  EXPECT_GT(v.bytes(), 0);
  EXPECT_THROW(MakePlaceView(cv::Mat(), options_), std::invalid_argument);
}

TEST_F(PlaceCellsTest, ImageDifferenceFindsTheRotation) {
  const auto p = Grid(6, 6);
  PlaceView a = View(p.x(), p.y(), 0);
  PlaceView b = View(p.x(), p.y(), 0.7);
  int shift = 0;
  const double rotated = ImageDifference(a.signature, b.signature, &shift);
  EXPECT_NEAR(std::abs(shift), 0.7 / (2 * M_PI) * options_.signature_width_px, 1.5);
  EXPECT_LT(rotated, 12.0);
  const auto q = Grid(0, 0);
  EXPECT_GT(ImageDifference(a.signature, View(q.x(), q.y()).signature), rotated);
}

TEST_F(PlaceCellsTest, BearingDistanceGrowsWithDistanceAndGivesTheHeading) {
  const auto c = Grid(6, 6);
  PlaceCellMemory memory(options_, renderer_->options().panorama);
  memory.Add(Pose2{c.x(), c.y(), 0}, 0, View(c.x(), c.y()));
  std::vector<double> distances;
  for (double d : {0.1, 0.4, 1.0}) {
    const auto compared = memory.Compare(View(c.x() + d, c.y(), 0.5), {0}, PlaceMeasureOptions{});
    ASSERT_TRUE(compared[0].seen) << d;
    // Near the cell the bearing differences are the rotation; further away translation adds to them.
    if (d < 0.2) {
      EXPECT_NEAR(compared[0].rotation_rad, 0.5, 0.05) << d;
    }
    distances.push_back(compared[0].distance);
  }
  EXPECT_LT(distances[0], distances[1]);
  EXPECT_LT(distances[1], distances[2]);
  EXPECT_LT(distances[0], 0.03);
}

TEST_F(PlaceCellsTest, EveryMeasureLocalizesOnTheGrid) {
  PlaceCellMemory memory = GridMemory(3);  // 60 cm spacing, 25 cells
  for (PlaceMeasure m : {PlaceMeasure::kBearingDifference, PlaceMeasure::kMatchCount, PlaceMeasure::kVlineTemplate}) {
    LocalizerOptions o;
    o.measure.measure = m;
    o.estimate = PlaceEstimate::kNearestCell;
    int right = 0, total = 0;
    for (auto [ix, iy] : {std::pair{3, 3}, {6, 9}, {9, 0}, {12, 12}, {0, 6}}) {
      const auto p = Grid(ix, iy);
      const auto loc = memory.Localize(View(p.x() + 0.05, p.y() - 0.04, 1.0), std::nullopt, o);
      ASSERT_TRUE(loc) << PlaceMeasureName(m);
      ++total;
      right += std::hypot(loc->pose.x_m - p.x(), loc->pose.y_m - p.y()) < 0.01;
      if (m != PlaceMeasure::kVlineTemplate) {
        EXPECT_NEAR(WrapAngle(loc->pose.theta_rad - 1.0), 0, 0.1);
      }
    }
    EXPECT_GE(right, m == PlaceMeasure::kVlineTemplate ? 3 : total) << PlaceMeasureName(m);
  }
}

TEST_F(PlaceCellsTest, InterpolationBeatsTheNearestCellOffGrid) {
  PlaceCellMemory memory = GridMemory(2);  // 40 cm spacing
  LocalizerOptions nearest, interpolated;
  nearest.estimate = PlaceEstimate::kNearestCell;
  interpolated.estimate = PlaceEstimate::kInterpolated;
  double e_nearest = 0, e_interp = 0;
  int n = 0;
  for (auto [x, y] : {std::pair{2.45, 2.0}, {3.0, 2.5}, {3.65, 3.1}, {4.2, 3.9}, {2.9, 3.7}}) {
    const PlaceView v = View(x, y, 0.3);
    const auto a = memory.Localize(v, std::nullopt, nearest);
    const auto b = memory.Localize(v, std::nullopt, interpolated);
    ASSERT_TRUE(a && b);
    e_nearest += std::hypot(a->pose.x_m - x, a->pose.y_m - y);
    e_interp += std::hypot(b->pose.x_m - x, b->pose.y_m - y);
    ++n;
  }
  EXPECT_LT(e_interp / n, 0.15);
  EXPECT_LT(e_interp, e_nearest * 1.05);
}

TEST_F(PlaceCellsTest, DistanceFilterRejectsALookAlikeFarCell) {
  // The far cell holds the very view of the query position (a perfect look-alike) but sits 3 m
  // away; the near cell is 20 cm from the query. Without the filter the look-alike wins.
  const auto q = Grid(6, 6);
  PlaceCellMemory memory(options_, renderer_->options().panorama);
  memory.Add(Pose2{q.x() + 0.2, q.y(), 0}, 0, View(q.x() + 0.2, q.y()));
  memory.Add(Pose2{q.x() - 3.0, q.y() + 1.0, 0}, 0, View(q.x(), q.y()));
  LocalizerOptions o;
  o.estimate = PlaceEstimate::kNearestCell;
  const PlaceView query = View(q.x(), q.y());
  const auto unfiltered = memory.Localize(query, std::nullopt, o);
  ASSERT_TRUE(unfiltered);
  EXPECT_EQ(unfiltered->cell, 1);
  const auto filtered = memory.Localize(query, Pose2{q.x() + 0.1, q.y() - 0.1, 0}, o);
  ASSERT_TRUE(filtered);
  EXPECT_EQ(filtered->cell, 0);
  EXPECT_GT(filtered->compared.back().spatial_score, 2.5);
}

TEST_F(PlaceCellsTest, VocabularyIndexRanksTheSourceCellFirst) {
  PlaceCellMemory memory = GridMemory(2);
  memory.BuildIndex();
  ASSERT_TRUE(memory.vocabulary().trained());
  EXPECT_GT(memory.vocabulary().words(), 100);
  for (int i : {0, 10, 30, memory.size() - 1}) {
    const auto ranked = memory.vocabulary().Query(memory.cell(i).view.landmarks.descriptors, 3);
    ASSERT_FALSE(ranked.empty());
    EXPECT_EQ(ranked[0].first, i);
  }
  // A new view near cell 24's position (the centre, (6, 6)) ranks that cell among the first few.
  const auto p = Grid(6, 6);
  const PlaceView v = View(p.x() + 0.05, p.y() + 0.05);
  const auto ranked = memory.vocabulary().Query(v.landmarks.descriptors, 4);
  bool found = false;
  for (const auto& [cell, score] : ranked) found |= std::hypot(memory.cell(cell).pose.x_m - p.x(), memory.cell(cell).pose.y_m - p.y()) < 0.01;
  EXPECT_TRUE(found);
}

TEST_F(PlaceCellsTest, CandidatesComeFromTheIndexOnALargeMemory) {
  PlaceCellMemory memory = GridMemory(2);  // 49 cells
  LocalizerOptions o;
  o.exhaustive_below = 16;
  o.candidates = 8;
  o.near_candidates = 4;
  const auto p = Grid(4, 8);
  const auto loc = memory.Localize(View(p.x() + 0.03, p.y() + 0.02, -0.4), Pose2{p.x() + 0.2, p.y(), 0}, o);
  ASSERT_TRUE(loc);
  EXPECT_LE(loc->candidates, 12);
  EXPECT_LT(std::hypot(loc->pose.x_m - p.x(), loc->pose.y_m - p.y()), 0.12);
  EXPECT_GT(loc->covariance(0, 0), 0);
  EXPECT_GT(loc->covariance(2, 2), 0);
}

TEST_F(PlaceCellsTest, ExplorationThresholdSetsTheDensity) {
  LocalizerOptions o;
  std::vector<int> sizes;
  for (double threshold : {0.02, 0.08}) {
    PlaceCellMemory memory(options_, renderer_->options().panorama);
    for (int i = 0; i <= 24; ++i) {
      const double x = 1.0 + i * 0.1;
      ExploreStep(memory, Pose2{x, 3.0, 0}, i, View(x, 3.0), threshold, o);
    }
    sizes.push_back(memory.size());
  }
  EXPECT_GT(sizes[0], sizes[1]);
  EXPECT_GE(sizes[1], 2);
  EXPECT_LT(sizes[0], 25);
}

TEST_F(PlaceCellsTest, EmptyMemoryAndFeaturelessViewGiveNoAnswer) {
  PlaceCellMemory memory(options_, renderer_->options().panorama);
  const auto p = Grid(6, 6);
  const PlaceView v = View(p.x(), p.y());
  EXPECT_FALSE(memory.Localize(v, std::nullopt, LocalizerOptions{}));
  memory.Add(Pose2{p.x(), p.y(), 0}, 0, v);
  const PlaceView blank = MakePlaceView(cv::Mat(120, 720, CV_8UC1, cv::Scalar(128)), options_);
  EXPECT_TRUE(blank.landmarks.empty());
  EXPECT_FALSE(memory.Localize(blank, std::nullopt, LocalizerOptions{}));
  EXPECT_THROW(memory.Add(Pose2{NAN, 0, 0}, 0, v), std::invalid_argument);
}

TEST(PlaceOptions, ValidateNamesTheBadOption) {
  LocalizerOptions o;
  o.filter.weight = 2;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  PlaceMeasureOptions m;
  m.keep_fraction = 0;
  EXPECT_THROW(m.Validate(), std::invalid_argument);
  PlaceViewOptions v;
  v.features.method = LandmarkMethod::kVline;
  EXPECT_THROW(v.Validate(), std::invalid_argument);
  EXPECT_EQ(*ParsePlaceMeasure("count"), PlaceMeasure::kMatchCount);
  EXPECT_FALSE(ParsePlaceMeasure("nope"));
}

}  // namespace
}  // namespace snapnav::nav
