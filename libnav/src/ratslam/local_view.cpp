// RatSLAM local view cells: panorama -> template, comparison at the best column shift.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <opencv2/core/hal/hal.hpp>

#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"

namespace snapnav::nav {
namespace {

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
// OpenRatSLAM skips a template whose mean differs from the view's by more than the threshold plus
// this: the mean absolute difference at any shift is at least the difference of the means.
constexpr double kMeanSkipEpsilon = 0.005;

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("ratslam local view: " + what);
}

struct Crop {
  int x0, x1, y0, y1;
};

Crop CropOf(const LocalViewOptions& o, int cols, int rows) {
  Crop c{o.image_crop_x_min_px, o.image_crop_x_max_px < 0 ? cols : o.image_crop_x_max_px, o.image_crop_y_min_px,
         o.image_crop_y_max_px < 0 ? rows : o.image_crop_y_max_px};
  const std::string size = std::to_string(cols) + "x" + std::to_string(rows);
  Require(c.x1 <= cols && c.y1 <= rows,
          "crop columns " + std::to_string(c.x0) + ".." + std::to_string(c.x1) + ", rows " + std::to_string(c.y0) +
              ".." + std::to_string(c.y1) + " exceed the " + size + " image");
  Require((c.x1 - c.x0) >= o.template_x_size && (c.y1 - c.y0) >= o.template_y_size,
          "the crop of the " + size + " image is smaller than the " + std::to_string(o.template_x_size) + "x" +
              std::to_string(o.template_y_size) + " template");
  return c;
}

}  // namespace

void LocalViewOptions::Validate() const {
  Require(image_crop_x_min_px >= 0 && image_crop_y_min_px >= 0, "image_crop_x_min_px and image_crop_y_min_px must be >= 0");
  Require(image_crop_x_max_px == -1 || image_crop_x_max_px > image_crop_x_min_px,
          "image_crop_x_max_px must be -1 (the width) or > image_crop_x_min_px");
  Require(image_crop_y_max_px == -1 || image_crop_y_max_px > image_crop_y_min_px,
          "image_crop_y_max_px must be -1 (the height) or > image_crop_y_min_px");
  Require(template_x_size >= 1 && template_y_size >= 1 && template_x_size <= 4096 && template_y_size <= 4096,
          "template_x_size and template_y_size must be 1..4096");
  Require(vt_step_match >= 1, "vt_step_match must be >= 1");
  Require(vt_shift_match >= 0, "vt_shift_match must be >= 0");
  Require(vt_panoramic || 2 * vt_shift_match < template_x_size,
          "vt_shift_match must leave template columns to compare (2 * vt_shift_match < template_x_size)");
  Require(std::isfinite(vt_match_threshold) && vt_match_threshold >= 0, "vt_match_threshold must be >= 0");
  Require(std::isfinite(vt_normalisation) && vt_normalisation >= 0, "vt_normalisation must be >= 0 (0: off)");
  Require(vt_patch_normalise >= 0, "vt_patch_normalise must be >= 0 (0: off)");
  Require(std::isfinite(vt_min_patch_normalisation_std) && vt_min_patch_normalisation_std >= 0,
          "vt_min_patch_normalisation_std must be >= 0");
}

LocalViewCells::LocalViewCells(const LocalViewOptions& options) : options_(options) {
  options_.Validate();
  const size_t n = static_cast<size_t>(options_.template_x_size) * options_.template_y_size;
  view_.assign(n, 0.0f);
  doubled_.assign(2 * n, 0.0f);
  patch_copy_.assign(n, 0.0f);
  templates_.reserve(1024);
}

