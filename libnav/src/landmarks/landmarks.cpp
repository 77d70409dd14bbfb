#include "snapnav/nav/landmarks/landmarks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <opencv2/features2d.hpp>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

const char* LandmarkMethodName(LandmarkMethod method) {
  switch (method) {
    case LandmarkMethod::kHog: return "hog";
    case LandmarkMethod::kVline: return "vline";
    case LandmarkMethod::kSift: return "sift";
    case LandmarkMethod::kSurf: return "surf";
  }
  return "?";
}

std::optional<LandmarkMethod> ParseLandmarkMethod(const std::string& name) {
  for (auto m : {LandmarkMethod::kHog, LandmarkMethod::kVline, LandmarkMethod::kSift, LandmarkMethod::kSurf}) {
    if (name == LandmarkMethodName(m)) return m;
  }
  return std::nullopt;
}

// ------------------------------------------------------------------------------------ SIFT
void SiftOptions::Validate() const {
  if (max_features < 0) throw std::invalid_argument("sift: max_features must be >= 0");
  if (octave_layers < 1) throw std::invalid_argument("sift: octave_layers must be >= 1");
  if (!(contrast_threshold > 0)) throw std::invalid_argument("sift: contrast_threshold must be > 0");
  if (!(edge_threshold > 0)) throw std::invalid_argument("sift: edge_threshold must be > 0");
  if (!(sigma > 0)) throw std::invalid_argument("sift: sigma must be > 0");
}

LandmarkSet DetectSift(const cv::Mat& gray, const SiftOptions& options) {
  options.Validate();
  if (gray.empty() || gray.type() != CV_8UC1) throw std::invalid_argument("sift: need a non-empty 8-bit grey image");
  // One detector per thread: creating it is cheap next to the detection.
  auto sift = cv::SIFT::create(options.max_features, options.octave_layers, options.contrast_threshold,
                               options.edge_threshold, options.sigma);
  // Pad by the neighbourhood a keypoint of a few octaves needs (descriptor window ~ 6 sigma).
  const int pad = std::min(48, gray.cols);
  return DetectWrapped(gray, pad, [&](const cv::Mat& image) {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    sift->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
    LandmarkSet set;
    set.method = LandmarkMethod::kSift;
    set.width_px = image.cols;
    set.height_px = image.rows;
    set.landmarks.reserve(keypoints.size());
    for (const auto& k : keypoints) {
      set.landmarks.push_back(Landmark{k.pt.x, k.pt.y, k.response, k.size, k.angle});
    }
    if (!keypoints.empty()) descriptors.convertTo(set.descriptors, CV_32F);
    return set;
  });
}

LandmarkSet CropWrapped(const LandmarkSet& padded, int pad_px, int width_px, int height_px) {
  LandmarkSet out;
  out.method = padded.method;
  out.width_px = width_px;
  out.height_px = height_px;
  std::vector<int> keep;
  for (int i = 0; i < padded.size(); ++i) {
    const float x = padded.landmarks[i].x_px - pad_px;
    if (x >= 0 && x < width_px) keep.push_back(i);
  }
  out.landmarks.reserve(keep.size());
  if (!keep.empty() && !padded.descriptors.empty()) out.descriptors.create(static_cast<int>(keep.size()), padded.descriptors.cols, CV_32F);
  for (size_t j = 0; j < keep.size(); ++j) {
    Landmark l = padded.landmarks[keep[j]];
    l.x_px -= pad_px;
    out.landmarks.push_back(l);
    if (!out.descriptors.empty()) padded.descriptors.row(keep[j]).copyTo(out.descriptors.row(static_cast<int>(j)));
  }
  return out;
}

// ------------------------------------------------------------------------------------ matching
void MatchOptions::Validate() const {
  if (!(ratio > 0)) throw std::invalid_argument("matching: ratio must be > 0 (>= 1 turns the ratio test off)");
  if (!std::isfinite(max_distance)) throw std::invalid_argument("matching: max_distance must be finite");
  if (!std::isfinite(max_x_displacement_px)) throw std::invalid_argument("matching: max_x_displacement_px must be finite");
}

namespace {

double WrappedColumnDifference(double a, double b, int width) {
  double d = std::fmod(a - b, static_cast<double>(width));
  if (d > width / 2.0) d -= width;
  if (d < -width / 2.0) d += width;
  return d;
}

}  // namespace

