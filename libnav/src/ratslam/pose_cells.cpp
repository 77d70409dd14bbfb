// RatSLAM pose-cell network: the (x, y, theta) continuous attractor network of OpenRatSLAM.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "snapnav/nav/ratslam/ratslam.hpp"

namespace snapnav::nav {
namespace {

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("ratslam pose cells: " + what);
}

// 3D Gaussian weights over a dim^3 cube around its centre, summing to 1 (OpenRatSLAM's norm2d:
// exp(-d^2 / (2 var^2)), so "var" acts as a standard deviation).
std::vector<double> GaussianWeights(int dim, double var) {
  std::vector<double> w;
  w.reserve(static_cast<size_t>(dim) * dim * dim);
  const int c = dim / 2;
  double total = 0;
  for (int k = 0; k < dim; ++k) {
    for (int j = 0; j < dim; ++j) {
      for (int i = 0; i < dim; ++i) {
        const double d2 = (i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c);
        w.push_back(std::exp(-d2 / (2.0 * var * var)));
        total += w.back();
      }
    }
  }
  for (double& v : w) v /= total;
  return w;
}

// a wrapped into [0, n).
double WrapCells(double a, double n) {
  a = std::fmod(a, n);
  if (a < 0) a += n;
  if (a >= n) a -= n;  // -tiny + n rounds to n
  return a;
}

// Shortest distance between d1 and d2 on a circle of n cells.
double MinDelta(double d1, double d2, double n) {
  const double d = std::abs(d1 - d2);
  return std::min(d, n - d);
}

}  // namespace

void PoseCellOptions::Validate() const {
  Require(pc_dim_xy >= 3 && pc_dim_xy <= 256 && pc_dim_th >= 3 && pc_dim_th <= 720,
          "pc_dim_xy must be 3..256 and pc_dim_th 3..720");
  Require(pc_w_e_dim >= 1 && pc_w_e_dim % 2 == 1 && pc_w_e_dim <= std::min(pc_dim_xy, pc_dim_th),
          "pc_w_e_dim must be odd and at most pc_dim_xy and pc_dim_th");
  Require(pc_w_i_dim >= 1 && pc_w_i_dim % 2 == 1 && pc_w_i_dim <= std::min(pc_dim_xy, pc_dim_th),
          "pc_w_i_dim must be odd and at most pc_dim_xy and pc_dim_th");
  Require(std::isfinite(pc_w_e_var) && pc_w_e_var > 0 && std::isfinite(pc_w_i_var) && pc_w_i_var > 0,
          "pc_w_e_var and pc_w_i_var must be > 0");
  Require(std::isfinite(pc_global_inhib) && pc_global_inhib >= 0 && pc_global_inhib < 1,
          "pc_global_inhib must be in [0, 1)");
  Require(std::isfinite(pc_cell_x_size_m) && pc_cell_x_size_m > 0, "pc_cell_x_size_m must be > 0");
  Require(pc_cells_to_avg >= 0 && 2 * pc_cells_to_avg + 1 <= std::min(pc_dim_xy, pc_dim_th),
          "pc_cells_to_avg must be >= 0 with 2 * pc_cells_to_avg + 1 <= pc_dim_xy and pc_dim_th");
  Require(std::isfinite(pc_vt_inject_energy) && pc_vt_inject_energy >= 0, "pc_vt_inject_energy must be >= 0");
  Require(std::isfinite(vt_active_decay) && vt_active_decay >= 0, "vt_active_decay must be >= 0");
  Require(std::isfinite(pc_vt_restore) && pc_vt_restore >= 0, "pc_vt_restore must be >= 0");
  Require(pc_vt_skip_recent >= 0, "pc_vt_skip_recent must be >= 0");
  Require(std::isfinite(exp_delta_pc_threshold) && exp_delta_pc_threshold > 0, "exp_delta_pc_threshold must be > 0");
  Require(std::isfinite(pc_update_interval_s) && pc_update_interval_s >= 0,
          "pc_update_interval_s must be >= 0 (0: every odometry message)");
}