void LocalViewCells::ConvertView(const cv::Mat& gray, const cv::Mat& mask) {
  Require(!gray.empty() && gray.type() == CV_8UC1, "the view must be a non-empty 8-bit grey image (CV_8UC1)");
  Require(mask.empty() || (mask.type() == CV_8UC1 && mask.size() == gray.size()),
          "the mask must be CV_8UC1 of the view's size");
  const LocalViewOptions& o = options_;
  const Crop c = CropOf(o, gray.cols, gray.rows);
  const int nx = o.template_x_size, ny = o.template_y_size;
  // As OpenRatSLAM: blocks of (crop / size) pixels from the crop's corner; leftover pixels unused.
  const int bx = (c.x1 - c.x0) / nx, by = (c.y1 - c.y0) / ny;
  const double scale = 1.0 / (255.0 * bx * by);
  if (HasMaskedPixels(mask)) {
    // The usable pixels' mean per block; blocks without one are interpolated along the row.
    std::vector<double> sum(static_cast<size_t>(nx)), count(static_cast<size_t>(nx));
    for (int ty = 0; ty < ny; ++ty) {
      std::fill(sum.begin(), sum.end(), 0.0);
      std::fill(count.begin(), count.end(), 0.0);
      for (int y = c.y0 + ty * by; y < c.y0 + (ty + 1) * by; ++y) {
        const uint8_t* row = gray.ptr<uint8_t>(y) + c.x0;
        const uint8_t* usable = mask.ptr<uint8_t>(y) + c.x0;
        for (int tx = 0; tx < nx; ++tx) {
          for (int x = tx * bx; x < (tx + 1) * bx; ++x) {
            if (!usable[x]) continue;
            sum[tx] += row[x];
            count[tx] += 1;
          }
        }
      }
      cv::Mat values(1, nx, CV_8UC1), have(1, nx, CV_8UC1);
      float* out = &view_[static_cast<size_t>(ty) * nx];
      for (int tx = 0; tx < nx; ++tx) {
        out[tx] = count[tx] > 0 ? static_cast<float>(sum[tx] / (255.0 * count[tx])) : 0.0f;
        have.at<uint8_t>(0, tx) = count[tx] > 0 ? 255 : 0;
      }
      if (cv::countNonZero(have) == nx) continue;
      if (cv::countNonZero(have) == 0) {
        std::fill(out, out + nx, 0.5f);
        continue;
      }
      // Linear interpolation between the nearest usable cells (circular on a panorama).
      for (int tx = 0; tx < nx; ++tx) {
        if (have.at<uint8_t>(0, tx)) continue;
        int l = tx, r = tx, dl = 0, dr = 0;
        do {
          l = o.vt_panoramic ? (l + nx - 1) % nx : l - 1;
          ++dl;
        } while (l >= 0 && !have.at<uint8_t>(0, l) && dl < nx);
        do {
          r = o.vt_panoramic ? (r + 1) % nx : r + 1;
          ++dr;
        } while (r < nx && !have.at<uint8_t>(0, r) && dr < nx);
        const bool lok = l >= 0 && have.at<uint8_t>(0, l), rok = r < nx && have.at<uint8_t>(0, r);
        if (lok && rok) {
          out[tx] = static_cast<float>((out[l] * dr + out[r] * dl) / static_cast<double>(dl + dr));
        } else {
          out[tx] = lok ? out[l] : out[r];
        }
      }
    }
  } else {
    for (int ty = 0; ty < ny; ++ty) {
      float* out = &view_[static_cast<size_t>(ty) * nx];
      std::fill(out, out + nx, 0.0f);
      for (int y = c.y0 + ty * by; y < c.y0 + (ty + 1) * by; ++y) {
        const uint8_t* row = gray.ptr<uint8_t>(y) + c.x0;
        for (int tx = 0; tx < nx; ++tx) {
          int sum = 0;
          for (int x = tx * bx; x < (tx + 1) * bx; ++x) sum += row[x];
          out[tx] += static_cast<float>(sum);
        }
      }
      for (int tx = 0; tx < nx; ++tx) out[tx] = static_cast<float>(out[tx] * scale);
    }
  }
  const size_t n = view_.size();
  if (o.vt_normalisation > 0) {
    double mean = 0;
    for (float v : view_) mean += v;
    mean /= static_cast<double>(n);
    for (float& v : view_) {
      v = mean > 0 ? static_cast<float>(std::clamp(v * o.vt_normalisation / mean, 0.0, 1.0)) : 0.0f;
    }
  }
  if (o.vt_patch_normalise > 0) {
    // Each cell against the mean and std. dev. of the (2p+1)^2 patch around it, mapped to
    // [0, 1] as (z + 3) / 6. Rows clip at the edge (OpenRatSLAM); on a panorama columns wrap.
    const int p = o.vt_patch_normalise;
    const double count = (2.0 * p + 1) * (2.0 * p + 1);
    std::copy(view_.begin(), view_.end(), patch_copy_.begin());
    auto col = [&](int x) {
      if (o.vt_panoramic) return ((x % nx) + nx) % nx;
      return std::clamp(x, 0, nx - 1);
    };
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x) {
        double sum = 0, sum2 = 0;
        for (int py = y - p; py <= y + p; ++py) {
          const float* row = &patch_copy_[static_cast<size_t>(std::clamp(py, 0, ny - 1)) * nx];
          for (int px = x - p; px <= x + p; ++px) {
            const double v = row[col(px)];
            sum += v;
            sum2 += v * v;
          }
        }
        const double mean = sum / count;
        const double std_dev = std::sqrt(std::max(0.0, sum2 / count - mean * mean));
        const double v = patch_copy_[static_cast<size_t>(y) * nx + x];
        float& out = view_[static_cast<size_t>(y) * nx + x];
        if (std_dev < o.vt_min_patch_normalisation_std || std_dev <= 0) {
          out = 0.5f;
        } else {
          out = static_cast<float>(std::clamp(((v - mean) / std_dev + 3.0) / 6.0, 0.0, 1.0));
        }
      }
    }
  }
  double sum = 0;
  for (float v : view_) sum += v;
  view_mean_ = sum / static_cast<double>(n);
}