std::vector<LandmarkMatch> MatchLandmarks(const LandmarkSet& home, const LandmarkSet& current,
                                          const MatchOptions& options, double shift_px) {
  options.Validate();
  std::vector<LandmarkMatch> matches;
  if (home.empty() || current.empty()) return matches;
  if (home.descriptors.cols != current.descriptors.cols || home.descriptors.rows != home.size() ||
      current.descriptors.rows != current.size() || home.descriptors.type() != CV_32F ||
      current.descriptors.type() != CV_32F) {
    throw std::invalid_argument("matching: landmark sets need CV_32F descriptors of one length, one row per landmark (" +
                                std::to_string(home.descriptors.cols) + " vs " +
                                std::to_string(current.descriptors.cols) + " values)");
  }
  // All pairwise distances at once: rows current, columns home.
  cv::Mat dist;
  cv::batchDistance(current.descriptors, home.descriptors, dist, CV_32F, cv::noArray(), cv::NORM_L2);
  const int nc = dist.rows, nh = dist.cols;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Best and second-best current landmark for every home landmark (the reverse check).
  std::vector<int> home_best(nh, -1), home_second(nh, -1);
  std::vector<float> home_best_d(nh, kInf), home_second_d(nh, kInf);
  for (int c = 0; c < nc; ++c) {
    const float* row = dist.ptr<float>(c);
    for (int h = 0; h < nh; ++h) {
      const float d = row[h];
      if (d < home_best_d[h]) {
        home_second_d[h] = home_best_d[h];
        home_second[h] = home_best[h];
        home_best_d[h] = d;
        home_best[h] = c;
      } else if (d < home_second_d[h]) {
        home_second_d[h] = d;
        home_second[h] = c;
      }
    }
  }
  const int width = current.width_px > 0 ? current.width_px : home.width_px;
  for (int c = 0; c < nc; ++c) {
    const float* row = dist.ptr<float>(c);
    int best = -1;
    float d1 = kInf, d2 = kInf;
    for (int h = 0; h < nh; ++h) {
      if (row[h] < d1) {
        d2 = d1;
        d1 = row[h];
        best = h;
      } else if (row[h] < d2) {
        d2 = row[h];
      }
    }
    if (best < 0) continue;  // no finite distance to any home landmark (e.g. descriptors of 1e38)
    const float ratio = std::isfinite(d2) && d2 > 0 ? d1 / d2 : 1.0f;
    if (options.ratio < 1 && std::isfinite(d2) && !(d1 < options.ratio * d2)) continue;
    if (options.max_distance > 0 && d1 > options.max_distance) continue;
    if (options.mutual) {
      const bool is_best = home_best[best] == c;
      const bool is_second = options.relaxed_second_best && home_second[best] == c;
      if (!is_best && !is_second) continue;
    }
    if (options.max_x_displacement_px > 0 && width > 0) {
      const double dx = WrappedColumnDifference(current.landmarks[c].x_px - shift_px, home.landmarks[best].x_px, width);
      if (std::abs(dx) > options.max_x_displacement_px) continue;
    }
    matches.push_back(LandmarkMatch{best, c, d1, ratio});
  }
  return matches;
}

std::optional<double> RotationFromMatches(const LandmarkSet& home, const LandmarkSet& current,
                                          const std::vector<LandmarkMatch>& matches, const PanoramaModel& panorama,
                                          double window_rad) {
  if (matches.empty()) return std::nullopt;
  // rotation r (current heading relative to home): a landmark's bearing drops by r, so each
  // match votes for r = bearing_home - bearing_current.
  std::vector<double> votes;
  votes.reserve(matches.size());
  for (const auto& m : matches) {
    votes.push_back(WrapAngle(panorama.BearingOfColumn(home.landmarks[m.home].x_px) -
                              panorama.BearingOfColumn(current.landmarks[m.current].x_px)));
  }
  constexpr int kBins = 360;
  std::vector<double> hist(kBins, 0.0);
  for (double v : votes) {
    const int b = static_cast<int>(std::floor((v + M_PI) / (2 * M_PI) * kBins)) % kBins;
    hist[(b + kBins) % kBins] += 1;
  }
  const int half = std::max(1, static_cast<int>(std::lround(window_rad / (2 * M_PI) * kBins)));
  int best_bin = 0;
  double best = -1;
  for (int b = 0; b < kBins; ++b) {
    double s = 0;
    for (int k = -half; k <= half; ++k) s += hist[((b + k) % kBins + kBins) % kBins];
    if (s > best) {
      best = s;
      best_bin = b;
    }
  }
  const double mode = -M_PI + (best_bin + 0.5) * 2 * M_PI / kBins;
  double sum = 0;
  int n = 0;
  for (double v : votes) {
    const double d = WrapAngle(v - mode);
    if (std::abs(d) <= window_rad) {
      sum += d;
      ++n;
    }
  }
  return WrapAngle(mode + (n > 0 ? sum / n : 0.0));
}

