// Place cells (thesis 4.4, 5.1, 5.2): views, distance measures, memory, localization, exploration.

#include "snapnav/nav/places/place_cells.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/homing/image_mask.hpp"

namespace snapnav::nav {

namespace {
constexpr double kPi = 3.14159265358979323846;

double Clamp01(double v) { return std::max(0.0, std::min(1.0, v)); }

// Descriptors whose values are all integers in [0, 255] (OpenCV's SIFT) are kept as 8 bits.
cv::Mat CompactDescriptors(const cv::Mat& descriptors) {
  if (descriptors.empty() || descriptors.type() != CV_32F) return descriptors;
  for (int r = 0; r < descriptors.rows; ++r) {
    const float* p = descriptors.ptr<float>(r);
    for (int c = 0; c < descriptors.cols; ++c) {
      if (p[c] < 0 || p[c] > 255 || p[c] != std::floor(p[c])) return descriptors;
    }
  }
  cv::Mat out;
  descriptors.convertTo(out, CV_8U);
  return out;
}

// A landmark set whose descriptors are CV_32F (matching needs them), sharing what it can.
LandmarkSet FloatSet(const LandmarkSet& set) {
  if (set.descriptors.empty() || set.descriptors.type() == CV_32F) return set;
  LandmarkSet out;
  out.method = set.method;
  out.width_px = set.width_px;
  out.height_px = set.height_px;
  out.landmarks = set.landmarks;
  set.descriptors.convertTo(out.descriptors, CV_32F);
  return out;
}

double Bearing(const PanoramaModel& panorama, const Landmark& l) { return panorama.BearingOfColumn(l.x_px); }

// The circular mode of angles (1 degree bins smoothed over +-window), refined by the mean of the
// angles within the window.
double CircularMode(const std::vector<double>& angles, double window_rad) {
  constexpr int kBins = 360;
  std::vector<double> hist(kBins, 0.0);
  for (double a : angles) {
    int b = static_cast<int>(std::floor((WrapAngle(a) + kPi) / (2 * kPi) * kBins)) % kBins;
    hist[(b + kBins) % kBins] += 1;
  }
  const int w = std::max(1, static_cast<int>(std::round(window_rad / (2 * kPi) * kBins)));
  int best = 0;
  double best_v = -1;
  for (int b = 0; b < kBins; ++b) {
    double v = 0;
    for (int d = -w; d <= w; ++d) v += hist[(b + d + kBins) % kBins];
    if (v > best_v) {
      best_v = v;
      best = b;
    }
  }
  const double centre = (best + 0.5) / kBins * 2 * kPi - kPi;
  double s = 0, c = 0;
  for (double a : angles) {
    if (std::abs(WrapAngle(a - centre)) <= window_rad) {
      s += std::sin(a);
      c += std::cos(a);
    }
  }
  return (s == 0 && c == 0) ? centre : std::atan2(s, c);
}

}  // namespace

const char* PlaceMeasureName(PlaceMeasure measure) {
  switch (measure) {
    case PlaceMeasure::kBearingDifference: return "bearing";
    case PlaceMeasure::kMatchCount: return "count";
    case PlaceMeasure::kVlineTemplate: return "vline";
  }
  return "?";
}
std::optional<PlaceMeasure> ParsePlaceMeasure(const std::string& name) {
  if (name == "bearing") return PlaceMeasure::kBearingDifference;
  if (name == "count") return PlaceMeasure::kMatchCount;
  if (name == "vline") return PlaceMeasure::kVlineTemplate;
  return std::nullopt;
}
const char* MatchRefinementName(MatchRefinement refinement) {
  return refinement == MatchRefinement::kRansac ? "ransac" : "smallest";
}
const char* PlaceEstimateName(PlaceEstimate estimate) {
  return estimate == PlaceEstimate::kInterpolated ? "interpolated" : "nearest";
}

void PlaceViewOptions::Validate() const {
  features.Validate();
  if (features.method != LandmarkMethod::kSift && features.method != LandmarkMethod::kSurf) {
    throw std::invalid_argument("place cells: features.method must be sift or surf");
  }
  vline.Validate();
  if (window_px < 4 || window_px > 64) throw std::invalid_argument("place cells: window_px must be in [4, 64]");
  if (!(window_scale > 0)) throw std::invalid_argument("place cells: window_scale must be positive");
  if (signature_width_px < 8 || signature_height_px < 1) {
    throw std::invalid_argument("place cells: signature_width_px must be >= 8 and signature_height_px >= 1");
  }
}

void PlaceMeasureOptions::Validate() const {
  match.Validate();
  if (!(keep_fraction > 0 && keep_fraction <= 1)) throw std::invalid_argument("place cells: keep_fraction must be in (0, 1]");
  if (keep_min < 1) throw std::invalid_argument("place cells: keep_min must be at least 1");
  if (!(ransac_threshold_rad > 0)) throw std::invalid_argument("place cells: ransac_threshold_rad must be positive");
  if (!(residual_cap_rad >= 0)) throw std::invalid_argument("place cells: residual_cap_rad must be >= 0");
  if (ransac_iterations < 1) throw std::invalid_argument("place cells: ransac_iterations must be at least 1");
  if (!(window_min_ncc >= -1 && window_min_ncc <= 1)) throw std::invalid_argument("place cells: window_min_ncc must be in [-1, 1]");
  if (min_matches < 1) throw std::invalid_argument("place cells: min_matches must be at least 1");
  if (templates < 1 || templates > 64) throw std::invalid_argument("place cells: templates must be in [1, 64]");
  if (!(image_difference_weight >= 0)) throw std::invalid_argument("place cells: image_difference_weight must be >= 0");
}

void DistanceFilterOptions::Validate() const {
  if (!(radius_m > 0)) throw std::invalid_argument("place cells: filter radius_m must be positive");
  if (!(weight >= 0 && weight <= 1)) throw std::invalid_argument("place cells: filter weight must be in [0, 1]");
  if (!(gate_m >= 0)) throw std::invalid_argument("place cells: filter gate_m must be >= 0");
}

void LocalizerOptions::Validate() const {
  measure.Validate();
  filter.Validate();
  if (interpolate_k < 1) throw std::invalid_argument("place cells: interpolate_k must be at least 1");
  if (!(interpolate_power > 0)) throw std::invalid_argument("place cells: interpolate_power must be positive");
  if (!(interpolate_radius_m > 0)) throw std::invalid_argument("place cells: interpolate_radius_m must be positive");
  if (candidates < 1) throw std::invalid_argument("place cells: candidates must be at least 1");
  if (near_candidates < 0) throw std::invalid_argument("place cells: near_candidates must be >= 0");
  if (exhaustive_below < 0) throw std::invalid_argument("place cells: exhaustive_below must be >= 0");
  if (!(min_position_sigma_m > 0)) throw std::invalid_argument("place cells: min_position_sigma_m must be positive");
}

// ---------------------------------------------------------------------------------------------
// Views.

int64_t PlaceView::bytes() const {
  auto set_bytes = [](const LandmarkSet& s) {
    return static_cast<int64_t>(s.landmarks.size() * sizeof(Landmark) + s.descriptors.total() * s.descriptors.elemSize());
  };
  return set_bytes(landmarks) + set_bytes(vlines) + static_cast<int64_t>(windows.total() * windows.elemSize()) +
         static_cast<int64_t>(signature.total() * signature.elemSize());
}

namespace {
// Normalised windows around the landmarks (5.2.1): the grey panorama wraps horizontally and is
// replicated vertically.
cv::Mat MakeWindows(const cv::Mat& gray, const LandmarkSet& set, const PlaceViewOptions& options) {
  const int n = set.size();
  const int side = options.window_px;
  cv::Mat windows(n, side * side, CV_8S);
  if (n == 0) return windows;
  float largest = 8;
  for (const auto& l : set.landmarks) largest = std::max(largest, static_cast<float>(options.window_scale * l.scale_px));
  const int pad = std::min(static_cast<int>(std::ceil(largest / 2)) + 2, 256);
  cv::Mat wrapped, padded;
  const int hpad = std::min(pad, gray.cols);
  cv::copyMakeBorder(gray, wrapped, 0, 0, hpad, hpad, cv::BORDER_WRAP);
  cv::copyMakeBorder(wrapped, padded, pad, pad, 0, 0, cv::BORDER_REPLICATE);
  cv::Mat patch, resized, f;
  for (int i = 0; i < n; ++i) {
    const auto& l = set.landmarks[i];
    const int s = std::max(8, static_cast<int>(std::round(options.window_scale * l.scale_px)));
    const int s_clamped = std::min(s, 2 * pad - 2);
    const int x0 = static_cast<int>(std::round(l.x_px)) + hpad - s_clamped / 2;
    const int y0 = static_cast<int>(std::round(l.y_px)) + pad - s_clamped / 2;
    const cv::Rect roi = cv::Rect(x0, y0, s_clamped, s_clamped) & cv::Rect(0, 0, padded.cols, padded.rows);
    cv::resize(padded(roi), resized, cv::Size(side, side), 0, 0, cv::INTER_AREA);
    resized.convertTo(f, CV_32F);
    cv::Scalar mean, stddev;
    cv::meanStdDev(f, mean, stddev);
    const double sd = std::max(stddev[0], 1.0);
    signed char* out = windows.ptr<signed char>(i);
    const float* in = f.ptr<float>(0);
    for (int j = 0; j < side * side; ++j) {
      const double v = (in[j] - mean[0]) / sd * 32.0;
      out[j] = static_cast<signed char>(std::max(-127.0, std::min(127.0, std::round(v))));
    }
  }
  return windows;
}

double WindowNcc(const cv::Mat& a, int ra, const cv::Mat& b, int rb) {
  const signed char* pa = a.ptr<signed char>(ra);
  const signed char* pb = b.ptr<signed char>(rb);
  double ab = 0, aa = 0, bb = 0;
  for (int j = 0; j < a.cols; ++j) {
    ab += static_cast<double>(pa[j]) * pb[j];
    aa += static_cast<double>(pa[j]) * pa[j];
    bb += static_cast<double>(pb[j]) * pb[j];
  }
  return (aa > 0 && bb > 0) ? ab / std::sqrt(aa * bb) : 0.0;
}
}  // namespace

PlaceView MakePlaceView(const cv::Mat& panorama, const PlaceViewOptions& options, const cv::Mat& mask,
                        const cv::Mat& clearance_in) {
  options.Validate();
  if (panorama.empty()) throw std::invalid_argument("place cells: empty panorama");
  cv::Mat gray;
  if (panorama.type() == CV_8UC3) {
    cv::cvtColor(panorama, gray, cv::COLOR_BGR2GRAY);
  } else if (panorama.type() == CV_8UC1) {
    gray = panorama;
  } else {
    throw std::invalid_argument("place cells: the panorama must be 8-bit grey or BGR");
  }
  CheckMask(mask, gray.size(), "place cells");
  const bool masked = HasMaskedPixels(mask);
  if (masked) {
    gray = gray.clone();
    FillMasked(mask, &gray);
  }
  // The landmarks' and the lines' masking share one distance transform.
  const cv::Mat clearance = masked && clearance_in.empty() ? MaskClearance(mask) : clearance_in;
  PlaceView view;
  view.landmarks = ExtractLandmarks(gray, options.features, masked ? mask : cv::Mat(), clearance);
  view.windows = MakeWindows(gray, view.landmarks, options);
  if (options.keep_vlines) {
    view.vlines = DetectVlineLandmarks(gray, options.vline);
    if (masked) view.vlines = DropMaskedLandmarks(view.vlines, mask, options.features, clearance);
  }
  const cv::Size signature(options.signature_width_px, options.signature_height_px);
  if (!masked) {
    cv::resize(gray, view.signature, signature, 0, 0, cv::INTER_AREA);
  } else {
    // The mean of the usable pixels under each signature pixel; one without any is filled from
    // its row's neighbours.
    cv::Mat usable, weighted, weight, g;
    mask.convertTo(usable, CV_32F, 1.0 / 255);
    cv::threshold(usable, usable, 0, 1, cv::THRESH_BINARY);
    gray.convertTo(g, CV_32F);
    cv::resize(g.mul(usable), weighted, signature, 0, 0, cv::INTER_AREA);
    cv::resize(usable, weight, signature, 0, 0, cv::INTER_AREA);
    cv::Mat mean = weighted / cv::max(weight, 1e-6);
    mean.convertTo(view.signature, CV_8U);
    const cv::Mat none = weight > 1e-6;
    FillMasked(none, &view.signature);
  }
  return view;
}

double ImageDifference(const cv::Mat& a, const cv::Mat& b, int* shift_cols) {
  if (a.empty() || a.size() != b.size() || a.type() != CV_8UC1 || b.type() != CV_8UC1) {
    throw std::invalid_argument("image difference: signatures must be non-empty 8-bit grey images of one size");
  }
  const int w = a.cols, h = a.rows;
  int64_t best = std::numeric_limits<int64_t>::max();
  int best_shift = 0;
  for (int s = 0; s < w; ++s) {
    int64_t sum = 0;
    for (int r = 0; r < h && sum < best; ++r) {
      const uchar* pa = a.ptr<uchar>(r);
      const uchar* pb = b.ptr<uchar>(r);
      for (int c = 0; c < w; ++c) {
        const int d = static_cast<int>(pa[c]) - pb[(c + s) % w];
        sum += d * d;
      }
    }
    if (sum < best) {
      best = sum;
      best_shift = s;
    }
  }
  if (shift_cols) *shift_cols = best_shift > w / 2 ? best_shift - w : best_shift;
  return std::sqrt(static_cast<double>(best) / (static_cast<double>(w) * h));
}

// ---------------------------------------------------------------------------------------------
// The memory.

PlaceCellMemory::PlaceCellMemory(const PlaceViewOptions& view, const PanoramaModel& panorama,
                                 const VocabularyOptions& vocabulary)
    : view_(view), panorama_(panorama), vocabulary_(vocabulary) {
  view_.Validate();
  panorama_.Validate();
}

void PlaceCellMemory::SetPose(int index, const Pose2& pose) {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad)) {
    throw std::invalid_argument("place cells: a cell's pose must be finite");
  }
  cells_.at(static_cast<size_t>(index)).pose = pose;
}

