#pragma once
// Homing evaluation over a scene's grid database (thesis 3.1.4, Appendix A):
// the image database, the angular error at every grid position, the average
// angular error (AAE), and the closed-loop return ratio with images rendered at
// the robot's actual pose.

#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/homing/unwrap.hpp"

namespace snapnav::eval {

// A homing method under test: set a home view, then ask for the direction home.
class HomingMethod {
 public:
  virtual ~HomingMethod() = default;
  virtual std::string name() const = 0;
  virtual void SetHome(const cv::Mat& panorama) = 0;
  virtual std::optional<nav::HomingEstimate> Home(const cv::Mat& panorama) = 0;
  // Several frames of one still view (the robot standing for a few seconds, people walking):
  // a method that fuses them overrides these; the default uses the first frame.
  virtual void SetHomeFrames(const std::vector<cv::Mat>& frames) { SetHome(frames.front()); }
  virtual std::optional<nav::HomingEstimate> HomeFrames(const std::vector<cv::Mat>& frames) {
    return Home(frames.front());
  }
  // The panoramas' self-occlusion mask (image_mask.hpp; empty: none), before the home. A method
  // that cannot use one throws std::logic_error for a non-empty mask.
  virtual void SetMask(const cv::Mat& panorama_mask);
};

class HogMethod : public HomingMethod {
 public:
  // median_frames: several frames of a view are fused into their per-pixel median panorama.
  HogMethod(const nav::HogHomingConfig& config, const nav::PanoramaModel& panorama, bool median_frames = false)
      : homer_(config, panorama), median_frames_(median_frames) {}
  std::string name() const override { return median_frames_ ? "hog median" : "hog"; }
  void SetHome(const cv::Mat& panorama) override { homer_.SetHome(panorama); }
  std::optional<nav::HomingEstimate> Home(const cv::Mat& panorama) override { return homer_.Home(panorama); }
  void SetHomeFrames(const std::vector<cv::Mat>& frames) override;
  std::optional<nav::HomingEstimate> HomeFrames(const std::vector<cv::Mat>& frames) override;
  void SetMask(const cv::Mat& panorama_mask) override { homer_.SetMask(panorama_mask); }

 private:
  nav::HogHomer homer_;
  bool median_frames_;
};

// How images reach the method: rendered as raw catadioptric images and unwrapped (the
// real pipeline), or rendered directly as panoramas; with optional image effects.
struct CameraPipeline {
  enum class Input { kRaw, kPanorama } input = Input::kRaw;
  nav::sim::ImageEffectsOptions effects;
  double low_resolution_scale = 1.0;  // < 1: downsample (nearest) and back (thesis fig. 3.12 b)
};

// Raw images are unwrapped with the calibration a frame would carry (the camera's
// ReportedMirror: off by a few pixels with the realistic optics), as the processes do.
class ViewRenderer {
 public:
  ViewRenderer(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera, uint64_t seed);
  const nav::sim::Scene& scene() const { return *scene_; }
  // The sensor image (raw or panorama) seen from `pose`, before effects.
  cv::Mat Sensor(const nav::Pose2& pose, CameraPipeline::Input input, const std::vector<nav::sim::Cylinder>& people);
  // Effects and unwrap: sensor image -> panorama given to the method (masked pixels filled).
  cv::Mat ToPanorama(const cv::Mat& sensor, const CameraPipeline& pipeline);
  const nav::PanoramaModel& panorama_model() const { return camera_.panorama; }
  // The raw images' self-occlusion mask for the unwrap (empty: none).
  void SetMask(const cv::Mat& raw_mask) { unwrapper_.SetMask(raw_mask); }
  // The unwrapped panoramas' mask (empty without one): what the methods ignore.
  const cv::Mat& panorama_mask() const { return unwrapper_.panorama_mask(); }
  // The robot's parts the renderer draws (the realistic optics; all usable for the clean camera).
  cv::Mat PartsMask() const { return renderer_.PartsMask(); }
  const nav::sim::OmniCameraOptions& camera() const { return camera_; }