PoseCellNetwork::PoseCellNetwork(const PoseCellOptions& options) : options_(options) {
  options_.Validate();
  const int d = options_.pc_dim_xy, t = options_.pc_dim_th;
  const size_t n = static_cast<size_t>(d) * d * t;
  cells_.assign(n, 0.0);
  scratch_.assign(n, 0.0);
  layer_.assign(static_cast<size_t>(d) * d, 0.0);
  excite_weights_ = GaussianWeights(options_.pc_w_e_dim, options_.pc_w_e_var);
  inhibit_weights_ = GaussianWeights(options_.pc_w_i_dim, options_.pc_w_i_var);
  // wrap_[i + dim] = i mod dim for i in [-dim, 2 dim).
  wrap_xy_.resize(3 * static_cast<size_t>(d));
  for (int i = -d; i < 2 * d; ++i) wrap_xy_[static_cast<size_t>(i + d)] = ((i % d) + d) % d;
  wrap_th_.resize(3 * static_cast<size_t>(t));
  for (int i = -t; i < 2 * t; ++i) wrap_th_[static_cast<size_t>(i + t)] = ((i % t) + t) % t;
  sum_x_.assign(static_cast<size_t>(d), 0.0);
  sum_y_.assign(static_cast<size_t>(d), 0.0);
  sum_th_.assign(static_cast<size_t>(t), 0.0);
  templates_.reserve(1024);
  experiences_.reserve(1024);
  SetSingleCell(d / 2, d / 2, t / 2);
}

void PoseCellNetwork::SetSingleCell(int x, int y, int th) {
  const int d = options_.pc_dim_xy, t = options_.pc_dim_th;
  Require(x >= 0 && x < d && y >= 0 && y < d && th >= 0 && th < t, "SetSingleCell outside the network");
  std::fill(cells_.begin(), cells_.end(), 0.0);
  cells_[Index(x, y, th)] = 1.0;
  FindBest();
}

void PoseCellNetwork::Inject(int x, int y, int th, double energy) {
  const int d = options_.pc_dim_xy, t = options_.pc_dim_th;
  if (x >= 0 && x < d && y >= 0 && y < d && th >= 0 && th < t) cells_[Index(x, y, th)] += energy;
}

// out += every active cell's activity spread by the dim^3 weights centred on it (wrapping).
void PoseCellNetwork::Spread(const std::vector<double>& weights, int dim, std::vector<double>* out) const {
  const int d = options_.pc_dim_xy, t = options_.pc_dim_th, half = dim / 2;
  const int* wxy = wrap_xy_.data() + d;
  const int* wth = wrap_th_.data() + t;
  double* o = out->data();
  for (int z = 0; z < t; ++z) {
    for (int y = 0; y < d; ++y) {
      const double* row = &cells_[Index(0, y, z)];
      for (int x = 0; x < d; ++x) {
        const double v = row[x];
        if (v == 0) continue;
        const double* w = weights.data();
        for (int dz = -half; dz <= half; ++dz) {
          const size_t zw = static_cast<size_t>(wth[z + dz]);
          for (int dy = -half; dy <= half; ++dy) {
            double* orow = o + (zw * d + static_cast<size_t>(wxy[y + dy])) * d;
            for (int dx = -half; dx <= half; ++dx) orow[wxy[x + dx]] += v * *w++;
          }
        }
      }
    }
  }
}