// ------------------------------------------------------------------------------------ ALV
std::optional<AlvVariant> ParseAlvVariant(const std::string& name) {
  for (auto v : {AlvVariant::kUnit, AlvVariant::kWeighted, AlvVariant::kScale}) {
    if (name == AlvVariantName(v)) return v;
  }
  return std::nullopt;
}

const char* AlvVariantName(AlvVariant variant) {
  switch (variant) {
    case AlvVariant::kUnit: return "unit";
    case AlvVariant::kWeighted: return "weighted";
    case AlvVariant::kScale: return "scale";
  }
  return "?";
}

const char* MatchWeightName(MatchWeight weight) {
  return weight == MatchWeight::kDistance ? "distance" : "score";
}

void LandmarkAlvOptions::Validate() const {
  if (top_n < 0) throw std::invalid_argument("landmark alv: top_n must be >= 0 (0: all matches)");
  if (!(max_scale_ratio >= 1)) throw std::invalid_argument("landmark alv: max_scale_ratio must be >= 1");
  if (min_landmarks < 1) throw std::invalid_argument("landmark alv: min_landmarks must be >= 1");
  if (!(consensus_window_rad > 0 && consensus_window_rad <= M_PI)) {
    throw std::invalid_argument("landmark alv: consensus_window_rad must lie in (0, 180] degrees");
  }
  if (!(rotation_refine_rad >= 0 && rotation_refine_rad < M_PI)) {
    throw std::invalid_argument("landmark alv: rotation_refine_rad must lie in [0, 180) degrees");
  }
}

namespace {

// Per-landmark home directions of the scale-compensated ALV at `rotation`, and their consensus:
// the mean direction of those within `window` of the best-supported one.
struct Consensus {
  Eigen::Vector2d direction = Eigen::Vector2d::Zero();  // unit (zero: none)
  int inliers = 0;
  double coherence = 0;  // sum over inliers of cos(angle to the consensus)
  std::vector<int> members;  // indices of the inliers
};

// Direction each landmark alone gives (NaN where its vector vanishes).
std::vector<double> LandmarkDirections(const std::vector<double>& bh, const std::vector<double>& bc,
                                       const std::vector<double>& k, double rotation, bool home_minus_current) {
  std::vector<double> dir(bh.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < bh.size(); ++i) {
    Eigen::Vector2d v = k[i] * Eigen::Vector2d(std::cos(bc[i] + rotation), std::sin(bc[i] + rotation)) -
                        Eigen::Vector2d(std::cos(bh[i]), std::sin(bh[i]));
    if (home_minus_current) v = -v;
    if (v.norm() < 1e-9) continue;
    dir[i] = std::atan2(v.y(), v.x());
  }
  return dir;
}

Consensus ScaleConsensus(const std::vector<double>& bh, const std::vector<double>& bc, const std::vector<double>& k,
                         double rotation, double window, bool home_minus_current) {
  const size_t n = bh.size();
  const std::vector<double> dir = LandmarkDirections(bh, bc, k, rotation, home_minus_current);
  Consensus best;
  size_t best_c = n;
  // The mode: the landmark direction with the most others within the window (ties: the tighter).
  for (size_t c = 0; c < n; ++c) {
    if (std::isnan(dir[c])) continue;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int count = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!std::isnan(dir[i]) && std::abs(WrapAngle(dir[i] - dir[c])) <= window) {
        sum += Eigen::Vector2d(std::cos(dir[i]), std::sin(dir[i]));
        ++count;
      }
    }
    if (count > best.inliers || (count == best.inliers && sum.norm() > best.coherence)) {
      best.inliers = count;
      best.coherence = sum.norm();
      best.direction = sum.normalized();
      best_c = c;
    }
  }
  if (best_c < n) {
    for (size_t i = 0; i < n; ++i) {
      if (!std::isnan(dir[i]) && std::abs(WrapAngle(dir[i] - dir[best_c])) <= window) best.members.push_back(static_cast<int>(i));
    }
  }
  return best;
}

}  // namespace

