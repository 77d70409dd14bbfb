#include "snapnav/nav/landmarks/landmark_extractor.hpp"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/homing/image_mask.hpp"

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
  if (!(mask_margin_px >= 0)) throw std::invalid_argument("landmarks: mask_margin_px must be >= 0");
}

LandmarkSet DropMaskedLandmarks(const LandmarkSet& set, const cv::Mat& mask, const LandmarkExtractorConfig& config,
                                const cv::Mat& clearance) {
  // Keypoints (SIFT, SURF) carry their neighbourhood's size; a vertical line's scale is its
  // descriptor window, not its extent.
  return DropMaskedLandmarks(set, mask, config.mask_margin_px, set.method != LandmarkMethod::kVline, clearance);
}

LandmarkSet ExtractLandmarks(const cv::Mat& panorama, const LandmarkExtractorConfig& config, const cv::Mat& mask,
                             const cv::Mat& clearance) {
  config.Validate();
  if (panorama.empty()) throw std::invalid_argument("landmarks: empty panorama");
  CheckMask(mask, panorama.size(), "landmarks");
  cv::Mat gray;
  if (panorama.type() == CV_8UC3) {
    cv::cvtColor(panorama, gray, cv::COLOR_BGR2GRAY);
  } else if (panorama.type() == CV_8UC1) {
    gray = panorama;
  } else {
    throw std::invalid_argument("landmarks: the panorama must be 8-bit grey or BGR");
  }
  const bool masked = HasMaskedPixels(mask);
  if (masked) {
    gray = gray.clone();
    FillMasked(mask, &gray);  // no edge of the robot's parts reaches the detector
  }
  if (config.equalize_histogram) {
    cv::Mat eq;
    cv::equalizeHist(gray, eq);
    gray = eq;
  }
  LandmarkSet set;
  switch (config.method) {
    case LandmarkMethod::kVline: set = DetectVlineLandmarks(gray, config.vline); break;
    case LandmarkMethod::kSift: set = DetectSift(gray, config.sift); break;
    case LandmarkMethod::kSurf:
      set = DetectWrapped(gray, config.surf_pad_px, [&](const cv::Mat& g) { return DetectSurf(g, config.surf); });
      break;
    case LandmarkMethod::kHog: throw std::invalid_argument("landmarks: no extractor for this method");
  }
  return masked ? DropMaskedLandmarks(set, mask, config, clearance) : set;
}

}  // namespace snapnav::nav