void PoseCellNetwork::Iterate() {
  // Local excitation: the activity becomes its spread by the excitatory weights.
  std::fill(scratch_.begin(), scratch_.end(), 0.0);
  Spread(excite_weights_, options_.pc_w_e_dim, &scratch_);
  cells_.swap(scratch_);
  // Local inhibition: minus its spread by the (wider) inhibitory weights.
  std::fill(scratch_.begin(), scratch_.end(), 0.0);
  Spread(inhibit_weights_, options_.pc_w_i_dim, &scratch_);
  // Global inhibition (floor 0), then normalisation to a total of 1.
  const double g = options_.pc_global_inhib;
  double total = 0;
  for (size_t i = 0; i < cells_.size(); ++i) {
    const double v = cells_[i] - scratch_[i];
    cells_[i] = v >= g ? v - g : 0.0;
    total += cells_[i];
  }
  if (!(total > 0)) {
    // Everything inhibited (cannot happen with sane weights; OpenRatSLAM asserts): restart the
    // packet at the last best cell rather than divide by zero.
    SetSingleCell(static_cast<int>(best_x_) % options_.pc_dim_xy, static_cast<int>(best_y_) % options_.pc_dim_xy,
                  static_cast<int>(best_th_) % options_.pc_dim_th);
    return;
  }
  const double inv = 1.0 / total;
  for (double& v : cells_) v *= inv;
}

void PoseCellNetwork::PathIntegrate(double translation_cells, double direction_rad, double rotation_rad) {
  Require(std::isfinite(translation_cells) && std::isfinite(direction_rad) && std::isfinite(rotation_rad),
          "path integration needs finite values");
  const int d = options_.pc_dim_xy, t = options_.pc_dim_th;
  const double cell_th = kTwoPi / t;
  const size_t plane = static_cast<size_t>(d) * d;
  const int* wxy = wrap_xy_.data() + d;
  if (translation_cells != 0) {
    // Each theta layer shifts along its own heading: activity at p moves to p + s. The integer
    // part of s is an index shift, the fraction spreads over four cells with bilinear weights
    // (OpenRatSLAM's weights for shifts under one cell).
    for (int k = 0; k < t; ++k) {
      double* cells = &cells_[static_cast<size_t>(k) * plane];
      bool active = false;
      for (size_t i = 0; i < plane && !active; ++i) active = cells[i] != 0;
      if (!active) continue;
      const double dir = k * cell_th + direction_rad;
      const double sx = translation_cells * std::cos(dir), sy = translation_cells * std::sin(dir);
      const double fx0 = std::floor(sx), fy0 = std::floor(sy);
      const double fx = sx - fx0, fy = sy - fy0;
      // Integer shifts reduced to [0, d) so that x - ix - 1 stays within the wrap table.
      const int ix = static_cast<int>(WrapCells(fx0, d)), iy = static_cast<int>(WrapCells(fy0, d));
      const double w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
      std::copy(cells, cells + plane, layer_.begin());
      for (int y = 0; y < d; ++y) {
        const double* r0 = &layer_[static_cast<size_t>(wxy[y - iy]) * d];
        const double* r1 = &layer_[static_cast<size_t>(wxy[y - iy - 1]) * d];
        double* out = cells + static_cast<size_t>(y) * d;
        for (int x = 0; x < d; ++x) {
          const int c0 = wxy[x - ix], c1 = wxy[x - ix - 1];
          out[x] = w00 * r0[c0] + w10 * r0[c1] + w01 * r1[c0] + w11 * r1[c1];
        }
      }
    }
  }
  if (rotation_rad != 0) {
    // Layer k takes (1 - f) of layer k - n and f of layer k - n - 1, n + f = the turn in cells.
    const double r = rotation_rad / cell_th;
    const double n0 = std::floor(r);
    const double f = r - n0;
    const int n = static_cast<int>(WrapCells(n0, t));
    const int* wth = wrap_th_.data() + t;
    for (int k = 0; k < t; ++k) {
      const double* a = &cells_[static_cast<size_t>(wth[k - n]) * plane];
      const double* b = &cells_[static_cast<size_t>(wth[k - n - 1]) * plane];
      double* out = &scratch_[static_cast<size_t>(k) * plane];
      for (size_t i = 0; i < plane; ++i) out[i] = (1 - f) * a[i] + f * b[i];
    }
    cells_.swap(scratch_);
  }
}

