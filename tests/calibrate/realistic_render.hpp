#pragma once
// Realistic catadioptric renders with known truth for the calibration and mask tests: the
// simulator's `realistic` optics on a shipped scene, at any image size, mirror centre and radius,
// housing brightness, noise and rim softness.

#include <map>
#include <opencv2/core.hpp>
#include <string>

#include "scene_file.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace snapnav::testing {

struct RenderCase {
  std::string scene = "indoor13";
  int width = 640, height = 480;
  double cx = 320, cy = 240, radius = 230;
  double housing_grey = 24;
  double lens_grey = 14;
  double read_noise = 2.0, shot_noise = 0.3;
  double rim_softness = 1.5;
  double vignetting = 0.35;
  uint64_t seed = 1;
  nav::Pose2 pose{0, 0, 0.3};  // inside the scene (the scene's start when zero)
  std::string Name() const {
    return scene + " " + std::to_string(width) + "x" + std::to_string(height) + " c(" + std::to_string(cx) + "," +
           std::to_string(cy) + ") R" + std::to_string(radius) + " housing " + std::to_string(housing_grey) + " seed " +
           std::to_string(seed);
  }
};

inline nav::sim::OmniCameraOptions RealisticCamera(const RenderCase& c) {
  nav::sim::OmniCameraOptions o;
  o.omni_width_px = c.width;
  o.omni_height_px = c.height;
  o.mirror.center_x_px = c.cx;
  o.mirror.center_y_px = c.cy;
  o.mirror.outer_radius_px = c.radius;
  o.mirror.inner_radius_px = 40.0 / 230.0 * c.radius;
  o.mirror.elevation_inner_rad = -40 * M_PI / 180;
  o.mirror.elevation_outer_rad = 20 * M_PI / 180;
  o.panorama.elevation_top_rad = 20 * M_PI / 180;  // as config/sim.ini's [panorama]
  o.panorama.elevation_bottom_rad = -20 * M_PI / 180;
  o.optics = nav::sim::CameraOpticsPreset("realistic");
  o.optics.housing_grey = c.housing_grey;
  o.optics.lens_grey = c.lens_grey;
  o.optics.read_noise_grey = c.read_noise;
  o.optics.shot_noise = c.shot_noise;
  o.optics.rim_softness_px = c.rim_softness;
  o.optics.vignetting = c.vignetting;
  o.optics.seed = c.seed;
  return o;
}

inline const nav::sim::Scene& SharedScene(const std::string& name) {
  static std::map<std::string, nav::sim::Scene> scenes;
  auto it = scenes.find(name);
  if (it == scenes.end()) it = scenes.emplace(name, processes::LoadSceneFile(processes::SceneFilePath(name))).first;
  return it->second;
}

inline nav::Pose2 PoseIn(const nav::sim::Scene& scene, const nav::Pose2& pose) {
  if (pose.x_m == 0 && pose.y_m == 0) return {scene.start_pose.x(), scene.start_pose.y(), pose.theta_rad};
  return pose;
}

inline cv::Mat RenderRealistic(const RenderCase& c) {
  const auto& scene = SharedScene(c.scene);
  nav::sim::OmniRenderer r(scene, RealisticCamera(c));
  cv::Mat image;
  r.RenderOmni(PoseIn(scene, c.pose), {}, &image);
  return image;
}

}  // namespace snapnav::testing
