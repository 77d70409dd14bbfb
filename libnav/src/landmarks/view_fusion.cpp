#include "snapnav/nav/landmarks/view_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace snapnav::nav {

std::optional<ViewFusion> ParseViewFusion(const std::string& name) {
  if (name == "persistent") return ViewFusion::kPersistent;
  if (name == "median") return ViewFusion::kMedian;
  return std::nullopt;
}

const char* ViewFusionName(ViewFusion fusion) { return fusion == ViewFusion::kMedian ? "median" : "persistent"; }

void PersistenceOptions::Validate() const {
  if (!(min_fraction > 0 && min_fraction <= 1)) throw std::invalid_argument("persistence: min_fraction must lie in (0, 1]");
  if (!(max_shift_px >= 0) || !(max_row_shift_px >= 0)) {
    throw std::invalid_argument("persistence: max_shift_px and max_row_shift_px must be >= 0");
  }
  if (!(max_descriptor_distance_frac > 0)) throw std::invalid_argument("persistence: max_descriptor_distance_frac must be > 0");
}

LandmarkSet PersistentLandmarks(const std::vector<LandmarkSet>& frames, const PersistenceOptions& options,
                                std::vector<int>* seen) {
  options.Validate();
  if (frames.empty()) throw std::invalid_argument("persistence: no frames");
  const LandmarkSet& first = frames.front();
  for (const auto& f : frames) {
    if (f.method != first.method || f.width_px != first.width_px || f.height_px != first.height_px) {
      throw std::invalid_argument("persistence: the frames must come from one extractor and one panorama size");
    }
    if (!f.empty() && (f.descriptors.rows != f.size() || f.descriptors.type() != CV_32F ||
                       (!first.empty() && f.descriptors.cols != first.descriptors.cols))) {
      throw std::invalid_argument("persistence: landmark sets need CV_32F descriptors of one length, one row per landmark");
    }
  }
  if (frames.size() == 1) {
    if (seen) seen->assign(first.size(), 1);
    return first;
  }
  const bool rows = first.method != LandmarkMethod::kVline;
  const double width = first.width_px;
  struct Track {
    int frame, index;  // first observation
    int seen = 1;
  };
  std::vector<Track> tracks;
  std::vector<float> track_norm;
  for (size_t k = 0; k < frames.size(); ++k) {
    const LandmarkSet& f = frames[k];
    std::vector<float> norm(f.size());
    for (int j = 0; j < f.size(); ++j) norm[j] = static_cast<float>(cv::norm(f.descriptors.row(j)));
    // Candidate pairs within the gate, nearest descriptors first, assigned one to one.
    std::vector<std::tuple<float, int, int>> pairs;  // distance, landmark, track
    for (int j = 0; j < f.size(); ++j) {
      const Landmark& l = f.landmarks[j];
      for (size_t t = 0; t < tracks.size(); ++t) {
        const Landmark& o = frames[tracks[t].frame].landmarks[tracks[t].index];
        double dx = std::fmod(std::abs(l.x_px - o.x_px), width);
        dx = std::min(dx, width - dx);
        if (dx > options.max_shift_px) continue;
        if (rows && std::abs(l.y_px - o.y_px) > options.max_row_shift_px) continue;
        const float d = static_cast<float>(
            cv::norm(f.descriptors.row(j), frames[tracks[t].frame].descriptors.row(tracks[t].index), cv::NORM_L2));
        if (d > options.max_descriptor_distance_frac * 0.5 * (norm[j] + track_norm[t])) continue;
        pairs.emplace_back(d, j, static_cast<int>(t));
      }
    }
    std::sort(pairs.begin(), pairs.end());
    std::vector<char> landmark_done(f.size(), 0), track_done(tracks.size(), 0);
    for (const auto& [d, j, t] : pairs) {
      if (landmark_done[j] || track_done[t]) continue;
      landmark_done[j] = track_done[t] = 1;
      ++tracks[t].seen;
    }
    for (int j = 0; j < f.size(); ++j) {
      if (landmark_done[j]) continue;
      tracks.push_back(Track{static_cast<int>(k), j});
      track_norm.push_back(norm[j]);
    }
  }
  // Found again at least once: in two frames, and in min_fraction of them.
  const int needed = std::max(2, static_cast<int>(std::ceil(options.min_fraction * frames.size() - 1e-9)));
  LandmarkSet out;
  out.method = first.method;
  out.width_px = first.width_px;
  out.height_px = first.height_px;
  if (seen) seen->clear();
  std::vector<cv::Mat> rows_out;
  for (const auto& t : tracks) {
    if (t.seen < needed) continue;
    out.landmarks.push_back(frames[t.frame].landmarks[t.index]);
    rows_out.push_back(frames[t.frame].descriptors.row(t.index));
    if (seen) seen->push_back(t.seen);
  }
  if (!rows_out.empty()) cv::vconcat(rows_out, out.descriptors);
  return out;
}

cv::Mat MedianImage(const std::vector<cv::Mat>& frames) {
  if (frames.empty()) throw std::invalid_argument("median image: no frames");
  const cv::Mat& first = frames.front();
  if (first.empty() || first.depth() != CV_8U) throw std::invalid_argument("median image: need non-empty 8-bit images");
  for (const auto& f : frames) {
    if (f.size() != first.size() || f.type() != first.type()) {
      throw std::invalid_argument("median image: the frames must have one size and type");
    }
  }
  if (frames.size() == 1) return first.clone();
  cv::Mat out(first.size(), first.type());
  const int n = static_cast<int>(frames.size());
  const int values = first.cols * first.channels();
  std::vector<uchar> v(n);
  std::vector<const uchar*> in(n);
  for (int r = 0; r < first.rows; ++r) {
    for (int k = 0; k < n; ++k) in[k] = frames[k].ptr<uchar>(r);
    uchar* o = out.ptr<uchar>(r);
    for (int c = 0; c < values; ++c) {
      for (int k = 0; k < n; ++k) v[k] = in[k][c];
      std::nth_element(v.begin(), v.begin() + (n - 1) / 2, v.end());
      o[c] = v[(n - 1) / 2];
    }
  }
  return out;
}

}  // namespace snapnav::nav