std::optional<HomingEstimate> LandmarkAlvHoming(const LandmarkSet& home, const LandmarkSet& current,
                                                const std::vector<LandmarkMatch>& all_matches, double rotation_rad,
                                                const PanoramaModel& panorama, const LandmarkAlvOptions& options,
                                                bool refine_rotation, std::vector<int>* used) {
  options.Validate();
  if (used) used->clear();
  for (const auto& m : all_matches) {
    if (m.home < 0 || m.home >= home.size() || m.current < 0 || m.current >= current.size()) {
      throw std::invalid_argument("landmark alv: a match refers to a landmark outside its set");
    }
  }
  // The matches that count: all, or the top_n of smallest descriptor distance (indices into all_matches).
  std::vector<int> index(all_matches.size());
  std::iota(index.begin(), index.end(), 0);
  if (options.top_n > 0 && static_cast<int>(index.size()) > options.top_n) {
    std::partial_sort(index.begin(), index.begin() + options.top_n, index.end(),
                      [&](int a, int b) { return all_matches[a].distance < all_matches[b].distance; });
    index.resize(options.top_n);
  }
  std::vector<LandmarkMatch> matches;
  matches.reserve(index.size());
  for (int i : index) matches.push_back(all_matches[i]);
  if (static_cast<int>(matches.size()) < options.min_landmarks) return std::nullopt;

  std::vector<double> weights(matches.size(), 1.0);
  if (options.variant == AlvVariant::kWeighted) {
    double mean_d = 0;
    for (const auto& m : matches) mean_d += m.distance;
    mean_d /= static_cast<double>(matches.size());
    for (size_t i = 0; i < matches.size(); ++i) {
      weights[i] = options.weight == MatchWeight::kDistance
                       ? (mean_d > 0 ? std::exp(-matches[i].distance / mean_d) : 1.0)
                       : std::max(0.0, 1.0 - static_cast<double>(matches[i].ratio));
    }
  }
  if (options.variant == AlvVariant::kScale && options.consensus) {
    std::vector<double> bh, bc, k;
    for (const auto& m : matches) {
      const Landmark& h = home.landmarks[m.home];
      const Landmark& c = current.landmarks[m.current];
      bh.push_back(panorama.BearingOfColumn(h.x_px));
      bc.push_back(panorama.BearingOfColumn(c.x_px));
      k.push_back(h.scale_px > 0 && c.scale_px > 0
                      ? std::clamp(static_cast<double>(h.scale_px) / c.scale_px, 1.0 / options.max_scale_ratio,
                                   options.max_scale_ratio)
                      : 1.0);
    }
    const bool hmc = options.difference == AlvDifference::kHomeMinusCurrent;
    double rotation = rotation_rad;
    Consensus best = ScaleConsensus(bh, bc, k, rotation, options.consensus_window_rad, hmc);
    if (refine_rotation && options.rotation_refine_rad > 0) {
      constexpr double kStep = 0.5 * M_PI / 180;
      const int steps = static_cast<int>(std::ceil(options.rotation_refine_rad / kStep));
      for (int s = -steps; s <= steps; ++s) {
        if (s == 0) continue;
        const double r = rotation_rad + s * kStep;
        Consensus c = ScaleConsensus(bh, bc, k, r, options.consensus_window_rad, hmc);
        if (c.inliers > best.inliers || (c.inliers == best.inliers && c.coherence > best.coherence)) {
          best = std::move(c);
          rotation = r;
        }
      }
    }
    if (best.inliers < options.min_landmarks || best.direction.norm() == 0) return std::nullopt;
    HomingEstimate e;
    e.compass_rotation_rad = WrapAngle(rotation);
    e.direction_rad = WrapAngle(std::atan2(best.direction.y(), best.direction.x()) - rotation);
    e.magnitude = best.coherence / static_cast<double>(matches.size());
    e.bins_used = best.inliers;
    if (used) {
      for (int m : best.members) used->push_back(index[m]);
    }
    return e;
  }
  Eigen::Vector2d home_alv = Eigen::Vector2d::Zero(), cur_alv = Eigen::Vector2d::Zero();
  double wsum = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    const Landmark& h = home.landmarks[matches[i].home];
    const Landmark& c = current.landmarks[matches[i].current];
    const double bh = panorama.BearingOfColumn(h.x_px);
    // The current landmark's bearing in the home-aligned frame.
    const double bc = panorama.BearingOfColumn(c.x_px) + rotation_rad;
    double length = 1.0;
    if (options.variant == AlvVariant::kScale && h.scale_px > 0 && c.scale_px > 0) {
      length = std::clamp(static_cast<double>(h.scale_px) / c.scale_px, 1.0 / options.max_scale_ratio,
                          options.max_scale_ratio);
    }
    home_alv += weights[i] * Eigen::Vector2d(std::cos(bh), std::sin(bh));
    cur_alv += weights[i] * length * Eigen::Vector2d(std::cos(bc), std::sin(bc));
    wsum += weights[i];
  }
  if (!(wsum > 0)) return std::nullopt;
  const Eigen::Vector2d diff = (options.difference == AlvDifference::kCurrentMinusHome ? cur_alv - home_alv
                                                                                        : home_alv - cur_alv) /
                               wsum;
  if (!(diff.norm() > 1e-12)) return std::nullopt;
  HomingEstimate e;
  e.compass_rotation_rad = WrapAngle(rotation_rad);
  e.direction_rad = WrapAngle(std::atan2(diff.y(), diff.x()) - rotation_rad);
  e.magnitude = diff.norm();
  e.bins_used = static_cast<int>(matches.size());
  if (used) {
    for (size_t i = 0; i < matches.size(); ++i) {
      if (weights[i] > 0) used->push_back(index[i]);
    }
  }
  return e;
}

