#pragma once
// A place view of a simulated pose made the way the robot's pipeline makes it: the raw omni image
// rendered, unwrapped (with the camera's image effects), masked and turned into a nav::PlaceView.
// Shared by the localization and route evaluations; times both steps.
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "homing_eval.hpp"
#include "snapnav/nav/places/place_cells.hpp"

namespace snapnav::eval {

class PlaceViewMaker {
 public:
  // mask: the raw frames' self-occlusion mask, as UseMask reads it (none | calibrated | truth | FILE).
  PlaceViewMaker(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera,
                 const nav::sim::ImageEffectsOptions& effects, const std::string& mask, const nav::PlaceViewOptions& view,
                 uint64_t seed);
  // The view at `pose` among `people`; the panorama also written to save_png when it is not empty.
  // The time taken is added to *render_ms and *view_ms where they are given.
  nav::PlaceView Make(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people,
                      const std::string& save_png = "", double* render_ms = nullptr, double* view_ms = nullptr);
  const nav::PanoramaModel& panorama() const { return renderer_.panorama_model(); }
  int views() const { return views_; }
  double render_ms() const { return views_ ? render_ms_ / views_ : 0; }   // per view: render + unwrap
  double extract_ms() const { return views_ ? extract_ms_ / views_ : 0; }  // per view: MakePlaceView
  double mean_landmarks() const { return views_ ? static_cast<double>(landmarks_) / views_ : 0; }

 private:
  ViewRenderer renderer_;
  CameraPipeline pipeline_;
  nav::PlaceViewOptions view_;
  cv::Mat mask_;       // the panoramas' mask (empty: none)
  cv::Mat clearance_;  // its nav::MaskClearance, computed once
  int views_ = 0;
  int64_t landmarks_ = 0;
  double render_ms_ = 0, extract_ms_ = 0;
};

}  // namespace snapnav::eval