int PlaceCellMemory::Add(const Pose2& pose, int64_t utime, PlaceView view) {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad)) {
    throw std::invalid_argument("place cells: a cell's pose must be finite");
  }
  if (view.signature.empty() || view.signature.cols != view_.signature_width_px ||
      view.signature.rows != view_.signature_height_px) {
    throw std::invalid_argument("place cells: the view's signature does not have the memory's size");
  }
  if (!view.landmarks.empty() &&
      (view.landmarks.width_px != panorama_.width_px || view.landmarks.height_px != panorama_.height_px)) {
    throw std::invalid_argument("place cells: the view's panorama size differs from the memory's");
  }
  PlaceCell cell;
  cell.id = next_id_++;
  cell.pose = pose;
  cell.utime = utime;
  cell.view = std::move(view);
  cell.view.landmarks.descriptors = CompactDescriptors(cell.view.landmarks.descriptors);
  cells_.push_back(std::move(cell));
  templates_stale_ = true;
  return size() - 1;
}

void PlaceCellMemory::SetTemplateCount(int count) {
  if (count < 1 || count > 64) throw std::invalid_argument("place cells: template count must be in [1, 64]");
  template_count_ = count;
  templates_stale_ = true;
}

void PlaceCellMemory::BuildIndex() {
  trained_at_ = 0;
  indexed_cells_ = 0;
  templates_stale_ = true;
  EnsureIndex();
  EnsureTemplates();
}