void PoseCellNetwork::FindBest() {
  const int d = options_.pc_dim_xy, t = options_.pc_dim_th, avg = options_.pc_cells_to_avg;
  // The most active cell (the first of equals in th, y, x order, as OpenRatSLAM).
  double max = 0;
  int mx = static_cast<int>(best_x_), my = static_cast<int>(best_y_), mth = static_cast<int>(best_th_);
  for (int k = 0; k < t; ++k) {
    for (int j = 0; j < d; ++j) {
      const double* row = &cells_[Index(0, j, k)];
      for (int i = 0; i < d; ++i) {
        if (row[i] > max) {
          max = row[i];
          mx = i;
          my = j;
          mth = k;
        }
      }
    }
  }
  if (!(max > 0)) return;  // no activity: keep the last estimate
  // Sums over each axis within +-avg cells of it, then the circular mean of each axis
  // (population vector decoding, so the packet may straddle the wrap-around).
  std::fill(sum_x_.begin(), sum_x_.end(), 0.0);
  std::fill(sum_y_.begin(), sum_y_.end(), 0.0);
  std::fill(sum_th_.begin(), sum_th_.end(), 0.0);
  const int* wxy = wrap_xy_.data() + d;
  const int* wth = wrap_th_.data() + t;
  for (int k = mth - avg; k <= mth + avg; ++k) {
    const int kw = wth[k];
    for (int j = my - avg; j <= my + avg; ++j) {
      const int jw = wxy[j];
      for (int i = mx - avg; i <= mx + avg; ++i) {
        const int iw = wxy[i];
        const double v = cells_[Index(iw, jw, kw)];
        sum_x_[static_cast<size_t>(iw)] += v;
        sum_y_[static_cast<size_t>(jw)] += v;
        sum_th_[static_cast<size_t>(kw)] += v;
      }
    }
  }
  auto circular_mean = [](const std::vector<double>& sums, int n) {
    double s = 0, c = 0;
    for (int i = 0; i < n; ++i) {
      s += std::sin(kTwoPi * i / n) * sums[static_cast<size_t>(i)];
      c += std::cos(kTwoPi * i / n) * sums[static_cast<size_t>(i)];
    }
    return WrapCells(std::atan2(s, c) * n / kTwoPi, n);
  };
  best_x_ = circular_mean(sum_x_, d);
  best_y_ = circular_mean(sum_y_, d);
  best_th_ = circular_mean(sum_th_, t);
}

double PoseCellNetwork::best_heading_rad() const { return best_th_ * kTwoPi / options_.pc_dim_th; }

PoseCellPeak PoseCellNetwork::peak() const {
  PoseCellPeak p;
  p.x = best_x_;
  p.y = best_y_;
  p.th = best_th_;
  for (double v : cells_) {
    p.max_activity = std::max(p.max_activity, v);
    if (v > 0) ++p.active_cells;
  }
  return p;
}

void PoseCellNetwork::OnOdometry(double translation_m, double direction_rad, double rotation_rad) {
  Require(std::isfinite(translation_m) && std::isfinite(direction_rad) && std::isfinite(rotation_rad),
          "odometry must be finite");
  Iterate();
  PathIntegrate(translation_m / options_.pc_cell_x_size_m, direction_rad, rotation_rad);
  FindBest();
  odo_update_ = true;
}

