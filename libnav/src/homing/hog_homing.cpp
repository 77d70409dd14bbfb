#include "snapnav/nav/homing/hog_homing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

std::optional<OrientationRange> ParseOrientationRange(const std::string& name) {
  if (name == "all") return OrientationRange::kAll;
  if (name == "vertical") return OrientationRange::kVertical;
  if (name == "horizontal") return OrientationRange::kHorizontal;
  if (name == "narrow_vertical") return OrientationRange::kNarrowVertical;
  return std::nullopt;
}

const char* OrientationRangeName(OrientationRange range) {
  switch (range) {
    case OrientationRange::kAll: return "all";
    case OrientationRange::kVertical: return "vertical";
    case OrientationRange::kHorizontal: return "horizontal";
    case OrientationRange::kNarrowVertical: return "narrow_vertical";
  }
  return "?";
}

void HogOptions::Validate() const {
  if (cell_size_px < 2) throw std::invalid_argument("hog: cell_size_px must be >= 2");
  if (bins < 2 || bins > 360) throw std::invalid_argument("hog: bins must be in 2..360");
  if (band_top_px < 0 || band_height_px < 0)
    throw std::invalid_argument("hog: band_top_px and band_height_px must not be negative");
  if (!(narrow_range_deg > 0 && narrow_range_deg <= 90)) throw std::invalid_argument("hog: narrow_range_deg in (0, 90]");
  if (!(max_masked_share >= 0 && max_masked_share < 1)) throw std::invalid_argument("hog: max_masked_share in [0, 1)");
}

void HogAlvOptions::Validate() const {
  if (!(threshold_frac >= 0 && threshold_frac <= 1)) throw std::invalid_argument("hog alv: threshold_frac in [0, 1]");
  if (min_bins < 1) throw std::invalid_argument("hog alv: min_bins >= 1");
  if (!(log_scale > 0)) throw std::invalid_argument("hog alv: log_scale must be > 0");
}

Gradients ComputeGradients(const cv::Mat& gray) {
  if (gray.empty() || gray.type() != CV_8UC1) throw std::invalid_argument("hog: need a non-empty 8-bit grey panorama");
  // Centred differences; the columns wrap around (a panorama is a cylinder), rows replicate.
  cv::Mat padded;
  cv::copyMakeBorder(gray, padded, 1, 1, 0, 0, cv::BORDER_REPLICATE);
  cv::copyMakeBorder(padded, padded, 0, 0, 1, 1, cv::BORDER_WRAP);
  cv::Mat f;
  padded.convertTo(f, CV_32F);
  const cv::Rect inner(1, 1, gray.cols, gray.rows);
  cv::Mat gx = f(inner + cv::Point(1, 0)) - f(inner - cv::Point(1, 0));
  cv::Mat gy = f(inner + cv::Point(0, 1)) - f(inner - cv::Point(0, 1));
  Gradients g;
  cv::cartToPolar(gx, gy, g.magnitude, g.angle_rad, false);  // angle in [0, 2 pi)
  return g;
}