void PlaceCellMemory::EnsureIndex() const {
  if (cells_.empty()) return;
  if (!vocabulary_.trained() || size() >= 2 * std::max(trained_at_, 1)) {
    int rows = 0, cols = 0;
    for (const auto& c : cells_) {
      rows += c.view.landmarks.descriptors.rows;
      if (!c.view.landmarks.descriptors.empty()) cols = c.view.landmarks.descriptors.cols;
    }
    if (rows >= 16) {
      cv::Mat all(rows, cols, CV_32F);
      int r = 0;
      for (const auto& c : cells_) {
        const cv::Mat& d = c.view.landmarks.descriptors;
        if (d.empty()) continue;
        d.convertTo(all.rowRange(r, r + d.rows), CV_32F);
        r += d.rows;
      }
      vocabulary_.Train(all);
      trained_at_ = size();
      indexed_cells_ = 0;
    }
  }
  if (vocabulary_.trained()) {
    for (; indexed_cells_ < size(); ++indexed_cells_) {
      vocabulary_.Add(indexed_cells_, cells_[indexed_cells_].view.landmarks.descriptors);
    }
  }
}

void PlaceCellMemory::EnsureTemplates() const {
  if (templates_stale_) {
    // Templates (4.4): cluster every cell's line descriptors; one line of each cluster is a
    // template, so the templates are lines of the memory that differ from each other.
    int rows = 0, cols = 0;
    for (const auto& c : cells_) {
      rows += c.view.vlines.descriptors.rows;
      if (!c.view.vlines.descriptors.empty()) cols = c.view.vlines.descriptors.cols;
    }
    templates_.release();
    if (rows >= template_count_) {
      cv::Mat all(rows, cols, CV_32F);
      int r = 0;
      for (const auto& c : cells_) {
        const cv::Mat& d = c.view.vlines.descriptors;
        if (d.empty()) continue;
        d.copyTo(all.rowRange(r, r + d.rows));
        r += d.rows;
      }
      VocabularyOptions o;
      o.branching = std::max(2, template_count_);
      o.depth = 1;
      o.max_training = std::max(o.branching, 20000);
      VocabularyIndex clusters(o);
      clusters.Train(all);
      // One template per cluster: its first line (a real line of the memory, not a centre).
      std::vector<int> first(clusters.words(), -1);
      for (int i = 0; i < all.rows; ++i) {
        int& f = first[clusters.Word(all.ptr<float>(i))];
        if (f < 0) f = i;
      }
      templates_.create(0, cols, CV_32F);
      for (int i : first) {
        if (i >= 0) templates_.push_back(all.row(i));
      }
    }
    template_bearings_.clear();
    for (const auto& c : cells_) template_bearings_.push_back(TemplateBearings(c.view));
    templates_stale_ = false;
  }
}

