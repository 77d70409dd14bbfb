#pragma once
// Renders what an omnidirectional camera sees in a Scene: the unwrapped
// panorama directly (column ray casting), and the raw catadioptric image by
// remapping a finer panorama through the mirror model (map precomputed once).

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::nav::sim {

// A part of the robot that the camera sees across the mirror (a strut holding the mirror, a
// cable): a bar from (bearing0, radius0) to (bearing1, radius1), radii as fractions of the rim
// radius (beyond 1: over the housing), bearings in the robot frame as omni_geometry.hpp's.
struct RobotPart {
  double bearing0_rad = 0, radius0_frac = 0.4;
  double bearing1_rad = 0, radius1_frac = 1.05;
  double width_frac = 0.03;  // of the rim radius
  double grey = 40;          // its grey level
};

// The camera beyond the ideal mirror: what a real catadioptric camera shows (the `realistic`
// preset; the `clean` camera has none of it). Applied to the raw image only (RenderOmni).
struct CameraOptics {
  bool enabled = false;             // false: the clean camera (everything below ignored)
  double housing_grey = 24;         // the housing around the mirror [grey level]
  double lens_radius_frac = 0.40;   // the camera's own reflection: a disc of this fraction of the rim radius
  double lens_grey = 14;            // its grey level; a lighter ring (the lens barrel) at its edge
  double vignetting = 0.35;         // brightness falls by this fraction from the centre to the rim (quadratic)
  double colour_gain_b = 0.82, colour_gain_g = 1.0, colour_gain_r = 1.10;  // a warm cast
  double shot_noise = 0.3;          // noise variance per grey level: sigma^2 = shot_noise * v + read_noise^2
  double read_noise_grey = 2.0;     // [grey levels]
  double rim_softness_px = 1.5;     // the rim's anti-aliased edge: blend over this width [px]
  std::vector<RobotPart> parts;     // struts and cables across the mirror
  // A bright window at a world bearing (it moves through the image as the robot turns): the
  // scene's brightness times window_gain over [bearing - width/2, bearing + width/2] and the
  // elevations [window_elevation_bottom, window_elevation_top].
  double window_bearing_rad = 3.5;
  double window_width_rad = 0.7;
  double window_elevation_bottom_rad = -0.05;
  double window_elevation_top_rad = 0.35;
  double window_gain = 2.2;
  // The calibration the frames carry is off by this from the mirror the renderer uses, as a real
  // calibration is [px]; its inner radius is the reflection's edge (ReportedMirror).
  double calibration_error_x_px = 1.6;
  double calibration_error_y_px = -1.1;
  double calibration_error_radius_px = -1.3;
  // Auto-exposure: the camera meters the mean grey of what the mirror shows and moves its gain a
  // share `exposure_rate` of the way (in log) to the gain that gives exposure_target_grey, each
  // frame (1: at once; the first frame starts settled), within [exposure_min, exposure_max]: a
  // bright window in view darkens the rest of the image, and it lags a turn by a few frames.
  bool auto_exposure = true;
  double exposure_target_grey = 100;
  double exposure_rate = 0.5;
  double exposure_min = 0.5, exposure_max = 2.5;
  // The camera's own compression, as a USB camera's MJPEG stream [1..100; 0: none]: the image
  // carries JPEG's block and ringing artefacts (and the sim publishes the camera's bytes).
  int jpeg_quality = 90;
  // Motion blur: the shutter is open exposure_time_s x the auto-exposure's gain; each pixel is
  // smeared along the bearing by how far its scene point turns in that time (the robot's turn
  // rate, and its speed over the point's distance). 0: no blur.
  double exposure_time_s = 0.02;
  uint64_t seed = 1;                // sensor noise
  void Validate() const;            // throws std::invalid_argument
};
// The shipped presets: "clean" (no optics) and "realistic" (the values above with three struts
// and a cable). Throws std::invalid_argument on another name.
CameraOptics CameraOpticsPreset(const std::string& name);

// The robot's motion while a frame is exposed (motion blur; ignored by the clean camera).
struct CameraMotion {
  double linear_mps = 0;
  double angular_radps = 0;
};

struct OmniCameraOptions {
  double height_m = 0.55;   // optical centre above the floor [m]
  double offset_x_m = 0.0;  // position on the robot, forward [m]
  int omni_width_px = 640;
  int omni_height_px = 480;
  MirrorModel mirror;       // raw image geometry (centre, radii, elevations): the truth the renderer uses
  PanoramaModel panorama;   // geometry of panoramas rendered directly
  CameraOptics optics;      // clean by default
  void Validate() const;    // throws std::invalid_argument
  // The calibration a frame carries: `mirror` for the clean camera; with optics, the centre and
  // rim off by the calibration error, the inner radius at the camera's reflection (2 px outside
  // it), the elevations from the mirror's profile at those radii.
  MirrorModel ReportedMirror() const;
};

// Image degradations applied after rendering (thesis 3.1.4-3.1.5 test conditions).
struct ImageEffectsOptions {
  double blur_sigma_px = 0;        // Gaussian blur
  double noise_sigma = 0;          // additive Gaussian noise [grey levels]
  double salt_pepper_fraction = 0; // share of pixels set to 0 or 255
  double gain = 1.0;               // illumination: out = gain * in + offset
  double offset = 0.0;             // [grey levels]
  void Validate() const;
  bool IsIdentity() const {        // changes no pixel
    return blur_sigma_px == 0 && noise_sigma == 0 && salt_pepper_fraction == 0 && gain == 1.0 && offset == 0.0;
  }
};
void ApplyImageEffects(const ImageEffectsOptions& options, std::mt19937_64& rng, cv::Mat* image);

class OmniRenderer {
 public:
  OmniRenderer(const Scene& scene, const OmniCameraOptions& options);

  // Panorama (CV_8UC3, options.panorama size) seen from robot pose `robot`; `people` are extra cylinders.
  void RenderPanorama(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out) const;
  // Raw catadioptric image (CV_8UC3, omni_width_px x omni_height_px), with the optics when enabled
  // (each call draws new sensor noise, moves the auto-exposure and blurs by `motion`). With the
  // camera's own JPEG (optics.jpeg_quality > 0), `out` is the decoded JPEG; when `jpeg` is given,
  // the camera's JPEG bytes go there and `out` is the image before compression (no decode: a
  // process that publishes the camera's bytes); `jpeg` is cleared when the camera does not compress.
  void RenderOmni(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out,
                  const CameraMotion& motion = {}, std::vector<uint8_t>* jpeg = nullptr);
  // The auto-exposure's gain of the last frame (1 for the clean camera).
  double exposure() const { return exposure_; }
  // The pixels of the robot's own parts in the raw image (image_mask.hpp's convention: 0 = a
  // part, 255 = usable; every pixel the parts cover by at least 2 %), the truth a calibration's mask
  // estimates. All usable for the clean camera.
  cv::Mat PartsMask() const;

  const OmniCameraOptions& options() const { return options_; }

 private:
  // Rows [0, rows) of the panorama (rows < 0: all); `depth`, when given, gets each column's nearest
  // surface distance [m].
  void Render(const PanoramaModel& model, const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out,
              int rows = -1, std::vector<float>* depth = nullptr) const;
  void MeterExposure(const cv::Mat& fine);
  void ApplyMotionBlur(const CameraMotion& motion, cv::Mat* fine);
  void BuildOptics(const cv::Mat& map_y);  // map_y: each raw pixel's fine panorama row
  void ApplyWindow(const Pose2& robot, cv::Mat* fine) const;
  void ApplyOptics(cv::Mat* image);

  const Scene& scene_;
  OmniCameraOptions options_;
  PanoramaModel fine_;     // the panorama the raw image is remapped from
  cv::Mat remap_xy_, remap_frac_;  // raw pixel -> fine panorama pixel, in cv::remap's fixed-point form
  cv::Mat fine_image_;
  // Optics, per raw pixel and channel: out = (content * gain + offset) / 256 + noise (fixed point).
  std::vector<uint16_t> optics_gain_;
  std::vector<uint16_t> optics_offset_;
  cv::Mat parts_alpha_;              // CV_32F, the parts' coverage
  std::vector<float> noise_table_;   // standard normal samples
  std::array<float, 256> noise_sigma_{};  // sigma per grey level
  uint64_t noise_state_ = 0;
  int render_rows_ = -1;             // fine panorama rows that reach a visible pixel (the rest is under the lens)
  double exposure_ = 1.0;
  bool exposure_settled_ = false;    // false until the first frame
  std::vector<float> column_depth_;  // nearest surface per fine column [m] (motion blur)
  std::vector<int32_t> prefix_;      // motion blur's running sums
  std::vector<uint8_t> jpeg_;
};

}  // namespace snapnav::nav::sim