namespace {

cv::Mat ToGray(const cv::Mat& panorama) {
  if (panorama.empty() || panorama.depth() != CV_8U) throw std::invalid_argument("hog: need a non-empty 8-bit panorama");
  if (panorama.channels() == 1) return panorama;
  cv::Mat gray;
  cv::cvtColor(panorama, gray, panorama.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

}  // namespace

ColumnHistograms::ColumnHistograms(const Gradients& gradients, const HogOptions& options, const cv::Mat& mask) {
  Build(gradients, options, mask);
}

ColumnHistograms::ColumnHistograms(const cv::Mat& panorama, const HogOptions& options) {
  options.Validate();
  Build(ComputeGradients(ToGray(panorama)), options, cv::Mat());
}

void ColumnHistograms::Build(const Gradients& g, const HogOptions& o, const cv::Mat& mask) {
  o.Validate();
  if (g.magnitude.empty()) throw std::invalid_argument("hog: empty gradients");
  const int rows = g.magnitude.rows;
  const int band_h = o.band_height_px > 0 ? o.band_height_px : rows - o.band_top_px;
  if (o.band_top_px + band_h > rows || band_h < o.cell_size_px) {
    throw std::invalid_argument("hog: band rows " + std::to_string(o.band_top_px) + "+" + std::to_string(band_h) +
                                " do not fit a panorama of " + std::to_string(rows) + " rows with cells of " +
                                std::to_string(o.cell_size_px));
  }
  CheckMask(mask, g.magnitude.size(), "hog");
  const bool use_mask = HasMaskedPixels(mask);
  width_ = g.magnitude.cols;
  cell_rows_ = band_h / o.cell_size_px;
  bins_ = o.bins;
  cell_size_ = o.cell_size_px;
  max_masked_share_ = o.max_masked_share;
  prefix_.assign(static_cast<size_t>(cell_rows_) * (width_ + 1) * bins_, 0.0);
  if (use_mask) {
    masked_prefix_.assign(static_cast<size_t>(cell_rows_) * (width_ + 1), 0);
    for (int r = 0; r < cell_rows_; ++r) {
      int* mp = &masked_prefix_[static_cast<size_t>(r) * (width_ + 1)];
      for (int x = 0; x < width_; ++x) {
        int masked = 0;
        for (int y = o.band_top_px + r * o.cell_size_px; y < o.band_top_px + (r + 1) * o.cell_size_px; ++y) {
          masked += mask.at<uint8_t>(y, x) == 0;
        }
        mp[x + 1] = mp[x] + masked;
      }
    }
  }
  // Column histograms first (one pass over the pixels), then prefix sums over columns.
  std::vector<double> columns(static_cast<size_t>(width_) * bins_);
  const float bin_scale = static_cast<float>(bins_ / (2 * M_PI));
  const float narrow = static_cast<float>(o.narrow_range_deg * M_PI / 180);
  const float quarter = static_cast<float>(M_PI / 4), pi = static_cast<float>(M_PI), two_pi = static_cast<float>(2 * M_PI);
  for (int r = 0; r < cell_rows_; ++r) {
    std::fill(columns.begin(), columns.end(), 0.0);
    for (int y = o.band_top_px + r * o.cell_size_px; y < o.band_top_px + (r + 1) * o.cell_size_px; ++y) {
      const float* mag = g.magnitude.ptr<float>(y);
      const float* ang = g.angle_rad.ptr<float>(y);
      const uint8_t* usable = use_mask ? mask.ptr<uint8_t>(y) : nullptr;
      for (int x = 0; x < width_; ++x) {
        const float m = mag[x];
        if (m == 0 || (usable && !usable[x])) continue;
        const float a = ang[x];
        if (o.range != OrientationRange::kAll) {
          // Distance of the gradient direction from horizontal (a vertical edge): 0..pi/2.
          const float from_horizontal = std::min({a, std::abs(a - pi), two_pi - a});
          if (o.range == OrientationRange::kVertical && from_horizontal > quarter) continue;
          if (o.range == OrientationRange::kHorizontal && from_horizontal <= quarter) continue;
          if (o.range == OrientationRange::kNarrowVertical && from_horizontal > narrow) continue;
        }
        const int b = std::min(bins_ - 1, static_cast<int>(a * bin_scale));
        columns[static_cast<size_t>(x) * bins_ + b] += m;
      }
    }
    double* pre = &prefix_[static_cast<size_t>(r) * (width_ + 1) * bins_];
    for (int x = 0; x < width_; ++x) {
      for (int b = 0; b < bins_; ++b) pre[(x + 1) * bins_ + b] = pre[x * bins_ + b] + columns[static_cast<size_t>(x) * bins_ + b];
    }
  }
}

void ColumnHistograms::AddRun(int row, int x0, int n, double* out) const {
  const double* pre = &prefix_[static_cast<size_t>(row) * (width_ + 1) * bins_];
  x0 %= width_;
  if (x0 < 0) x0 += width_;
  while (n > 0) {
    const int take = std::min(n, width_ - x0);
    for (int b = 0; b < bins_; ++b) out[b] += pre[(x0 + take) * bins_ + b] - pre[x0 * bins_ + b];
    n -= take;
    x0 = 0;
  }
}

double ColumnHistograms::MaskedShare(int row, int x0, int n) const {
  if (masked_prefix_.empty() || n <= 0) return 0.0;
  const int* mp = &masked_prefix_[static_cast<size_t>(row) * (width_ + 1)];
  x0 %= width_;
  if (x0 < 0) x0 += width_;
  int masked = 0;
  const int total = n;
  while (n > 0) {
    const int take = std::min(n, width_ - x0);
    masked += mp[x0 + take] - mp[x0];
    n -= take;
    x0 = 0;
  }
  return static_cast<double>(masked) / (static_cast<double>(total) * cell_size_);
}

namespace {

// A cell's usability and the scale of its histogram (the usable share's inverse).
inline bool CellUsable(double masked_share, double max_masked_share, double* scale) {
  if (masked_share > max_masked_share) return false;
  *scale = masked_share > 0 ? 1.0 / (1.0 - masked_share) : 1.0;
  return true;
}

}  // namespace

HogCells CellsAtShift(const ColumnHistograms& h, int cell_size_px, int shift_px) {
  HogCells c;
  c.cell_rows = h.cell_rows();
  c.cell_cols = h.width() / cell_size_px;
  c.bins = h.bins();
  c.values.assign(static_cast<size_t>(c.cell_rows) * c.cell_cols * c.bins, 0.0);
  if (h.masked()) c.valid.assign(static_cast<size_t>(c.cell_rows) * c.cell_cols, 1);
  for (int r = 0; r < c.cell_rows; ++r) {
    for (int p = 0; p < c.cell_cols; ++p) {
      double* out = &c.values[(static_cast<size_t>(r) * c.cell_cols + p) * c.bins];
      h.AddRun(r, shift_px + p * cell_size_px, cell_size_px, out);
      if (!h.masked()) continue;
      double scale = 1.0;
      if (!CellUsable(h.MaskedShare(r, shift_px + p * cell_size_px, cell_size_px), h.max_masked_share(), &scale)) {
        c.valid[static_cast<size_t>(r) * c.cell_cols + p] = 0;
        std::fill(out, out + c.bins, 0.0);
      } else if (scale != 1.0) {
        for (int q = 0; q < c.bins; ++q) out[q] *= scale;
      }
    }
  }
  return c;
}

double CellEntropyBits(const HogCells& cells) {
  double weighted = 0, energy = 0;
  for (int k = 0; k < cells.cell_rows * cells.cell_cols; ++k) {
    const double* h = &cells.values[static_cast<size_t>(k) * cells.bins];
    double total = 0;
    for (int q = 0; q < cells.bins; ++q) total += h[q];
    if (total <= 0) continue;
    double entropy = 0;
    for (int q = 0; q < cells.bins; ++q) {
      if (h[q] > 0) entropy -= h[q] / total * std::log2(h[q] / total);
    }
    weighted += total * entropy;
    energy += total;
  }
  return energy > 0 ? weighted / energy : 0.0;
}

CompassResult VisualCompass(const ColumnHistograms& home, const ColumnHistograms& current, int cell_size_px) {
  if (home.width() != current.width() || home.cell_rows() != current.cell_rows() || home.bins() != current.bins()) {
    throw std::invalid_argument("compass: the two panoramas have different HOG shapes");
  }
  const HogCells h = CellsAtShift(home, cell_size_px, 0);
  CompassResult result;
  const int w = home.width(), bins = home.bins();
  result.distance_by_shift.assign(w, 0.0);
  // The current view's cell histogram starting at every column, per cell row: each shift
  // then reads contiguous memory instead of summing runs.
  std::vector<double> starts(static_cast<size_t>(w) * bins);
  // With masks: only cells usable in both views count, and D(s) is scaled to all the cells.
  const bool masked = home.masked() || current.masked();
  std::vector<uint8_t> start_usable(static_cast<size_t>(w), 1);
  std::vector<int> pairs(masked ? static_cast<size_t>(w) : 0, 0);
  for (int r = 0; r < h.cell_rows; ++r) {
    std::fill(starts.begin(), starts.end(), 0.0);
    for (int x = 0; x < w; ++x) {
      double* out = &starts[static_cast<size_t>(x) * bins];
      current.AddRun(r, x, cell_size_px, out);
      if (!current.masked()) continue;
      double scale = 1.0;
      start_usable[x] = CellUsable(current.MaskedShare(r, x, cell_size_px), current.max_masked_share(), &scale);
      if (scale != 1.0) {
        for (int q = 0; q < bins; ++q) out[q] *= scale;
      }
    }
    for (int p = 0; p < h.cell_cols; ++p) {
      const double* ref = &h.values[(static_cast<size_t>(r) * h.cell_cols + p) * bins];
      if (!h.usable(r, p)) continue;
      for (int s = 0; s < w; ++s) {
        int x = s + p * cell_size_px;
        if (x >= w) x -= w * (x / w);
        if (masked) {
          if (!start_usable[x]) continue;
          ++pairs[s];
        }
        const double* cur = &starts[static_cast<size_t>(x) * bins];
        double d2 = 0;
        for (int q = 0; q < bins; ++q) {
          const double diff = cur[q] - ref[q];
          d2 += diff * diff;
        }
        result.distance_by_shift[s] += std::sqrt(d2);  // Euclidean distance per cell (3.1.2), summed
      }
    }
  }
  if (masked) {
    const double all = static_cast<double>(h.cell_rows) * h.cell_cols;
    for (int s = 0; s < w; ++s) {
      result.distance_by_shift[s] = pairs[s] > 0 ? result.distance_by_shift[s] * all / pairs[s]
                                                 : std::numeric_limits<double>::max() / 4;
    }
  }
  int best = 0;
  for (int s = 1; s < w; ++s) {
    if (result.distance_by_shift[s] < result.distance_by_shift[best]) best = s;
  }
  // Sub-column refinement: vertex of the parabola through the minimum and its neighbours.
  const double dm = result.distance_by_shift[(best + w - 1) % w], d0 = result.distance_by_shift[best],
               dp = result.distance_by_shift[(best + 1) % w];
  const double denom = dm - 2 * d0 + dp;
  const double offset = denom > 0 ? std::clamp(0.5 * (dm - dp) / denom, -0.5, 0.5) : 0.0;
  result.shift_px = best + offset;
  if (result.shift_px > w / 2.0) result.shift_px -= w;
  result.rotation_rad = WrapAngle(result.shift_px * 2 * M_PI / w);
  result.min_distance = d0;
  return result;
}

std::vector<Eigen::Vector2d> BinAlvs(const HogCells& cells, int cell_size_px, const PanoramaModel& panorama,
                                     const HogAlvOptions& options, const std::vector<uint8_t>* use) {
  std::vector<Eigen::Vector2d> alv(static_cast<size_t>(cells.bins), Eigen::Vector2d::Zero());
  const bool log_weight = options.weight == CellWeight::kLog;
  for (int p = 0; p < cells.cell_cols; ++p) {
    // Bearing of the cell centre; for cells taken at the compass shift this is the bearing
    // in the home view's frame.
    const double phi = panorama.BearingOfColumn(p * cell_size_px + cell_size_px / 2.0);
    const Eigen::Vector2d dir(std::cos(phi), std::sin(phi));
    for (int r = 0; r < cells.cell_rows; ++r) {
      if (use && !(*use)[static_cast<size_t>(r) * cells.cell_cols + p]) continue;
      for (int q = 0; q < cells.bins; ++q) {
        const double m = std::abs(cells.at(r, p, q));
        alv[q] += (log_weight ? std::log1p(m / options.log_scale) : m) * dir;
      }
    }
  }
  return alv;
}

std::optional<HomingEstimate> HogHoming(const ColumnHistograms& home, const ColumnHistograms& current,
                                        const HogOptions& hog, const HogAlvOptions& alv_options,
                                        const PanoramaModel& panorama, const CompassResult& compass) {
  alv_options.Validate();
  if (home.width() != current.width() || home.cell_rows() != current.cell_rows() || home.bins() != current.bins()) {
    throw std::invalid_argument("hog homing: the two panoramas have different HOG shapes");
  }
  const double shift_px = compass.rotation_rad * home.width() / (2 * M_PI);
  const int shift = static_cast<int>(std::lround(shift_px));
  // Current cells sampled at the compass shift look at the same world bearings as the home cells.
  const HogCells home_cells = CellsAtShift(home, hog.cell_size_px, 0);
  const HogCells cur_cells = CellsAtShift(current, hog.cell_size_px, shift);
  // With masks, a cell counts in both ALVs only when it is usable in both views.
  std::vector<uint8_t> both;
  if (!home_cells.valid.empty() || !cur_cells.valid.empty()) {
    both.assign(static_cast<size_t>(home_cells.cell_rows) * home_cells.cell_cols, 1);
    for (int r = 0; r < home_cells.cell_rows; ++r) {
      for (int p = 0; p < home_cells.cell_cols; ++p) {
        both[static_cast<size_t>(r) * home_cells.cell_cols + p] = home_cells.usable(r, p) && cur_cells.usable(r, p);
      }
    }
  }
  const std::vector<uint8_t>* use = both.empty() ? nullptr : &both;
  const auto home_alv = BinAlvs(home_cells, hog.cell_size_px, panorama, alv_options, use);
  auto cur_alv = BinAlvs(cur_cells, hog.cell_size_px, panorama, alv_options, use);
  // The sub-column rest of the shift rotates the current cells' bearings in the home frame.
  const double residual = (shift_px - shift) * 2 * M_PI / home.width();
  if (residual != 0) {
    const Eigen::Rotation2Dd rot(residual);
    for (auto& v : cur_alv) v = rot * v;
  }
  std::vector<Eigen::Vector2d> diff(home_alv.size());
  double strongest = 0;
  for (size_t q = 0; q < diff.size(); ++q) {
    diff[q] = alv_options.difference == AlvDifference::kHomeMinusCurrent ? Eigen::Vector2d(home_alv[q] - cur_alv[q])
                                                                          : Eigen::Vector2d(cur_alv[q] - home_alv[q]);
    strongest = std::max(strongest, diff[q].norm());
  }
  if (strongest <= 0) return std::nullopt;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int used = 0;
  for (const auto& d : diff) {
    if (d.norm() >= alv_options.threshold_frac * strongest) {
      sum += d;
      ++used;
    }
  }
  if (used < alv_options.min_bins || sum.norm() == 0) return std::nullopt;
  HomingEstimate e;
  e.compass_rotation_rad = compass.rotation_rad;
  // `sum` is in the home-aligned frame; the current robot is turned by the compass rotation.
  e.direction_rad = WrapAngle(std::atan2(sum.y(), sum.x()) - compass.rotation_rad);
  e.magnitude = sum.norm();
  e.bins_used = used;
  return e;
}

std::optional<HomingEstimate> HogHoming(const ColumnHistograms& home, const ColumnHistograms& current,
                                        const HogOptions& hog, const HogAlvOptions& alv,
                                        const PanoramaModel& panorama) {
  return HogHoming(home, current, hog, alv, panorama, VisualCompass(home, current, hog.cell_size_px));
}

void WarpCompensationOptions::Validate() const {
  if (!(camera_height_m > 0)) throw std::invalid_argument("warp compensation: camera_height_m must be > 0");
  if (!(height_top_m > height_bottom_m)) throw std::invalid_argument("warp compensation: height_top_m must exceed height_bottom_m");
  if (!(min_distance_m > 0 && max_distance_m > min_distance_m)) throw std::invalid_argument("warp compensation: bad distance clamp");
  if (median_columns < 1 || median_columns % 2 == 0) throw std::invalid_argument("warp compensation: median_columns must be odd");
  if (!(canny_low >= 0 && canny_high >= canny_low)) throw std::invalid_argument("warp compensation: bad Canny thresholds");
}

cv::Mat CompensateWarping(const cv::Mat& gray, const PanoramaModel& panorama, const WarpCompensationOptions& o,
                          std::vector<double>* distances_m) {
  o.Validate();
  if (gray.empty() || gray.type() != CV_8UC1) throw std::invalid_argument("warp compensation: need an 8-bit grey panorama");
  if (gray.cols != panorama.width_px || gray.rows != panorama.height_px) {
    throw std::invalid_argument("warp compensation: image size differs from the panorama model");
  }
  cv::Mat blurred, edges;
  if (o.blur_sigma_px > 0) cv::GaussianBlur(gray, blurred, {0, 0}, o.blur_sigma_px); else blurred = gray;
  cv::Canny(blurred, edges, o.canny_low, o.canny_high);
  // Per column, the lowest edge above the floor: the bottom line of the objects. Rows below
  // the horizon only (an edge above the horizon says nothing about the floor contact).
  const int horizon = std::clamp(static_cast<int>(std::floor(panorama.RowOfElevation(0.0))), 0, gray.rows - 1);
  std::vector<double> distance(static_cast<size_t>(gray.cols), o.max_distance_m);
  for (int x = 0; x < gray.cols; ++x) {
    for (int y = gray.rows - 1; y > horizon; --y) {
      if (edges.at<uint8_t>(y, x) == 0) continue;
      const double elevation = panorama.ElevationOfRow(y);
      if (elevation < 0) distance[x] = std::clamp(o.camera_height_m / std::tan(-elevation), o.min_distance_m, o.max_distance_m);
      break;
    }
  }
  // Median over neighbouring columns (wrapping) removes single-column outliers.
  std::vector<double> smooth(distance.size()), window(static_cast<size_t>(o.median_columns));
  const int half = o.median_columns / 2;
  for (int x = 0; x < gray.cols; ++x) {
    for (int k = -half; k <= half; ++k) window[k + half] = distance[((x + k) % gray.cols + gray.cols) % gray.cols];
    std::nth_element(window.begin(), window.begin() + half, window.end());
    smooth[x] = window[half];
  }
  // Output row r shows height z(r) on the object at the column's distance.
  cv::Mat map_x(gray.size(), CV_32F), map_y(gray.size(), CV_32F);
  for (int x = 0; x < gray.cols; ++x) {
    for (int r = 0; r < gray.rows; ++r) {
      const double z = o.height_top_m - (o.height_top_m - o.height_bottom_m) * r / std::max(1, gray.rows - 1);
      const double elevation = std::atan2(z - o.camera_height_m, smooth[x]);
      map_x.at<float>(r, x) = static_cast<float>(x);
      map_y.at<float>(r, x) = static_cast<float>(panorama.RowOfElevation(elevation));
    }
  }
  cv::Mat out;
  cv::remap(gray, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  if (distances_m) *distances_m = smooth;
  return out;
}

void HogHomingConfig::Validate() const {
  hog.Validate();
  compass_hog.Validate();
  alv.Validate();
  if (warp_compensation) warp.Validate();
}

HogHomer::HogHomer(const HogHomingConfig& config, const PanoramaModel& panorama)
    : config_(config), panorama_(panorama) {
  config_.Validate();
  panorama_.Validate();
}

void HogHomer::SetMask(const cv::Mat& panorama_mask) {
  CheckMask(panorama_mask, cv::Size(panorama_.width_px, panorama_.height_px), "hog homing");
  if (!HasMaskedPixels(panorama_mask)) {
    mask_.release();
    cell_mask_.release();
    return;
  }
  mask_ = panorama_mask.clone();
  // The centred differences at a pixel next to a masked one read it: grown by a pixel.
  cell_mask_ = GrowMasked(mask_, 1);
  if (config_.warp_compensation) {
    // The warping moves pixels within their column: a column with a masked pixel is masked.
    cv::Mat columns;
    cv::reduce(cell_mask_, columns, 0, cv::REDUCE_MIN);
    cell_mask_ = cv::repeat(columns, cell_mask_.rows, 1);
  }
}

HogHomer::Views HogHomer::Describe(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("hog homing: empty panorama");
  if (image.cols != panorama_.width_px || image.rows != panorama_.height_px) {
    throw std::invalid_argument("hog homing: panorama is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", the model is " + std::to_string(panorama_.width_px) +
                                "x" + std::to_string(panorama_.height_px));
  }
  cv::Mat gray = ToGray(image);
  if (!mask_.empty()) {
    gray = gray.clone();
    FillMasked(mask_, &gray);  // no edge of the robot's parts (a no-op on a panorama unwrapped with the mask)
  }
  if (config_.equalize_histogram) {
    cv::Mat eq;
    cv::equalizeHist(gray, eq);
    gray = eq;
  }
  if (config_.warp_compensation) gray = CompensateWarping(gray, panorama_, config_.warp);
  const Gradients g = ComputeGradients(gray);
  return Views{ColumnHistograms(g, config_.hog, cell_mask_), ColumnHistograms(g, config_.compass_hog, cell_mask_)};
}

void HogHomer::SetHome(const cv::Mat& panorama) { home_.emplace(Describe(panorama)); }

std::optional<HomingEstimate> HogHomer::Home(const cv::Mat& panorama, std::optional<double> known_rotation_rad) const {
  if (!home_) throw std::logic_error("hog homing: no home snapshot set");
  const Views current = Describe(panorama);
  CompassResult compass;
  if (known_rotation_rad) {
    compass.rotation_rad = WrapAngle(*known_rotation_rad);
  } else if (config_.use_compass) {
    compass = VisualCompass(home_->compass, current.compass, config_.compass_hog.cell_size_px);
  }
  return HogHoming(home_->hog, current.hog, config_.hog, config_.alv, panorama_, compass);
}

}  // namespace snapnav::nav