std::vector<float> PlaceCellMemory::TemplateBearings(const PlaceView& view) const {
  std::vector<float> out(templates_.rows, std::numeric_limits<float>::quiet_NaN());
  if (templates_.empty() || view.vlines.empty()) return out;
  cv::Mat dist;
  cv::batchDistance(templates_, view.vlines.descriptors, dist, CV_32F, cv::noArray(), cv::NORM_L2);
  for (int t = 0; t < templates_.rows; ++t) {
    cv::Point best;
    cv::minMaxLoc(dist.row(t), nullptr, nullptr, &best, nullptr);
    out[t] = static_cast<float>(Bearing(panorama_, view.vlines.landmarks[best.x]));
  }
  return out;
}

std::vector<CellComparison> PlaceCellMemory::Compare(const PlaceView& view, const std::vector<int>& indices,
                                                     const PlaceMeasureOptions& options) const {
  options.Validate();
  std::vector<CellComparison> out;
  out.reserve(indices.size());
  const LandmarkSet query = FloatSet(view.landmarks);
  std::vector<float> query_templates;
  if (options.measure == PlaceMeasure::kVlineTemplate) {
    EnsureTemplates();
    query_templates = TemplateBearings(view);
  }
  std::mt19937_64 rng(options.ransac_seed);
  for (int index : indices) {
    const PlaceCell& cell = cells_.at(index);
    CellComparison c;
    c.cell = index;
    c.dissimilarity = options.measure == PlaceMeasure::kMatchCount ? 1.0 : kPi;
    c.distance = options.measure == PlaceMeasure::kMatchCount ? 0.0 : kPi;
    if (options.measure == PlaceMeasure::kVlineTemplate) {
      int shift = 0;
      const double difference = ImageDifference(cell.view.signature, view.signature, &shift);
      // The bearing change of every landmark from the cell's view to this one.
      const double cols = static_cast<double>(shift) * panorama_.width_px / view.signature.cols;
      const double delta = WrapAngle(panorama_.BearingOfColumn(cols) - panorama_.BearingOfColumn(0));
      c.rotation_rad = -delta;
      double sum = 0;
      int n = 0;
      const std::vector<float>& cell_templates = template_bearings_.at(index);
      for (size_t t = 0; t < query_templates.size() && t < cell_templates.size(); ++t) {
        if (std::isnan(query_templates[t]) || std::isnan(cell_templates[t])) continue;
        sum += std::abs(WrapAngle(query_templates[t] - cell_templates[t] - delta));
        ++n;
      }
      c.matches = n;
      c.seen = n > 0;
      const double templates = n > 0 ? sum / n : kPi / 2;  // no lines: a neutral template distance
      c.distance = templates + options.image_difference_weight * difference / 100.0;
      c.dissimilarity = c.distance;
      c.seen = true;  // the image difference always compares
      out.push_back(c);
      continue;
    }
    if (query.empty() || cell.view.landmarks.empty()) {
      out.push_back(c);
      continue;
    }
    const LandmarkSet home = FloatSet(cell.view.landmarks);
    std::vector<LandmarkMatch> matches = MatchLandmarks(home, query, options.match);
    if (static_cast<int>(matches.size()) < options.min_matches) {
      c.matches = static_cast<int>(matches.size());
      out.push_back(c);
      continue;
    }
    std::vector<double> diffs(matches.size());
    for (size_t i = 0; i < matches.size(); ++i) {
      diffs[i] = WrapAngle(Bearing(panorama_, query.landmarks[matches[i].current]) -
                           Bearing(panorama_, home.landmarks[matches[i].home]));
    }
    if (options.measure == PlaceMeasure::kMatchCount) {
      // 5.2.1: a match counts when the normalised windows around both keypoints agree.
      std::vector<double> kept;
      if (!view.windows.empty() && !cell.view.windows.empty() && view.windows.cols == cell.view.windows.cols) {
        for (size_t i = 0; i < matches.size(); ++i) {
          if (WindowNcc(cell.view.windows, matches[i].home, view.windows, matches[i].current) >= options.window_min_ncc) {
            kept.push_back(diffs[i]);
          }
        }
      }
      c.matches = static_cast<int>(kept.size());
      c.distance = static_cast<double>(kept.size());
      c.dissimilarity = 1.0 - static_cast<double>(kept.size()) / std::max(1, query.size());
      c.seen = c.matches >= options.min_matches;
      if (!kept.empty()) c.rotation_rad = -CircularMode(kept, 0.1);
      if (!c.seen) c.dissimilarity = 1.0;
      out.push_back(c);
      continue;
    }
    // Bearing difference (5.1.1): refine, then the mean residual after the common rotation.
    std::vector<double> used;
    double delta = 0;
    if (options.refinement == MatchRefinement::kSmallestDistance) {
      std::vector<size_t> order(matches.size());
      std::iota(order.begin(), order.end(), 0);
      std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return matches[a].distance != matches[b].distance ? matches[a].distance < matches[b].distance : a < b;
      });
      const size_t keep = std::min(matches.size(),
                                   std::max<size_t>(options.keep_min,
                                                    static_cast<size_t>(std::ceil(options.keep_fraction * matches.size()))));
      for (size_t i = 0; i < keep; ++i) used.push_back(diffs[order[i]]);
      delta = CircularMode(diffs, 0.1);  // the rotation from every match: robust to the few mismatches
    } else {
      std::uniform_int_distribution<size_t> pick(0, diffs.size() - 1);
      size_t best_inliers = 0;
      double best_delta = 0;
      for (int it = 0; it < options.ransac_iterations; ++it) {
        const double hyp = diffs[pick(rng)];
        size_t inliers = 0;
        for (double d : diffs) inliers += std::abs(WrapAngle(d - hyp)) <= options.ransac_threshold_rad;
        if (inliers > best_inliers) {
          best_inliers = inliers;
          best_delta = hyp;
        }
      }
      double s = 0, co = 0;
      for (double d : diffs) {
        if (std::abs(WrapAngle(d - best_delta)) <= options.ransac_threshold_rad) {
          s += std::sin(d);
          co += std::cos(d);
        }
      }
      delta = std::atan2(s, co);
      // Every match counts, an outlier at the cap (MSAC): the mean over the inliers alone would let
      // a far cell with a few consistent matches look near.
      used = diffs;
    }
    const double cap = options.residual_cap_rad > 0 ? options.residual_cap_rad
                       : options.refinement == MatchRefinement::kRansac ? options.ransac_threshold_rad
                                                                         : 0.0;
    double sum = 0;
    for (double d : used) {
      const double r = std::abs(WrapAngle(d - delta));
      sum += cap > 0 ? std::min(r, cap) : r;
    }
    c.matches = static_cast<int>(used.size());
    c.seen = c.matches >= std::min<int>(options.min_matches, static_cast<int>(matches.size()));
    c.distance = used.empty() ? kPi : sum / used.size();
    c.dissimilarity = c.seen ? c.distance : kPi;
    c.rotation_rad = WrapAngle(-delta);
    out.push_back(c);
  }
  return out;
}