 private:
  const nav::sim::Scene* scene_;
  nav::sim::OmniCameraOptions camera_;
  nav::sim::OmniRenderer renderer_;
  nav::Unwrapper unwrapper_;
  std::mt19937_64 rng_;
};

// The mask the evaluation's processing side uses, by `source`: "none" (empty), "calibrated"
// (calibrate-mirror's mask of 60 frames of the camera, calibrated_mask.hpp; `seed` their headings),
// "truth" (the renderer's robot parts grown by 2 px, the margin calibrate-mirror adds), or a mask
// image file (image_mask.hpp's convention, black = masked; of the raw image's size). Set on
// `renderer`; returns the panorama mask (empty for none). Throws std::runtime_error on a bad file.
cv::Mat UseMask(const std::string& source, ViewRenderer& renderer, cv::Size raw_size, uint64_t seed = 1);
// The same in two steps, for a second renderer of the same camera (a scene without its people) to
// take the first one's mask instead of calibrating again: the raw mask by `source` (empty for none),
// and setting it (returns the panorama mask).
cv::Mat RawMask(const std::string& source, const ViewRenderer& renderer, cv::Size raw_size, uint64_t seed = 1);
cv::Mat UseRawMask(const cv::Mat& raw_mask, ViewRenderer& renderer);

// How many frames of one view a still robot takes (people walking between them): the home
// view (taken once, the robot can stand for a while) and each current view (a robot that
// pauses to look). 1 and 1: the thesis' single snapshots.
struct FrameProtocol {
  int home_frames = 1;
  double home_interval_s = 1.0;     // people walk this long between home frames
  int current_frames = 1;
  double current_interval_s = 0.5;  // ... and between the frames of a current view
  void Validate() const;            // throws std::invalid_argument
  bool fused() const { return home_frames > 1 || current_frames > 1; }
};

// The grid image database: one sensor image per grid position.
struct GridDatabase {
  int nx = 0, ny = 0;
  std::vector<nav::Pose2> poses;   // true poses, index iy * nx + ix
  std::vector<cv::Mat> sensor;     // sensor images (raw or panorama)
  std::vector<std::vector<nav::sim::Cylinder>> people;  // the people in each image (scenes with people)
  // Further frames of each position (GridOptions::frames): the robot stays, the people walk
  // between frames. Frame 0 is `sensor`.
  std::vector<std::vector<cv::Mat>> more_sensor;
  std::vector<std::vector<std::vector<nav::sim::Cylinder>>> more_people;  // the people in those frames
  int home_index = 0;
  nav::Pose2 home;
};
struct GridOptions {
  std::optional<Eigen::Vector2d> home;  // default: the grid centre
  bool random_headings = false;         // else heading 0 everywhere (the home is always heading 0)
  uint64_t seed = 1;
  CameraPipeline::Input input = CameraPipeline::Input::kRaw;
  // Image effects (the sim config's [effects]) of the panoramas made from the database: RenderGrid
  // keeps the sensor images clean, the callers' CameraPipeline applies these.
  nav::sim::ImageEffectsOptions effects;
  // Frames per position: at home, and at the other positions. The first frame of every position
  // does not depend on these (the extra frames walk a copy of the crowd).
  FrameProtocol frames;
};
GridDatabase RenderGrid(const nav::sim::Scene& scene, ViewRenderer& renderer, const GridOptions& options,
                        const std::function<void(int, int)>& progress = {});

struct GridResult {
  std::vector<double> error_rad;   // per grid position, NaN at home; pi where no estimate
  std::vector<double> direction_world_rad;  // estimated direction in the world frame (NaN: none)
  std::vector<double> compass_error_rad;    // |compass rotation - true rotation| (NaN at home)
  int positions = 0, failures = 0;
  double aae_deg = 0, median_deg = 0, max_deg = 0, compass_mean_deg = 0;
  double seconds_in_method = 0;   // time spent in Home() calls
  int method_calls = 0;
};
// Angular error at every grid position (thesis' AAE), on the database's panoramas (index as
// db.poses).
GridResult EvaluatePanoramas(const GridDatabase& db, const std::vector<cv::Mat>& panoramas, HomingMethod& method);
// The same with several frames per position (frames[i]: the frames of position i, given to
// SetHomeFrames at home and to HomeFrames elsewhere).
GridResult EvaluateFrames(const GridDatabase& db, const std::vector<std::vector<cv::Mat>>& frames, HomingMethod& method);

struct ReturnOptions {
  double step_m = 0.1;
  double success_radius_m = 0.2;
  double max_path_factor = 3.0;  // path length limit: this times the straight-line distance
  // Scenes with people: they walk this long per step (the robot's 0.1 m at about 0.25 m/s), around
  // the robot; each start has its own crowd (seeded by the start), walked warm_up_s first.
  double people_dt_s = 0.4;
  double people_warm_up_s = 10.0;
  uint64_t seed = 1;
  // home_frames: frames of the home view (from the grid database); current_frames: frames per
  // step (the robot pauses, the people walk current_interval_s between them).
  FrameProtocol frames;
  int start_stride = 1;          // every n-th start only (a stated sample for long runs)
};
struct ReturnRun {
  std::vector<Eigen::Vector2d> path;
  bool success = false;
  double path_length_m = 0;
};
struct ReturnResult {
  std::vector<ReturnRun> runs;  // one per start (grid positions outside the success radius)
  int starts = 0, successes = 0;
  double ratio = 0;
  double mean_path_ratio = 0;   // successful runs: path length / (straight-line distance - success radius)
};
// Closed loop: from each grid position, step along the computed vector (the robot turns to
// face it), rendering the view at the actual pose each step (with the scene's people walking
// around the robot). The home view and the first view of each start come from the database:
// `panorama_frames` (the frames of each position as panoramas) if given, else db.sensor and
// db.more_sensor through `pipeline`.
ReturnResult EvaluateReturn(const GridDatabase& db, HomingMethod& method, ViewRenderer& renderer,
                            const CameraPipeline& pipeline, const ReturnOptions& options,
                            const std::function<void(int, int)>& progress = {},
                            const std::vector<std::vector<cv::Mat>>* panorama_frames = nullptr);

// Vector map (thesis figs. 3.6-3.7): an arrow per grid position, coloured by error, the home
// marked; with return paths if given.
cv::Mat DrawVectorMap(const GridDatabase& db, const GridResult& result, const std::string& title,
                      const ReturnResult* paths = nullptr);

}  // namespace snapnav::eval
