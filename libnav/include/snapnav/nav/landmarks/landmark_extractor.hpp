#pragma once
// One entry point for the landmark extractors of chapter 4: vertical lines (4.1), SIFT (4.2),
// SURF (4.3), with the matching rules that suit each, so the landmarks process, the homing
// process and the evaluation configure them the same way.

#include <opencv2/core.hpp>

#include "snapnav/nav/landmarks/landmark_set.hpp"
#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/landmarks/surf.hpp"
#include "snapnav/nav/landmarks/vline.hpp"

namespace snapnav::nav {

struct LandmarkExtractorConfig {
  LandmarkMethod method = LandmarkMethod::kSift;
  VlineOptions vline;
  SiftOptions sift;
  SurfOptions surf;
  int surf_pad_px = 64;             // wrapped columns around the seam for SURF's largest filters
  bool equalize_histogram = false;  // before extraction (3.1.5)
  // With a mask: a landmark is kept only at least this far from every masked pixel [px] (a
  // keypoint: plus half its size, its own neighbourhood).
  double mask_margin_px = 2.0;
  void Validate() const;            // throws std::invalid_argument; kHog has no extractor
};

// Landmarks of a panorama (8-bit grey or BGR). Throws std::invalid_argument on an empty image.
// `mask` (image_mask.hpp; empty: none): the robot's own parts are filled before detection and no
// landmark lies on or next to them (DropMaskedLandmarks); a mask of another size throws.
// `clearance`, when given, is MaskClearance(mask) (image_mask.hpp): a caller with a fixed mask
// computes it once instead of on every call (a distance transform of the panorama).
LandmarkSet ExtractLandmarks(const cv::Mat& panorama, const LandmarkExtractorConfig& config,
                             const cv::Mat& mask = cv::Mat(), const cv::Mat& clearance = cv::Mat());
// The masking step alone, for the extractors called directly (vertical lines of the place views).
LandmarkSet DropMaskedLandmarks(const LandmarkSet& set, const cv::Mat& mask, const LandmarkExtractorConfig& config,
                                const cv::Mat& clearance = cv::Mat());

}  // namespace snapnav::nav