std::vector<float> LocalViewCells::MakeTemplate(const cv::Mat& gray, const cv::Mat& mask) {
  ConvertView(gray, mask);
  return view_;
}

void LocalViewCells::Compare(int* best_id, double* best_sum, int* best_shift) const {
  const LocalViewOptions& o = options_;
  const int nx = o.template_x_size, ny = o.template_y_size;
  double min_sum = std::numeric_limits<double>::infinity();
  *best_id = -1;
  *best_shift = 0;
  const double skip = o.vt_match_threshold + kMeanSkipEpsilon;
  for (size_t id = 0; id < templates_.size(); ++id) {
    const Template& t = templates_[id];
    if (std::abs(view_mean_ - t.mean) > skip) continue;
    if (o.vt_panoramic) {
      // OpenRatSLAM compares view column c with template column c + offset (circularly):
      // with each view row doubled, that is the slice of the doubled row from nx - offset.
      for (int offset = 0; offset < nx; offset += o.vt_step_match) {
        double sum = 0;
        for (int y = 0; y < ny && sum <= min_sum; ++y) {  // stops once worse than the best so far
          sum += cv::hal::normL1_(&t.data[static_cast<size_t>(y) * nx],
                                  &doubled_[static_cast<size_t>(y) * 2 * nx + (nx - offset)], nx);
        }
        if (sum < min_sum) {
          min_sum = sum;
          *best_id = static_cast<int>(id);
          *best_shift = offset;
        }
      }
    } else {
      // View columns [s, nx - s) against template columns [offset, offset + nx - 2 s).
      const int s = o.vt_shift_match, width = nx - 2 * s;
      for (int offset = 0; offset <= 2 * s; offset += o.vt_step_match) {
        double sum = 0;
        for (int y = 0; y < ny && sum <= min_sum; ++y) {
          sum += cv::hal::normL1_(&t.data[static_cast<size_t>(y) * nx + offset], &view_[static_cast<size_t>(y) * nx + s],
                                  width);
        }
        if (sum < min_sum) {
          min_sum = sum;
          *best_id = static_cast<int>(id);
          *best_shift = offset - s;  // view column c against template column c + (offset - s)
        }
      }
    }
  }
  *best_sum = min_sum;
}

