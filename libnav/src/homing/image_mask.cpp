#include "snapnav/nav/homing/image_mask.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace snapnav::nav {

void CheckMask(const cv::Mat& mask, cv::Size size, const char* what) {
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1) {
    throw std::invalid_argument(std::string(what) + ": the mask must be an 8-bit single-channel image");
  }
  if (mask.size() != size) {
    throw std::invalid_argument(std::string(what) + ": the mask is " + std::to_string(mask.cols) + "x" +
                                std::to_string(mask.rows) + ", the image " + std::to_string(size.width) + "x" +
                                std::to_string(size.height));
  }
}

bool HasMaskedPixels(const cv::Mat& mask) {
  return !mask.empty() && cv::countNonZero(mask) < static_cast<int>(mask.total());
}

double MaskedFraction(const cv::Mat& mask) {
  if (mask.empty()) return 0.0;
  return 1.0 - static_cast<double>(cv::countNonZero(mask)) / static_cast<double>(mask.total());
}

void FillMasked(const cv::Mat& mask, cv::Mat* image, bool wrap_columns) {
  if (mask.empty() || !HasMaskedPixels(mask)) return;
  if (image->empty() || image->depth() != CV_8U || (image->channels() != 1 && image->channels() != 3)) {
    throw std::invalid_argument("fill masked: need an 8-bit grey or BGR image");
  }
  CheckMask(mask, image->size(), "fill masked");
  const int w = image->cols, ch = image->channels();
  cv::Scalar fallback(128, 128, 128);
  if (cv::countNonZero(mask) > 0) fallback = cv::mean(*image, mask);
  std::vector<int> usable;
  for (int y = 0; y < image->rows; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    uint8_t* p = image->ptr<uint8_t>(y);
    usable.clear();
    for (int x = 0; x < w; ++x) {
      if (m[x]) usable.push_back(x);
    }
    if (static_cast<int>(usable.size()) == w) continue;
    if (usable.empty()) {
      for (int x = 0; x < w; ++x) {
        for (int k = 0; k < ch; ++k) p[x * ch + k] = cv::saturate_cast<uint8_t>(fallback[k]);
      }
      continue;
    }
    // Each gap between consecutive usable pixels a < b (and, wrapping, the last to the first).
    auto fill = [&](int a, int b, int from, int to) {  // pixels from..to (may exceed w: wrap), ends a and b
      const double span = b - a;
      for (int x = from; x <= to; ++x) {
        const double t = span > 0 ? (x - a) / span : 0.0;
        const int xx = ((x % w) + w) % w;
        for (int k = 0; k < ch; ++k) {
          const double va = p[(((a % w) + w) % w) * ch + k], vb = p[(((b % w) + w) % w) * ch + k];
          p[xx * ch + k] = cv::saturate_cast<uint8_t>(va + t * (vb - va));
        }
      }
    };
    for (size_t i = 0; i + 1 < usable.size(); ++i) {
      if (usable[i + 1] - usable[i] > 1) fill(usable[i], usable[i + 1], usable[i] + 1, usable[i + 1] - 1);
    }
    const int first = usable.front(), last = usable.back();
    if (wrap_columns) {
      if (last + 1 < w + first) fill(last, first + w, last + 1, first + w - 1);
    } else {
      for (int x = 0; x < first; ++x) {
        for (int k = 0; k < ch; ++k) p[x * ch + k] = p[first * ch + k];
      }
      for (int x = last + 1; x < w; ++x) {
        for (int k = 0; k < ch; ++k) p[x * ch + k] = p[last * ch + k];
      }
    }
  }
}

cv::Mat MaskClearance(const cv::Mat& mask, bool wrap_columns) {
  if (mask.empty()) return {};
  const float diagonal = static_cast<float>(std::hypot(mask.cols, mask.rows));
  if (!HasMaskedPixels(mask)) return cv::Mat(mask.size(), CV_32F, cv::Scalar(diagonal));
  cv::Mat binary = mask != 0;  // 255 usable, 0 masked: the distance to the nearest zero
  cv::Mat dist;
  if (wrap_columns) {
    const int pad = mask.cols;  // a whole turn: distances across the seam are exact
    cv::Mat padded;
    cv::copyMakeBorder(binary, padded, 0, 0, pad, pad, cv::BORDER_WRAP);
    cv::Mat d;
    cv::distanceTransform(padded, d, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    dist = d.colRange(pad, pad + mask.cols).clone();
  } else {
    cv::distanceTransform(binary, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  }
  return dist;
}

LandmarkSet DropMaskedLandmarks(const LandmarkSet& set, const cv::Mat& mask, double margin_px, bool add_half_scale,
                                const cv::Mat& clearance_in) {
  if (mask.empty() || set.empty()) return set;
  if (set.width_px != mask.cols || set.height_px != mask.rows) {
    throw std::invalid_argument("landmark mask: the mask is " + std::to_string(mask.cols) + "x" +
                                std::to_string(mask.rows) + ", the landmarks' panorama " +
                                std::to_string(set.width_px) + "x" + std::to_string(set.height_px));
  }
  if (!clearance_in.empty() && (clearance_in.size() != mask.size() || clearance_in.type() != CV_32F)) {
    throw std::invalid_argument("landmark mask: the clearance given is not MaskClearance of a mask of this size");
  }
  const cv::Mat clearance = clearance_in.empty() ? MaskClearance(mask) : clearance_in;
  LandmarkSet out;
  out.method = set.method;
  out.width_px = set.width_px;
  out.height_px = set.height_px;
  std::vector<int> keep;
  for (int i = 0; i < set.size(); ++i) {
    const Landmark& l = set.landmarks[i];
    const int x = std::clamp(static_cast<int>(std::lround(l.x_px)), 0, mask.cols - 1) % mask.cols;
    const int y = std::clamp(static_cast<int>(std::lround(l.y_px)), 0, mask.rows - 1);
    const double need = margin_px + (add_half_scale ? 0.5 * l.scale_px : 0.0);
    if (mask.at<uint8_t>(y, x) != 0 && clearance.at<float>(y, x) >= need) keep.push_back(i);
  }
  out.landmarks.reserve(keep.size());
  if (!keep.empty() && !set.descriptors.empty()) {
    out.descriptors.create(static_cast<int>(keep.size()), set.descriptors.cols, set.descriptors.type());
  }
  for (size_t j = 0; j < keep.size(); ++j) {
    out.landmarks.push_back(set.landmarks[keep[j]]);
    if (!out.descriptors.empty()) set.descriptors.row(keep[j]).copyTo(out.descriptors.row(static_cast<int>(j)));
  }
  return out;
}

cv::Mat GrowMasked(const cv::Mat& mask, int radius_px, bool wrap_columns) {
  if (mask.empty() || radius_px <= 0 || !HasMaskedPixels(mask)) return mask;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, {2 * radius_px + 1, 2 * radius_px + 1});
  cv::Mat out;
  if (wrap_columns) {
    const int pad = std::min(radius_px, mask.cols);
    cv::Mat padded, eroded;
    cv::copyMakeBorder(mask, padded, 0, 0, pad, pad, cv::BORDER_WRAP);
    cv::erode(padded, eroded, kernel, {-1, -1}, 1, cv::BORDER_REPLICATE);
    out = eroded.colRange(pad, pad + mask.cols).clone();
  } else {
    cv::erode(mask, out, kernel, {-1, -1}, 1, cv::BORDER_REPLICATE);
  }
  return out;
}

}  // namespace snapnav::nav
