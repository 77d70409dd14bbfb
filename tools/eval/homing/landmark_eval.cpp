#include "landmark_eval.hpp"

#include <algorithm>
#include <chrono>

namespace snapnav::eval {
namespace {
using Clock = std::chrono::steady_clock;
}

LandmarkCache ExtractAll(const std::vector<cv::Mat>& panoramas, const nav::LandmarkExtractorConfig& config,
                         const cv::Mat& mask) {
  LandmarkCache cache;
  cache.sets.reserve(panoramas.size());
  double total = 0;
  const cv::Mat clearance = nav::MaskClearance(mask);
  for (size_t i = 0; i < panoramas.size(); ++i) {
    const auto t0 = Clock::now();
    cache.sets.push_back(nav::ExtractLandmarks(panoramas[i], config, mask, clearance));
    cache.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    cache.index[panoramas[i].data] = static_cast<int>(i);
    total += cache.sets.back().size();
  }
  cache.mean_landmarks = panoramas.empty() ? 0 : total / panoramas.size();
  return cache;
}

LandmarkMethod::LandmarkMethod(const nav::LandmarkExtractorConfig& extractor, const nav::LandmarkHomingConfig& homing,
                               const nav::PanoramaModel& panorama, const LandmarkCache* cache,
                               const FrameFusion& fusion)
    : extractor_(extractor), fusion_(fusion), homer_(homing, panorama), cache_(cache) {
  extractor_.Validate();
  fusion_.persistence.Validate();
}

std::string LandmarkMethod::name() const {
  return LandmarkLabel(extractor_.method, homer_.config().alv.variant, homer_.config().alv.top_n);
}

const nav::LandmarkSet& LandmarkMethod::Landmarks(const cv::Mat& panorama) {
  if (cache_) {
    const auto it = cache_->index.find(panorama.data);
    if (it != cache_->index.end()) return cache_->sets[it->second];
  }
  const auto t0 = Clock::now();
  scratch_ = nav::ExtractLandmarks(panorama, extractor_, mask_, clearance_);
  extract_seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
  ++extracted_;
  return scratch_;
}

void LandmarkMethod::SetHome(const cv::Mat& panorama) { homer_.SetHome(Landmarks(panorama)); }

std::optional<nav::HomingEstimate> LandmarkMethod::Home(const cv::Mat& panorama) { return HomeSet(Landmarks(panorama)); }

std::optional<nav::HomingEstimate> LandmarkMethod::HomeSet(const nav::LandmarkSet& set) {
  const auto r = homer_.Home(set);
  if (!r) return std::nullopt;
  matches_ += r->matches;
  ++estimates_;
  return r->estimate;
}

nav::LandmarkSet LandmarkMethod::Fused(const std::vector<cv::Mat>& frames) {
  if (frames.size() == 1) return Landmarks(frames.front());
  if (fusion_.mode == nav::ViewFusion::kMedian) {
    const auto t0 = Clock::now();
    nav::LandmarkSet set = nav::ExtractLandmarks(nav::MedianImage(frames), extractor_, mask_, clearance_);
    extract_seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
    ++extracted_;
    return set;
  }
  std::vector<nav::LandmarkSet> sets;
  for (const auto& f : frames) sets.push_back(Landmarks(f));
  return nav::PersistentLandmarks(sets, fusion_.persistence);
}

void LandmarkMethod::SetHomeFrames(const std::vector<cv::Mat>& frames) {
  if (frames.size() == 1) return SetHome(frames.front());
  homer_.SetHome(Fused(frames));
}

std::optional<nav::HomingEstimate> LandmarkMethod::HomeFrames(const std::vector<cv::Mat>& frames) {
  if (frames.size() == 1) return Home(frames.front());
  return HomeSet(Fused(frames));
}

Grid RenderScene(const nav::sim::Scene& scene, const GridOptions& options, ViewRenderer& renderer,
                 const std::function<void(int, int)>& progress) {
  Grid g;
  g.scene = scene;
  CameraPipeline pipeline;
  pipeline.input = options.input;
  pipeline.effects = options.effects;
  g.db = RenderGrid(scene, renderer, options, progress);
  for (size_t i = 0; i < g.db.sensor.size(); ++i) {
    g.panos.push_back(renderer.ToPanorama(g.db.sensor[i], pipeline));
    g.frames.push_back({g.panos.back()});
    g.frame_people.push_back({g.db.people[i]});
    for (const auto& p : g.db.more_people[i]) g.frame_people.back().push_back(p);
    for (const auto& s : g.db.more_sensor[i]) g.frames.back().push_back(renderer.ToPanorama(s, pipeline));
    g.db.more_sensor[i].clear();
  }
  return g;
}

std::vector<std::vector<cv::Mat>> Grid::Frames(int n_home, int n_current) const {
  std::vector<std::vector<cv::Mat>> out;
  for (size_t i = 0; i < frames.size(); ++i) {
    const int n = static_cast<int>(i) == db.home_index ? n_home : n_current;
    out.emplace_back(frames[i].begin(), frames[i].begin() + std::clamp<int>(n, 1, static_cast<int>(frames[i].size())));
  }
  return out;
}

std::vector<cv::Mat> Grid::AllPanoramas() const {
  std::vector<cv::Mat> all;
  for (const auto& f : frames) all.insert(all.end(), f.begin(), f.end());
  return all;
}

std::string LandmarkLabel(nav::LandmarkMethod method, nav::AlvVariant variant, int top_n) {
  return std::string(nav::LandmarkMethodName(method)) + " " + nav::AlvVariantName(variant) + " " +
         (top_n > 0 ? "top" + std::to_string(top_n) : std::string("all"));
}

}  // namespace snapnav::eval
