#pragma once
// Masks of pixels that must not be used: the robot's own parts that the mirror shows (cables,
// struts, the camera's mount), in a raw catadioptric image or, unwrapped, in a panorama.
//
// A mask is CV_8UC1 of the image's size: non-zero = usable, 0 = masked (OpenCV's convention
// for detector masks). An empty cv::Mat means "every pixel usable" everywhere below.
//
// Every extractor ignores masked pixels the same way (docs/calibration.md, "Masks"):
//   - the panorama's masked pixels are filled from their usable neighbours in the same row
//     (FillMasked), so no edge, blob or line of a cable reaches a detector or a descriptor;
//   - landmarks (SIFT, SURF keypoints, vertical lines) whose centre lies within a margin of a
//     masked pixel are dropped (DropMaskedLandmarks): no landmark on the robot's own cables;
//   - dense descriptors (HOG cells, place-view signatures, RatSLAM's view templates) leave the
//     masked pixels out of their sums (hog_homing.hpp, ratslam.hpp).

#include <opencv2/core.hpp>

#include "snapnav/nav/landmarks/landmark_set.hpp"

namespace snapnav::nav {

// Throws std::invalid_argument (naming `what`) unless `mask` is empty or CV_8UC1 of `size`.
void CheckMask(const cv::Mat& mask, cv::Size size, const char* what);

// True when the mask is non-empty and has at least one masked pixel.
bool HasMaskedPixels(const cv::Mat& mask);
// Share of masked pixels, 0 for an empty mask.
double MaskedFraction(const cv::Mat& mask);

// Replaces every masked pixel of `image` (8-bit, 1 or 3 channels, the mask's size) by linear
// interpolation between the nearest usable pixels left and right of it in its row; with
// `wrap_columns` (a panorama) the row is a circle. A row without a usable pixel takes the mean of
// the image's usable pixels (grey 128 when there are none). An empty mask leaves the image as is.
void FillMasked(const cv::Mat& mask, cv::Mat* image, bool wrap_columns = true);

// Per pixel, the Euclidean distance [px] to the nearest masked pixel (CV_32F, the mask's size);
// with `wrap_columns` the columns wrap around (a panorama). Without masked pixels every value is
// the image's diagonal.
cv::Mat MaskClearance(const cv::Mat& mask, bool wrap_columns = true);

// The landmarks of `set` whose centre is usable and at least `margin_px` (plus half the
// landmark's scale when `add_half_scale`: a keypoint's own neighbourhood) from every masked
// pixel, with their descriptor rows. An empty mask returns the set unchanged. `clearance`, when
// given, is MaskClearance(mask) (computed here otherwise).
LandmarkSet DropMaskedLandmarks(const LandmarkSet& set, const cv::Mat& mask, double margin_px, bool add_half_scale,
                                const cv::Mat& clearance = cv::Mat());

// `mask` shrunk by `radius_px` usable pixels around every masked pixel (columns wrap with
// `wrap_columns`): pixels whose centred differences read a masked pixel become masked too.
cv::Mat GrowMasked(const cv::Mat& mask, int radius_px, bool wrap_columns = true);

}  // namespace snapnav::nav
