#include "snapnav/nav/hog_homing.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

std::optional<OrientationRange> ParseOrientationRange(const std::string& name) {
  if (name == "all") return OrientationRange::kAll;
  if (name == "vertical") return OrientationRange::kVertical;
  if (name == "horizontal") return OrientationRange::kHorizontal;
  if (name == "narrow_vertical") return OrientationRange::kNarrowVertical;
  return std::nullopt;
}

void HogOptions::Validate() const {
  if (cell_size_px < 2) throw std::invalid_argument("hog: cell_size_px must be >= 2");
  if (bins < 2 || bins > 360) throw std::invalid_argument("hog: bins must be in 2..360");
  if (band_top_px < 0 || band_height_px < 0) throw std::invalid_argument("hog: band must not be negative");
  if (!(narrow_range_deg > 0 && narrow_range_deg <= 90)) throw std::invalid_argument("hog: narrow_range_deg in (0, 90]");
}

void HogAlvOptions::Validate() const {
  if (!(threshold_frac >= 0 && threshold_frac <= 1)) throw std::invalid_argument("hog alv: threshold_frac in [0, 1]");
  if (min_bins < 1) throw std::invalid_argument("hog alv: min_bins >= 1");
}

ColumnHistograms::ColumnHistograms(const cv::Mat& panorama, const HogOptions& o) {
  o.Validate();
  if (panorama.empty() || panorama.depth() != CV_8U) throw std::invalid_argument("hog: need a non-empty 8-bit panorama");
  const int band_h = o.band_height_px > 0 ? o.band_height_px : panorama.rows - o.band_top_px;
  if (o.band_top_px + band_h > panorama.rows || band_h < o.cell_size_px) {
    throw std::invalid_argument("hog: band rows " + std::to_string(o.band_top_px) + "+" + std::to_string(band_h) +
                                " do not fit a panorama of " + std::to_string(panorama.rows) +
                                " rows with cells of " + std::to_string(o.cell_size_px));
  }
  cv::Mat gray;
  if (panorama.channels() == 3) cv::cvtColor(panorama, gray, cv::COLOR_BGR2GRAY); else gray = panorama;
  gray = gray.rowRange(o.band_top_px, o.band_top_px + band_h);
  if (o.equalize_histogram) {
    cv::Mat eq;
    cv::equalizeHist(gray, eq);
    gray = eq;
  }
  width_ = gray.cols;
  cell_rows_ = band_h / o.cell_size_px;
  bins_ = o.bins;
  prefix_.assign(static_cast<size_t>(cell_rows_) * (width_ + 1) * bins_, 0.0);
  std::vector<double> column(static_cast<size_t>(bins_));
  const double bin_width = 2 * M_PI / bins_;
  const double narrow = o.narrow_range_deg * M_PI / 180;
  for (int r = 0; r < cell_rows_; ++r) {
    double* pre = &prefix_[static_cast<size_t>(r) * (width_ + 1) * bins_];
    for (int x = 0; x < width_; ++x) {
      std::fill(column.begin(), column.end(), 0.0);
      const int xl = x == 0 ? width_ - 1 : x - 1, xr = x + 1 == width_ ? 0 : x + 1;  // the panorama wraps around
      for (int y = r * o.cell_size_px; y < (r + 1) * o.cell_size_px; ++y) {
        const int yu = std::max(0, y - 1), yd = std::min(gray.rows - 1, y + 1);
        const double gx = gray.at<uint8_t>(y, xr) - gray.at<uint8_t>(y, xl);  // centred gradient
        const double gy = gray.at<uint8_t>(yd, x) - gray.at<uint8_t>(yu, x);
        const double mag = std::hypot(gx, gy);
        if (mag == 0) continue;
        double angle = std::atan2(gy, gx);  // signed, (-pi, pi]
        if (angle < 0) angle += 2 * M_PI;
        // Distance of the gradient direction from horizontal (a vertical edge): 0..pi/2.
        const double from_horizontal = std::min({angle, std::abs(angle - M_PI), 2 * M_PI - angle});
        switch (o.range) {
          case OrientationRange::kAll: break;
          case OrientationRange::kVertical: if (from_horizontal > M_PI / 4) continue; break;
          case OrientationRange::kHorizontal: if (from_horizontal <= M_PI / 4) continue; break;
          case OrientationRange::kNarrowVertical: if (from_horizontal > narrow) continue; break;
        }
        const int b = std::min(bins_ - 1, static_cast<int>(angle / bin_width));
        column[b] += mag;
      }
      for (int b = 0; b < bins_; ++b) pre[(x + 1) * bins_ + b] = pre[x * bins_ + b] + column[b];
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

HogCells CellsAtShift(const ColumnHistograms& h, int cell_size_px, int shift_px) {
  HogCells c;
  c.cell_rows = h.cell_rows();
  c.cell_cols = h.width() / cell_size_px;
  c.bins = h.bins();
  c.values.assign(static_cast<size_t>(c.cell_rows) * c.cell_cols * c.bins, 0.0);
  for (int r = 0; r < c.cell_rows; ++r) {
    for (int p = 0; p < c.cell_cols; ++p) {
      h.AddRun(r, shift_px + p * cell_size_px, cell_size_px, &c.values[(static_cast<size_t>(r) * c.cell_cols + p) * c.bins]);
    }
  }
  return c;
}

CompassResult VisualCompass(const ColumnHistograms& home, const ColumnHistograms& current, int cell_size_px) {
  if (home.width() != current.width() || home.cell_rows() != current.cell_rows() || home.bins() != current.bins()) {
    throw std::invalid_argument("compass: the two panoramas have different HOG shapes");
  }
  const HogCells h = CellsAtShift(home, cell_size_px, 0);
  CompassResult result;
  result.distance_by_shift.resize(home.width());
  std::vector<double> cell(static_cast<size_t>(home.bins()));
  int best = 0;
  for (int s = 0; s < home.width(); ++s) {
    double d = 0;
    for (int r = 0; r < h.cell_rows; ++r) {
      for (int p = 0; p < h.cell_cols; ++p) {
        std::fill(cell.begin(), cell.end(), 0.0);
        current.AddRun(r, s + p * cell_size_px, cell_size_px, cell.data());
        double d2 = 0;
        for (int q = 0; q < h.bins; ++q) {
          const double diff = cell[q] - h.at(r, p, q);
          d2 += diff * diff;
        }
        d += std::sqrt(d2);  // Euclidean distance per cell (3.1.2), summed
      }
    }
    result.distance_by_shift[s] = d;
    if (d < result.distance_by_shift[best]) best = s;
  }
  // Sub-column refinement: vertex of the parabola through the minimum and its neighbours.
  const int w = home.width();
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

std::vector<Eigen::Vector2d> BinAlvs(const HogCells& cells, int cell_size_px, const PanoramaModel& panorama) {
  std::vector<Eigen::Vector2d> alv(static_cast<size_t>(cells.bins), Eigen::Vector2d::Zero());
  for (int p = 0; p < cells.cell_cols; ++p) {
    // Bearing of the cell centre; for cells taken at the compass shift this is the bearing
    // in the home view's frame.
    const double phi = panorama.BearingOfColumn(p * cell_size_px + cell_size_px / 2.0);
    const Eigen::Vector2d dir(std::cos(phi), std::sin(phi));
    for (int r = 0; r < cells.cell_rows; ++r) {
      for (int q = 0; q < cells.bins; ++q) alv[q] += std::abs(cells.at(r, p, q)) * dir;
    }
  }
  return alv;
}

std::optional<HomingEstimate> HogHoming(const ColumnHistograms& home, const ColumnHistograms& current,
                                        const HogOptions& hog, const HogAlvOptions& alv_options,
                                        const PanoramaModel& panorama) {
  alv_options.Validate();
  const CompassResult compass = VisualCompass(home, current, hog.cell_size_px);
  const int shift = static_cast<int>(std::lround(compass.shift_px));
  // Current cells sampled at the compass shift look at the same world bearings as the home cells.
  const auto home_alv = BinAlvs(CellsAtShift(home, hog.cell_size_px, 0), hog.cell_size_px, panorama);
  const auto cur_alv = BinAlvs(CellsAtShift(current, hog.cell_size_px, shift), hog.cell_size_px, panorama);
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

}  // namespace snapnav::nav
