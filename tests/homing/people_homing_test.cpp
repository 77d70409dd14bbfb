// Homing among walking people, rendered in the people11 room: a home snapshot taken while
// people stand close to the camera breaks the thesis' single-snapshot landmark homing; the same
// home fused from frames of a still robot over a few seconds (the people walk on) points home.
#include <gtest/gtest.h>

#include <cmath>

#include "homing_eval.hpp"
#include "landmark_eval.hpp"
#include "people_view.hpp"
#include "scene_file.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::eval {
namespace {

nav::sim::OmniCameraOptions Camera() {
  nav::sim::OmniCameraOptions c;
  c.panorama.width_px = 720;
  c.panorama.height_px = 120;
  c.panorama.elevation_top_rad = 20 * M_PI / 180;
  c.panorama.elevation_bottom_rad = -20 * M_PI / 180;
  return c;
}

// Mean angular error [deg] of `method` over `poses` (people-free current views), home at `home`.
double MeanError(HomingMethod& method, ViewRenderer& renderer, const std::vector<nav::Pose2>& poses,
                 const nav::Pose2& home) {
  double sum = 0;
  for (const auto& p : poses) {
    const auto e = method.Home(renderer.Sensor(p, CameraPipeline::Input::kPanorama, {}));
    double err = M_PI;
    if (e) {
      const double truth = std::atan2(home.y_m - p.y_m, home.x_m - p.x_m);
      err = std::abs(nav::WrapAngle(e->direction_rad + p.theta_rad - truth));
    }
    sum += err;
  }
  return sum / poses.size() * 180 / M_PI;
}

TEST(PeopleHoming, FusedHomeSnapshotPointsHomeWhereASingleOneFails) {
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath("people11"));
  const auto camera = Camera();
  ViewRenderer renderer(scene, camera, 1);
  const PeopleView people_view(scene, camera);
  const nav::Pose2 home{3.5, 3.0, 0};
  // Walk the crowd around the robot at home until someone stands close to the camera and the
  // people cover 40% of the view: the snapshot a robot should not rely on.
  nav::sim::World crowd(scene, {}, {}, 7);
  crowd.SetTruePose(home);
  int steps = 0;
  for (; steps < 3000; ++steps) {
    const auto m = people_view.Measure(home, crowd.people());
    if (m.nearest_surface_m < 0.25 && m.occluded_fraction > 0.4) break;
    crowd.Step(0, 0, 0.1);
  }
  ASSERT_LT(steps, 3000) << "no crowded moment at home";
  // Nine frames a second apart; the first is the crowded one.
  std::vector<cv::Mat> home_frames;
  for (int k = 0; k < 9; ++k) {
    home_frames.push_back(renderer.Sensor(home, CameraPipeline::Input::kPanorama, crowd.people()));
    for (int s = 0; s < 10; ++s) crowd.Step(0, 0, 0.1);
  }
  // Current views 0.6-1.2 m from home all around, without people (the home is what is tested).
  std::vector<nav::Pose2> poses;
  for (int i = 0; i < 12; ++i) {
    const double a = i * M_PI / 6, r = 0.6 + 0.05 * i;
    poses.push_back({home.x_m + r * std::cos(a), home.y_m + r * std::sin(a), 0});
  }
  nav::LandmarkExtractorConfig extractor;
  extractor.method = nav::LandmarkMethod::kSift;
  extractor.sift.max_features = 300;
  nav::LandmarkHomingConfig homing;
  homing.alv.variant = nav::AlvVariant::kScale;
  homing.alv.consensus = true;
  homing.alv.consensus_window_rad = 35 * M_PI / 180;

  LandmarkMethod single(extractor, homing, camera.panorama);
  single.SetHomeFrames({home_frames.front()});
  const double single_error = MeanError(single, renderer, poses, home);

  FrameFusion persistent;
  persistent.persistence.min_fraction = 0.2;
  LandmarkMethod fused(extractor, homing, camera.panorama, nullptr, persistent);
  fused.SetHomeFrames(home_frames);
  const double fused_error = MeanError(fused, renderer, poses, home);

  FrameFusion median;
  median.mode = nav::ViewFusion::kMedian;
  LandmarkMethod fused_median(extractor, homing, camera.panorama, nullptr, median);
  fused_median.SetHomeFrames(home_frames);
  const double median_error = MeanError(fused_median, renderer, poses, home);

  LandmarkMethod empty(extractor, homing, camera.panorama);
  empty.SetHome(renderer.Sensor(home, CameraPipeline::Input::kPanorama, {}));
  const double empty_error = MeanError(empty, renderer, poses, home);

  std::cout << "mean error: single crowded snapshot " << single_error << " deg, persistent 9 frames " << fused_error
            << ", median 9 frames " << median_error << ", people-free home " << empty_error << "\n";
  // Measured: 10.8 deg from the crowded snapshot, 1.9 fused either way, 1.8 from the empty room.
  EXPECT_LT(empty_error, 4);
  EXPECT_GT(single_error, 8);
  EXPECT_LT(fused_error, 4);
  EXPECT_LT(median_error, 4);
}

}  // namespace
}  // namespace snapnav::eval