std::vector<int> PlaceCellMemory::Candidates(const PlaceView& view, const std::optional<Pose2>& predicted,
                                             const LocalizerOptions& options) const {
  std::vector<int> out;
  if (size() <= options.exhaustive_below || options.measure.measure == PlaceMeasure::kVlineTemplate ||
      !vocabulary_.trained()) {
    out.resize(size());
    std::iota(out.begin(), out.end(), 0);
    return out;
  }
  for (const auto& [cell, score] : vocabulary_.Query(view.landmarks.descriptors, options.candidates)) {
    (void)score;
    out.push_back(cell);
  }
  if (predicted && options.filter.enabled && options.near_candidates > 0) {
    std::vector<std::pair<double, int>> near;
    near.reserve(cells_.size());
    for (int i = 0; i < size(); ++i) {
      near.emplace_back(std::hypot(cells_[i].pose.x_m - predicted->x_m, cells_[i].pose.y_m - predicted->y_m), i);
    }
    const size_t k = std::min<size_t>(options.near_candidates, near.size());
    std::partial_sort(near.begin(), near.begin() + k, near.end());
    for (size_t i = 0; i < k; ++i) {
      if (std::find(out.begin(), out.end(), near[i].second) == out.end()) out.push_back(near[i].second);
    }
  }
  return out;
}