void PoseCellNetwork::OnViewTemplate(int id, double relative_rad) {
  Require(std::isfinite(relative_rad), "the view's heading offset must be finite");
  const int count = static_cast<int>(templates_.size());
  Require(id >= 0 && id <= count,
          "view template " + std::to_string(id) + " unknown (" + std::to_string(count) + " seen; a new one is " +
              std::to_string(count) + ")");
  const int t = options_.pc_dim_th;
  vt_relative_rad_ = relative_rad;
  vt_delta_pc_th_ = relative_rad / kTwoPi * t;
  if (id == count) {
    // A new template remembers where the network is.
    templates_.push_back({best_x_, best_y_, best_th_, options_.vt_active_decay, {}});
  } else if (id < count - options_.pc_vt_skip_recent) {
    ViewCell& vc = templates_[static_cast<size_t>(id)];
    // Seen again and again (the robot stands still or the view is bland): less and less energy.
    if (id == current_vt_) vc.decay += options_.vt_active_decay;
    const double energy = options_.pc_vt_inject_energy / 30.0 * (30.0 - std::exp(1.2 * vc.decay));
    if (energy > 0) {
      // The nearest cell (OpenRatSLAM truncates, half a cell off on average).
      const int d = options_.pc_dim_xy;
      const auto nearest = [](double v, int n) { return static_cast<int>(std::lround(v)) % n; };
      Inject(nearest(vc.x, d), nearest(vc.y, d), nearest(WrapCells(vc.th + vt_delta_pc_th_, t), t), energy);
      ++injections_;
    }
  }
  for (ViewCell& vc : templates_) vc.decay = std::max(options_.vt_active_decay, vc.decay - options_.pc_vt_restore);
  prev_vt_ = current_vt_;
  current_vt_ = id;
  vt_update_ = true;
}

double PoseCellNetwork::DeltaPc(const CellExperience& e) const {
  // Headings in the frame of the templates: the best cell's and the experience's, each without the
  // heading offset of its view.
  const double th = WrapCells(best_th_ - vt_delta_pc_th_, options_.pc_dim_th);
  const double e_th = WrapCells(e.th - e.th_offset, options_.pc_dim_th);
  const double dx = MinDelta(best_x_, e.x, options_.pc_dim_xy);
  const double dy = MinDelta(best_y_, e.y, options_.pc_dim_xy);
  const double dth = MinDelta(th, e_th, options_.pc_dim_th);
  return std::sqrt(dx * dx + dy * dy + dth * dth);
}

void PoseCellNetwork::CreateExperience() {
  experiences_.push_back({best_x_, best_y_, best_th_, current_vt_, vt_delta_pc_th_});
  current_exp_ = static_cast<int>(experiences_.size()) - 1;
  templates_[static_cast<size_t>(current_vt_)].experiences.push_back(current_exp_);
}

PoseCellAction PoseCellNetwork::GetAction() {
  PoseCellAction a;
  if (!(odo_update_ && vt_update_)) return a;
  odo_update_ = vt_update_ = false;
  if (templates_.empty()) return a;
  a.relative_rad = vt_relative_rad_;
  const ViewCell& vc = templates_[static_cast<size_t>(current_vt_)];
  if (experiences_.empty() || vc.experiences.empty()) {
    CreateExperience();
    a.kind = PoseCellAction::kCreateExperience;
  } else {
    const double delta = DeltaPc(experiences_[static_cast<size_t>(current_exp_)]);
    if (delta > options_.exp_delta_pc_threshold || current_vt_ != prev_vt_) {
      // The experience of the current view nearest to the best cell (the current one aside).
      int nearest = -1;
      double nearest_delta = std::numeric_limits<double>::infinity();
      for (int e : vc.experiences) {
        if (e == current_exp_) continue;
        const double de = DeltaPc(experiences_[static_cast<size_t>(e)]);
        if (de < nearest_delta) {
          nearest_delta = de;
          nearest = e;
        }
      }
      const int matched = nearest_delta < options_.exp_delta_pc_threshold ? nearest : -1;
      if (matched >= 0) {
        current_exp_ = matched;
        a.kind = PoseCellAction::kLinkExperience;
      } else {
        // No familiar experience close enough: a new one.
        CreateExperience();
        a.kind = PoseCellAction::kCreateExperience;
      }
    }
  }
  a.experience = current_exp_;
  return a;
}

}  // namespace snapnav::nav
