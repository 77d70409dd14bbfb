#pragma once
// Homing with feature landmarks (thesis 4.1-4.3) in the chapter 3 evaluation: a HomingMethod
// that extracts landmarks from each panorama (or takes them from a cache of the grid
// database's sets, so that ALV variants are compared on the same landmarks) and homes with
// the landmark ALV.

#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "homing_eval.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/landmarks/view_fusion.hpp"

namespace snapnav::eval {

// Landmark sets of a list of panoramas, extracted once, with the time it took.
struct LandmarkCache {
  std::vector<nav::LandmarkSet> sets;
  std::unordered_map<const unsigned char*, int> index;  // panorama pixel buffer -> set
  double seconds = 0;                                    // extraction, all panoramas
  double mean_landmarks = 0;
  double ms_per_panorama() const { return sets.empty() ? 0 : seconds * 1000 / sets.size(); }
};
// `mask`: the panoramas' self-occlusion mask (empty: none).
LandmarkCache ExtractAll(const std::vector<cv::Mat>& panoramas, const nav::LandmarkExtractorConfig& config,
                         const cv::Mat& mask = cv::Mat());

// How a landmark method fuses several frames of one view (view_fusion.hpp).
struct FrameFusion {
  nav::ViewFusion mode = nav::ViewFusion::kPersistent;
  nav::PersistenceOptions persistence;
};

class LandmarkMethod : public HomingMethod {
 public:
  LandmarkMethod(const nav::LandmarkExtractorConfig& extractor, const nav::LandmarkHomingConfig& homing,
                 const nav::PanoramaModel& panorama, const LandmarkCache* cache = nullptr,
                 const FrameFusion& fusion = {});
  std::string name() const override;
  void SetHome(const cv::Mat& panorama) override;
  std::optional<nav::HomingEstimate> Home(const cv::Mat& panorama) override;
  void SetHomeFrames(const std::vector<cv::Mat>& frames) override;
  std::optional<nav::HomingEstimate> HomeFrames(const std::vector<cv::Mat>& frames) override;
  // Landmarks it extracts itself drop the masked ones (a cache's sets are as ExtractAll made them).
  void SetMask(const cv::Mat& panorama_mask) override {
    mask_ = panorama_mask;
    clearance_ = nav::MaskClearance(mask_);
  }
  // The landmark set several frames fuse into.
  nav::LandmarkSet Fused(const std::vector<cv::Mat>& frames);
  // Extraction time of panoramas not found in the cache.
  double extract_seconds() const { return extract_seconds_; }
  int extracted() const { return extracted_; }
  int64_t matches() const { return matches_; }
  int64_t estimates() const { return estimates_; }

 private:
  const nav::LandmarkSet& Landmarks(const cv::Mat& panorama);
  std::optional<nav::HomingEstimate> HomeSet(const nav::LandmarkSet& set);
  nav::LandmarkExtractorConfig extractor_;
  FrameFusion fusion_;
  nav::LandmarkHomer homer_;
  const LandmarkCache* cache_;
  nav::LandmarkSet scratch_;
  cv::Mat mask_;
  cv::Mat clearance_;  // nav::MaskClearance(mask_), computed once
  double extract_seconds_ = 0;
  int extracted_ = 0;
  int64_t matches_ = 0, estimates_ = 0;
};

// A scene's grid database and the panoramas the methods see.
struct Grid {
  nav::sim::Scene scene;
  GridDatabase db;
  std::vector<cv::Mat> panos;
  std::vector<std::vector<cv::Mat>> frames;  // every frame of each position; frames[i][0] is panos[i]
  std::vector<std::vector<std::vector<nav::sim::Cylinder>>> frame_people;  // the people in each of them
  // The first n frames of each position (n_home at home); fewer where fewer were rendered.
  std::vector<std::vector<cv::Mat>> Frames(int n_home, int n_current) const;
  std::vector<cv::Mat> AllPanoramas() const;  // every frame, for ExtractAll
};
// options.input, seed and frames are used. The sensor
// images of the extra frames are dropped once converted (db.more_sensor is emptied).
Grid RenderScene(const nav::sim::Scene& scene, const GridOptions& options, ViewRenderer& renderer,
                 const std::function<void(int, int)>& progress = {});

// Short label of a configuration: "sift weighted top20", "surf scale all".
std::string LandmarkLabel(nav::LandmarkMethod method, nav::AlvVariant variant, int top_n);

}  // namespace snapnav::eval
