#pragma once
// The landmarks one extractor finds in one panorama (thesis chapter 4): positions in the
// panorama, detector strength, scale and one descriptor row per landmark. Every extractor
// (vertical lines, SIFT, SURF) returns this; matching and the landmark ALVs consume it.

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace snapnav::nav {

// Same numbering as snapnav::landmark_set_t's method constants.
enum class LandmarkMethod { kHog = 0, kVline = 1, kSift = 2, kSurf = 3 };
const char* LandmarkMethodName(LandmarkMethod method);  // "hog", "vline", "sift", "surf"
std::optional<LandmarkMethod> ParseLandmarkMethod(const std::string& name);

struct Landmark {
  float x_px = 0;         // panorama column (fractional), in [0, width)
  float y_px = 0;         // panorama row (fractional)
  float strength = 0;     // detector response (Hessian, DoG contrast, line length ...)
  float scale_px = 0;     // keypoint size (diameter) or window width [px]
  float angle_deg = -1;   // keypoint orientation in [0, 360); -1: none (upright, lines)
};

struct LandmarkSet {
  LandmarkMethod method = LandmarkMethod::kSift;
  int width_px = 0, height_px = 0;   // the panorama's size
  std::vector<Landmark> landmarks;
  cv::Mat descriptors;               // CV_32F, landmarks.size() rows (empty when there are none)
  bool empty() const { return landmarks.empty(); }
  int size() const { return static_cast<int>(landmarks.size()); }
};

}  // namespace snapnav::nav
