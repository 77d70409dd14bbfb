#pragma once
// eval-homing with feature landmarks: one method's evaluation (AAE, return ratio, vector map)
// and the comparison of HOG, vertical lines, SIFT and SURF x ALV variant x landmark count on
// the thesis scenes (4.1-4.3), as markdown, CSV, summary.json and vector maps.

#include <string>
#include <vector>

#include "homing_eval.hpp"
#include "landmark_eval.hpp"
#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace snapnav::eval {

struct LandmarkEvalSetup {
  nav::sim::OmniCameraOptions camera;
  nav::sim::ImageEffectsOptions effects;          // the sim config's [effects], on every view
  nav::HogHomingConfig hog;                       // the HOG row of the comparison
  nav::LandmarkExtractorConfig extractor;         // method-independent parts; method set per row
  nav::LandmarkHomingConfig keypoint_homing, vline_homing;
  CameraPipeline::Input input = CameraPipeline::Input::kRaw;
  ReturnOptions ret;
  uint64_t seed = 1;
  // Several frames per view (homing.ini [view_fusion]): landmark methods fuse them with `fusion`,
  // HOG by the median panorama. 1 and 1: the thesis' single snapshots.
  FrameFusion fusion;
  FrameProtocol frames;
  std::string mask = "none";  // the self-occlusion mask (UseMask): none | truth | FILE; RunLandmarkEval only
  bool random_headings = false;  // grid views at random headings (the rotation from the matches); RunLandmarkEval only
  const nav::LandmarkHomingConfig& homing(nav::LandmarkMethod m) const {
    return m == nav::LandmarkMethod::kVline ? vline_homing : keypoint_homing;
  }
};

// One landmark method on one scene: AAE, return ratio, vector map, summary.json, report.md.
// Returns the process exit code.
int RunLandmarkEval(const LandmarkEvalSetup& setup, const std::string& scene_name, nav::LandmarkMethod method,
                    nav::AlvVariant variant, int top_n, bool no_return, const std::string& out_dir);

struct CompareOptions {
  std::vector<std::string> scenes;     // default: the thesis scenes
  std::vector<int> top_n = {3, 5, 20, 0};
  bool returns = true;                 // return ratio of each method x variant at its best count
  bool return_best_only = false;       // only of each method's best row (and best fused row)
  // Scenes with people: also each method x ALV (at its best count) with the home view fused from
  // fused.home_frames frames, and with the current views fused from fused.current_frames too
  // (people walking between them), persistent and median. Both 1: no fused rows.
  FrameProtocol fused{9, 1.0, 3, 0.5};
};
// The comparison table over scenes x methods x ALV variants x landmark counts.
int RunCompare(const LandmarkEvalSetup& setup, const CompareOptions& options, const std::string& out_dir);

}  // namespace snapnav::eval