double LocalViewCells::Difference(int id, double offset) const {
  const int nx = options_.template_x_size, ny = options_.template_y_size;
  // Template column c against the view at column c - offset: between view columns c - n and
  // c - n - 1 for offset = n + f (linear interpolation).
  const double n0 = std::floor(offset);
  const double f = offset - n0;
  const int n = ((static_cast<int>(n0) % nx) + nx) % nx;
  const Template& t = templates_[static_cast<size_t>(id)];
  double sum = 0;
  for (int y = 0; y < ny; ++y) {
    const float* tr = &t.data[static_cast<size_t>(y) * nx];
    const float* vr = &doubled_[static_cast<size_t>(y) * 2 * nx + nx];  // vr[c] = view column c, c in [-nx, nx)
    for (int c = 0; c < nx; ++c) {
      const int a = c - n;  // in [-nx, nx)
      const int b = a - 1 < -nx ? a - 1 + nx : a - 1;
      sum += std::abs(tr[c] - ((1 - f) * vr[a] + f * vr[b]));
    }
  }
  return sum;
}

ViewMatch LocalViewCells::OnImage(const cv::Mat& gray, const cv::Mat& mask) {
  ConvertView(gray, mask);
  const LocalViewOptions& o = options_;
  const int nx = o.template_x_size, ny = o.template_y_size;
  if (o.vt_panoramic) {
    for (int y = 0; y < ny; ++y) {
      const float* row = &view_[static_cast<size_t>(y) * nx];
      float* out = &doubled_[static_cast<size_t>(y) * 2 * nx];
      std::copy(row, row + nx, out);
      std::copy(row, row + nx, out + nx);
    }
  }
  int id = -1, shift = 0;
  double sum = 0;
  Compare(&id, &sum, &shift);
  double fraction = 0;  // refinement of the offset [columns]
  if (id >= 0 && o.vt_panoramic && o.vt_shift_subcolumn) {
    // The best fraction of a column around the matched shift (the whole shift when none is
    // better): a view turned between template columns differs less than at either whole shift.
    for (int k = -10; k <= 10; ++k) {
      if (k == 0) continue;
      const double d = Difference(id, shift + 0.05 * k);
      if (d < sum) {
        sum = d;
        fraction = 0.05 * k;
      }
    }
  }
  ViewMatch m;
  if (id >= 0) {
    const int compared = o.vt_panoramic ? nx * ny : (nx - 2 * o.vt_shift_match) * ny;
    m.difference = sum / compared;
  }
  if (m.difference && *m.difference <= o.vt_match_threshold) {
    m.template_id = id;
    // View column c shows what template column c + offset showed: the view moved by -offset
    // columns against the template. Columns run clockwise, so on a panorama that is a
    // counter-clockwise turn of -offset * 2 pi / nx (offsets past half a turn wrap to negative).
    const int offset = o.vt_panoramic && shift > nx / 2 ? shift - nx : shift;
    m.shift_columns = -offset;
    m.shift_fraction = -fraction;
    const double fine = offset + fraction;
    // OpenRatSLAM: a camera that does not see all around gives no heading.
    m.relative_rad = o.vt_panoramic ? -fine * kTwoPi / nx : 0.0;
  } else {
    m.new_template = true;
    m.template_id = static_cast<int>(templates_.size());
    templates_.push_back({view_, view_mean_});
  }
  current_ = m.template_id;
  return m;
}

}  // namespace snapnav::nav
