#pragma once
// SURF, Speeded-Up Robust Features (Bay, Ess, Tuytelaars, Van Gool, CVIU 110(3), 2008;
// thesis 4.3), written from the paper.
//
// Detector ("Fast-Hessian"): the determinant of the Hessian, with the Gaussian second
// derivatives approximated by box filters evaluated on an integral image,
//   det(H) = Dxx Dyy - (0.9 Dxy)^2,
// each response divided by the filter area L^2. Octave o (0-based) holds `intervals` filter
// sizes L = 3 (2^(o+1) (i+1) + 1): 9, 15, 21, 27 | 15, 27, 39, 51 | 27, 51, 75, 99 | ...,
// evaluated every init_sample * 2^o pixels. A filter of size L stands for a Gaussian of
// scale s = 1.2 L / 9 (a Gaussian blob of standard deviation sigma peaks at L ~ 5.5 sigma).
// Keypoints are the 3x3x3 maxima in (x, y, size) above the threshold, refined by fitting a 3D
// quadratic (offsets above half a sample in any direction, with a little tolerance: rejected).
//
// Orientation: Haar wavelet responses (side 4s) at the sample points (step s) within radius 6s,
// weighted by a Gaussian of sigma 2s; the sum of the responses within a sliding window of
// 60 degrees; the longest sum gives the orientation.
//
// Descriptor: a square of side 20s turned to the orientation, 4 x 4 subregions of 5 x 5 sample
// points (step s); per sample the Haar responses (side 2s) in the keypoint frame, weighted by a
// Gaussian of sigma 3.3s; per subregion (sum dx, sum dy, sum |dx|, sum |dy|): 64 values scaled
// to unit length. U-SURF skips the orientation (angle 0 in the image frame).
//
// Conventions. Pixel centres are at integer coordinates (as in OpenCV). The Hessian response is
// in (grey levels)^2 for grey levels 0..255, i.e. 255^2 = 65025 times the response on an image
// scaled to [0, 1]; this is OpenCV's SURF convention, so hessian_threshold = 100 means what it
// means there (0.0015 on a [0, 1] image). A Haar wavelet is centred on its pixel: two halves of
// h = round(side / 2) columns (rows) either side of the centre column (row), 2h + 1 long.
// Orientations are in image coordinates (x right, y down): 90 degrees points down the image,
// as OpenCV's KeyPoint::angle for SURF.

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/landmarks/landmark_set.hpp"

namespace snapnav::nav {

constexpr int kSurfDescriptorSize = 64;

struct SurfOptions {
  double hessian_threshold = 100;  // on det(H) in (grey levels)^2, see above (OpenCV's scale)
  int octaves = 4;                 // 1..8
  int intervals = 4;               // filter sizes per octave, >= 3 (the first and last only bound the NMS)
  int init_sample = 1;             // sampling step [px] in the first octave (doubles each octave)
  bool upright = false;            // U-SURF: no orientation assignment (angle_deg = -1)
  int max_keypoints = 0;           // keep the strongest N keypoints; 0: all
  void Validate() const;           // throws std::invalid_argument
};

// The integral image of an 8-bit grey image: entry (y, x) is the sum of the pixels in rows
// [0, y) and columns [0, x). Sums are kept modulo 2^32, so box sums are exact for any box of
// fewer than 2^23 pixels (any image size).
class IntegralImage {
 public:
  IntegralImage() = default;
  // `gray`: 8-bit single channel. Throws std::invalid_argument on an empty or other image.
  explicit IntegralImage(const cv::Mat& gray);

  int width() const { return width_; }
  int height() const { return height_; }
  bool empty() const { return width_ == 0; }
  // Sum of the pixels in columns [x0, x1) and rows [y0, y1); the box must lie inside the image.
  int BoxSum(int x0, int y0, int x1, int y1) const {
    const uint32_t* top = sums_.data() + static_cast<size_t>(y0) * stride_;
    const uint32_t* bottom = sums_.data() + static_cast<size_t>(y1) * stride_;
    return static_cast<int>(bottom[x1] - bottom[x0] - top[x1] + top[x0]);
  }
  // Same, with the box clipped to the image (0 when nothing is left).
  int ClippedBoxSum(int x0, int y0, int x1, int y1) const;
  // Row-major entries, (height + 1) rows of stride() = width + 1.
  const uint32_t* data() const { return sums_.data(); }
  int stride() const { return stride_; }

 private:
  int width_ = 0, height_ = 0, stride_ = 0;
  std::vector<uint32_t> sums_;
};

// Fast-Hessian keypoints of `integral`, strongest first: x_px, y_px (interpolated), strength =
// interpolated det(H) (> 0), scale_px = interpolated filter size L (OpenCV's KeyPoint::size for
// SURF; the scale is s = 1.2 scale_px / 9, the descriptor window 20s = 2.67 scale_px wide),
// angle_deg = -1. If `laplacian_signs` is given it receives, per keypoint, the sign of the
// Laplacian Dxx + Dyy (+1: dark blob on a bright background, -1: bright blob), which lets a
// matcher skip pairs of opposite sign. Throws std::invalid_argument on invalid options.
std::vector<Landmark> FastHessian(const IntegralImage& integral, const SurfOptions& options,
                                  std::vector<int8_t>* laplacian_signs = nullptr);

// Orientation [deg, image frame, in [0, 360)] of a keypoint at (x_px, y_px) of size scale_px
// (filter size; s = 1.2 scale_px / 9). 0 when there is no gradient around it.
float SurfOrientationDeg(const IntegralImage& integral, float x_px, float y_px, float scale_px);

// The 64-value descriptor of `keypoint` (its x_px, y_px, scale_px and angle_deg; angle_deg < 0:
// upright) into out[0..64). Unit length, or all zeros when the window holds no gradient.
void SurfDescriptor(const IntegralImage& integral, const Landmark& keypoint, float* out);

// Describes keypoints found elsewhere: unless options.upright, assigns each one's orientation
// (overwriting angle_deg), else sets angle_deg = -1; returns one CV_32F row of 64 values per
// keypoint (an empty Mat for no keypoints). Throws std::invalid_argument for a keypoint with
// scale_px <= 0. Keypoints near or beyond the border are described from the part of the window
// inside the image.
cv::Mat DescribeSurf(const IntegralImage& integral, std::vector<Landmark>* keypoints, const SurfOptions& options);
cv::Mat DescribeSurf(const cv::Mat& gray, std::vector<Landmark>* keypoints, const SurfOptions& options);

// Detects and describes: a LandmarkSet of method kSurf with the image size, landmarks strongest
// first. `gray`: 8-bit single channel; throws std::invalid_argument on an empty or other image
// and on invalid options. An image without structure gives an empty set.
LandmarkSet DetectSurf(const cv::Mat& gray, const SurfOptions& options, std::vector<int8_t>* laplacian_signs = nullptr);

}  // namespace snapnav::nav
