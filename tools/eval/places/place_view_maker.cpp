#include "place_view_maker.hpp"

#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/plot/plot.hpp"
#include "timing.hpp"

namespace snapnav::eval {

PlaceViewMaker::PlaceViewMaker(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera,
                               const nav::sim::ImageEffectsOptions& effects, const std::string& mask,
                               const nav::PlaceViewOptions& view, uint64_t seed)
    : renderer_(scene, camera, seed), view_(view) {
  pipeline_.input = CameraPipeline::Input::kRaw;
  pipeline_.effects = effects;
  mask_ = UseMask(mask, renderer_, cv::Size(camera.omni_width_px, camera.omni_height_px), seed);
  clearance_ = nav::MaskClearance(mask_);
}

nav::PlaceView PlaceViewMaker::Make(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people,
                                    const std::string& save_png, double* render_ms, double* view_ms) {
  auto t0 = Clock::now();
  const cv::Mat panorama = renderer_.ToPanorama(renderer_.Sensor(pose, CameraPipeline::Input::kRaw, people), pipeline_);
  const double rendered = MsSince(t0);
  if (!save_png.empty()) plot::SavePng(panorama, save_png);
  t0 = Clock::now();
  nav::PlaceView v = nav::MakePlaceView(panorama, view_, mask_, clearance_);
  const double made = MsSince(t0);
  render_ms_ += rendered;
  extract_ms_ += made;
  if (render_ms) *render_ms += rendered;
  if (view_ms) *view_ms += made;
  landmarks_ += static_cast<int64_t>(v.landmarks.size());
  ++views_;
  return v;
}

}  // namespace snapnav::eval