// ------------------------------------------------------------------------------------ homer
void LandmarkHomingConfig::Validate() const {
  match.Validate();
  alv.Validate();
  if (!(rotation_window_rad > 0 && rotation_window_rad < M_PI)) {
    throw std::invalid_argument("landmark homing: rotation_window_rad must lie in (0, 180) degrees");
  }
}

LandmarkHomer::LandmarkHomer(const LandmarkHomingConfig& config, const PanoramaModel& panorama)
    : config_(config), panorama_(panorama) {
  config_.Validate();
  panorama_.Validate();
}

void LandmarkHomer::CheckSize(const LandmarkSet& set) const {
  if (set.width_px != panorama_.width_px || set.height_px != panorama_.height_px) {
    throw std::invalid_argument("landmark homing: landmarks come from a " + std::to_string(set.width_px) + "x" +
                                std::to_string(set.height_px) + " panorama, the model is " +
                                std::to_string(panorama_.width_px) + "x" + std::to_string(panorama_.height_px));
  }
}

void LandmarkHomer::SetHome(LandmarkSet home) {
  CheckSize(home);
  home_ = std::move(home);
}

const LandmarkSet& LandmarkHomer::home() const {
  if (!home_) throw std::logic_error("landmark homing: no home snapshot set");
  return *home_;
}

std::optional<LandmarkHoming> LandmarkHomer::Home(const LandmarkSet& current,
                                                  std::optional<double> known_rotation_rad) const {
  if (!home_) throw std::logic_error("landmark homing: no home snapshot set");
  CheckSize(current);
  if (home_->empty() || current.empty()) return std::nullopt;
  if (home_->method != current.method) {
    throw std::invalid_argument(std::string("landmark homing: home landmarks are ") + LandmarkMethodName(home_->method) +
                                ", current ones " + LandmarkMethodName(current.method));
  }
  std::optional<double> rotation = known_rotation_rad;
  if (!rotation && config_.rotation == RotationSource::kNone) rotation = 0.0;
  std::vector<LandmarkMatch> matches;
  if (rotation) {
    const double shift_px = *rotation * panorama_.width_px / (2 * M_PI);  // current column = home column + shift
    matches = MatchLandmarks(*home_, current, config_.match, shift_px);
  } else {
    // The displacement limit needs the rotation: match without it, estimate the rotation,
    // then apply the limit around it.
    MatchOptions loose = config_.match;
    loose.max_x_displacement_px = 0;
    matches = MatchLandmarks(*home_, current, loose);
    rotation = RotationFromMatches(*home_, current, matches, panorama_, config_.rotation_window_rad);
    if (!rotation) return std::nullopt;
    if (config_.match.max_x_displacement_px > 0) {
      const double shift_px = *rotation * panorama_.width_px / (2 * M_PI);  // current column = home column + shift
      std::vector<LandmarkMatch> kept;
      for (const auto& m : matches) {
        const double dx = WrappedColumnDifference(current.landmarks[m.current].x_px - shift_px,
                                                  home_->landmarks[m.home].x_px, panorama_.width_px);
        if (std::abs(dx) <= config_.match.max_x_displacement_px) kept.push_back(m);
      }
      matches.swap(kept);
    }
  }
  const bool refine = !known_rotation_rad && config_.rotation == RotationSource::kMatches;
  std::vector<int> used;
  auto estimate = LandmarkAlvHoming(*home_, current, matches, *rotation, panorama_, config_.alv, refine, &used);
  if (!estimate) return std::nullopt;
  const int count = static_cast<int>(matches.size());
  return LandmarkHoming{*estimate, count, std::move(matches), std::move(used)};
}

}  // namespace snapnav::nav