std::optional<CellComparison> PlaceCellMemory::MostSimilar(const PlaceView& view, const LocalizerOptions& options) const {
  options.Validate();
  if (cells_.empty()) return std::nullopt;
  EnsureIndex();
  auto compared = Compare(view, Candidates(view, std::nullopt, options), options.measure);
  std::optional<CellComparison> best;
  for (const auto& c : compared) {
    if (c.seen && (!best || c.dissimilarity < best->dissimilarity)) best = c;
  }
  return best;
}

std::optional<Localization> PlaceCellMemory::Localize(const PlaceView& view, const std::optional<Pose2>& predicted,
                                                      const LocalizerOptions& options) const {
  options.Validate();
  if (cells_.empty()) return std::nullopt;
  EnsureIndex();
  Localization out;
  const auto candidates = Candidates(view, predicted, options);
  out.candidates = static_cast<int>(candidates.size());
  auto compared = Compare(view, candidates, options.measure);
  const bool filter = predicted.has_value() && options.filter.enabled;
  double worst = 0;
  for (const auto& c : compared) {
    if (c.seen) worst = std::max(worst, c.dissimilarity);
  }
  std::vector<CellComparison> usable;
  for (auto& c : compared) {
    c.image_score = (c.seen && worst > 0) ? Clamp01(c.dissimilarity / worst) : 1.0;
    if (filter) {
      const double d = std::hypot(cells_[c.cell].pose.x_m - predicted->x_m, cells_[c.cell].pose.y_m - predicted->y_m);
      c.spatial_score = (d / options.filter.radius_m) * (d / options.filter.radius_m);
      c.score = (1 - options.filter.weight) * c.image_score + options.filter.weight * c.spatial_score;
      if (options.filter.gate_m > 0 && d > options.filter.gate_m) continue;
    } else {
      c.score = c.image_score;
    }
    if (c.seen) usable.push_back(c);
  }
  std::sort(compared.begin(), compared.end(), [](const CellComparison& a, const CellComparison& b) {
    return a.score != b.score ? a.score < b.score : a.cell < b.cell;
  });
  out.compared = compared;
  if (usable.empty()) return std::nullopt;
  std::sort(usable.begin(), usable.end(), [](const CellComparison& a, const CellComparison& b) {
    return a.score != b.score ? a.score < b.score : a.cell < b.cell;
  });
  out.best = usable.front();
  out.cell = out.best.cell;
  const PlaceCell& best = cells_[out.cell];
  out.cell_id = best.id;
  out.pose.theta_rad = WrapAngle(best.pose.theta_rad + out.best.rotation_rad);
  // The filter picks the cell; the position is refined by the cells around it that look most
  // alike (the prediction does not pull the estimate, it only denies far cells).
  std::vector<CellComparison> around;
  if (options.estimate == PlaceEstimate::kInterpolated) {
    for (const auto& c : usable) {
      const auto& p = cells_[c.cell].pose;
      if (std::hypot(p.x_m - best.pose.x_m, p.y_m - best.pose.y_m) <= options.interpolate_radius_m) around.push_back(c);
    }
    std::sort(around.begin(), around.end(), [](const CellComparison& a, const CellComparison& b) {
      return a.image_score != b.image_score ? a.image_score < b.image_score : a.cell < b.cell;
    });
    if (static_cast<int>(around.size()) > options.interpolate_k) around.resize(options.interpolate_k);
  } else {
    around.push_back(out.best);
  }
  const int k = static_cast<int>(around.size());
  constexpr double kEpsilon = 0.02;
  double wsum = 0, x = 0, y = 0;
  std::vector<double> weights(k);
  for (int i = 0; i < k; ++i) {
    weights[i] = std::pow(1.0 / (around[i].image_score + kEpsilon), options.interpolate_power);
    wsum += weights[i];
    x += weights[i] * cells_[around[i].cell].pose.x_m;
    y += weights[i] * cells_[around[i].cell].pose.y_m;
  }
  out.pose.x_m = x / wsum;
  out.pose.y_m = y / wsum;
  // Covariance: the spread of the cells that make the estimate, floored by the cell spacing
  // scale min_position_sigma_m.
  Eigen::Matrix2d spread = Eigen::Matrix2d::Zero();
  for (int i = 0; i < k; ++i) {
    const Eigen::Vector2d d(cells_[around[i].cell].pose.x_m - out.pose.x_m, cells_[around[i].cell].pose.y_m - out.pose.y_m);
    spread += weights[i] / wsum * d * d.transpose();
  }
  const double floor = options.min_position_sigma_m * options.min_position_sigma_m;
  out.covariance.topLeftCorner<2, 2>() = spread + floor * Eigen::Matrix2d::Identity();
  const double heading_sigma = 0.03 + 0.5 * out.best.distance / std::max(1.0, std::sqrt(out.best.matches));
  out.covariance(2, 2) = heading_sigma * heading_sigma;
  return out;
}

int64_t PlaceCellMemory::bytes() const {
  int64_t b = static_cast<int64_t>(cells_.capacity() * sizeof(PlaceCell));
  for (const auto& c : cells_) b += c.view.bytes();
  for (const auto& t : template_bearings_) b += static_cast<int64_t>(t.size() * sizeof(float));
  return b + vocabulary_.bytes() + static_cast<int64_t>(templates_.total() * templates_.elemSize());
}

int ExploreStep(PlaceCellMemory& memory, const Pose2& pose, int64_t utime, PlaceView view, double threshold,
                const LocalizerOptions& options, double* novelty) {
  double n = options.measure.measure == PlaceMeasure::kMatchCount ? 1.0 : kPi;
  if (memory.size() > 0) {
    if (const auto best = memory.MostSimilar(view, options)) n = best->dissimilarity;
  }
  if (novelty) *novelty = n;
  if (memory.size() > 0 && n <= threshold) return -1;
  return memory.Add(pose, utime, std::move(view));
}

}  // namespace snapnav::nav
