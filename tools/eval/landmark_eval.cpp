#include "landmark_eval.hpp"

#include <chrono>

namespace snapnav::eval {
namespace {
using Clock = std::chrono::steady_clock;
}

LandmarkCache ExtractAll(const std::vector<cv::Mat>& panoramas, const nav::LandmarkExtractorConfig& config) {
  LandmarkCache cache;
  cache.sets.reserve(panoramas.size());
  double total = 0;
  for (size_t i = 0; i < panoramas.size(); ++i) {
    const auto t0 = Clock::now();
    cache.sets.push_back(nav::ExtractLandmarks(panoramas[i], config));
    cache.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    cache.index[panoramas[i].data] = static_cast<int>(i);
    total += cache.sets.back().size();
  }
  cache.mean_landmarks = panoramas.empty() ? 0 : total / panoramas.size();
  return cache;
}

LandmarkMethod::LandmarkMethod(const nav::LandmarkExtractorConfig& extractor, const nav::LandmarkHomingConfig& homing,
                               const nav::PanoramaModel& panorama, const LandmarkCache* cache)
    : extractor_(extractor), homer_(homing, panorama), cache_(cache) {
  extractor_.Validate();
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
  scratch_ = nav::ExtractLandmarks(panorama, extractor_);
  extract_seconds_ += std::chrono::duration<double>(Clock::now() - t0).count();
  ++extracted_;
  return scratch_;
}

void LandmarkMethod::SetHome(const cv::Mat& panorama) { homer_.SetHome(Landmarks(panorama)); }

std::optional<nav::HomingEstimate> LandmarkMethod::Home(const cv::Mat& panorama) {
  const auto r = homer_.Home(Landmarks(panorama));
  if (!r) return std::nullopt;
  matches_ += r->matches;
  ++estimates_;
  return r->estimate;
}

Grid RenderScene(const nav::sim::Scene& scene, CameraPipeline::Input input, uint64_t seed, ViewRenderer& renderer,
                 const std::function<void(int, int)>& progress) {
  Grid g;
  g.scene = scene;
  GridOptions grid;
  grid.seed = seed;
  grid.input = input;
  CameraPipeline pipeline;
  pipeline.input = input;
  g.db = RenderGrid(scene, renderer, grid, progress);
  for (const auto& s : g.db.sensor) g.panos.push_back(renderer.ToPanorama(s, pipeline));
  return g;
}

std::string LandmarkLabel(nav::LandmarkMethod method, nav::AlvVariant variant, int top_n) {
  return std::string(nav::LandmarkMethodName(method)) + " " + nav::AlvVariantName(variant) + " " +
         (top_n > 0 ? "top" + std::to_string(top_n) : std::string("all"));
}

}  // namespace snapnav::eval
