#pragma once
// Renders what an omnidirectional camera sees in a Scene: the unwrapped
// panorama directly (column ray casting), and the raw catadioptric image by
// remapping a finer panorama through the mirror model (map precomputed once).

#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::nav::sim {

struct OmniCameraOptions {
  double height_m = 0.55;   // optical centre above the floor [m]
  double offset_x_m = 0.0;  // position on the robot, forward [m]
  int omni_width_px = 640;
  int omni_height_px = 480;
  MirrorModel mirror;       // raw image geometry (centre, radii, elevations)
  PanoramaModel panorama;   // geometry of panoramas rendered directly
  void Validate() const;    // throws std::invalid_argument
};

// Image degradations applied after rendering (thesis 3.1.4-3.1.5 test conditions).
struct ImageEffectsOptions {
  double blur_sigma_px = 0;        // Gaussian blur
  double noise_sigma = 0;          // additive Gaussian noise [grey levels]
  double salt_pepper_fraction = 0; // share of pixels set to 0 or 255
  double gain = 1.0;               // illumination: out = gain * in + offset
  double offset = 0.0;             // [grey levels]
  void Validate() const;
};
void ApplyImageEffects(const ImageEffectsOptions& options, std::mt19937_64& rng, cv::Mat* image);

class OmniRenderer {
 public:
  OmniRenderer(const Scene& scene, const OmniCameraOptions& options);

  // Panorama (CV_8UC3, options.panorama size) seen from robot pose `robot`; `people` are extra cylinders.
  void RenderPanorama(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out) const;
  // Raw catadioptric image (CV_8UC3, omni_width_px x omni_height_px).
  void RenderOmni(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out);

  const OmniCameraOptions& options() const { return options_; }

 private:
  void Render(const PanoramaModel& model, const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out) const;

  const Scene& scene_;
  OmniCameraOptions options_;
  PanoramaModel fine_;     // the panorama the raw image is remapped from
  cv::Mat map_x_, map_y_;  // raw pixel -> fine panorama pixel
  cv::Mat fine_image_;
};

}  // namespace snapnav::nav::sim
