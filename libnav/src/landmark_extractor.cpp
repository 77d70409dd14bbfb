#include "snapnav/nav/landmark_extractor.hpp"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace snapnav::nav {

void LandmarkExtractorConfig::Validate() const {
  switch (method) {
    case LandmarkMethod::kHog:
      throw std::invalid_argument("landmarks: hog has no landmark extractor (HOG cells are homed by the HOG homing)");
    case LandmarkMethod::kVline: vline.Validate(); break;
    case LandmarkMethod::kSift: sift.Validate(); break;
    case LandmarkMethod::kSurf: surf.Validate(); break;
  }
  if (surf_pad_px < 0) throw std::invalid_argument("landmarks: surf_pad_px must be >= 0");
}

LandmarkSet ExtractLandmarks(const cv::Mat& panorama, const LandmarkExtractorConfig& config) {
  config.Validate();
  if (panorama.empty()) throw std::invalid_argument("landmarks: empty panorama");
  cv::Mat gray;
  if (panorama.type() == CV_8UC3) {
    cv::cvtColor(panorama, gray, cv::COLOR_BGR2GRAY);
  } else if (panorama.type() == CV_8UC1) {
    gray = panorama;
  } else {
    throw std::invalid_argument("landmarks: the panorama must be 8-bit grey or BGR");
  }
  if (config.equalize_histogram) {
    cv::Mat eq;
    cv::equalizeHist(gray, eq);
    gray = eq;
  }
  switch (config.method) {
    case LandmarkMethod::kVline: return DetectVlineLandmarks(gray, config.vline);
    case LandmarkMethod::kSift: return DetectSift(gray, config.sift);
    case LandmarkMethod::kSurf:
      return DetectWrapped(gray, config.surf_pad_px, [&](const cv::Mat& g) { return DetectSurf(g, config.surf); });
    case LandmarkMethod::kHog: break;
  }
  throw std::invalid_argument("landmarks: no extractor for this method");
}

MatchOptions DefaultMatchOptions(LandmarkMethod method) {
  MatchOptions o;
  if (method == LandmarkMethod::kVline) {
    o.ratio = 1.0;
    o.mutual = true;
    o.relaxed_second_best = true;
    o.max_x_displacement_px = 60;
  }
  return o;
}

}  // namespace snapnav::nav
