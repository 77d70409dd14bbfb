#pragma once
// Place cells (thesis 4.4, 5.1, 5.2): a memory of snapshots of places, each with the position
// where it was taken, and localization by comparing the current view with that memory.
//
// A view is what the robot keeps of one panorama: its feature landmarks (SIFT by default:
// bearings and descriptors), a normalised window around each landmark (5.2.1), its vertical
// lines with their R-HOG descriptors (4.4) and a compact signature (a small grey panorama) for
// the rotational image difference (Franz et al. 1998).
//
// Distance measures between the current view and a cell:
//   kBearingDifference  Distance = 1/N sum |theta_i - theta_t| over matched landmarks, after the
//                       heading difference is removed (5.1.1); the matches are refined by
//                       keeping those of smallest descriptor distance (the thesis) or by RANSAC
//                       on the rotation.
//   kMatchCount         the number of matches whose normalised windows agree (5.2.1-5.2.2);
//                       more is closer.
//   kVlineTemplate      for a few template lines, the bearing of the most similar line in each
//                       view (4.4), compared after aligning the views, plus the image difference.
// The distance filter (5.1.1) combines the normalised image distance with the normalised
// distance of each cell from the odometry-predicted position, so a far cell that looks alike
// is not chosen. Candidates come from a vocabulary-tree index over every cell's descriptors
// (votes, tf-idf), so a query does not match against every cell.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/landmarks/landmark_set.hpp"
#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/landmarks/vline.hpp"

namespace snapnav::nav {

// Same numbering as snapnav::place_cell_match_t's distance_measure constants.
enum class PlaceMeasure { kBearingDifference = 0, kMatchCount = 1, kVlineTemplate = 2 };
const char* PlaceMeasureName(PlaceMeasure measure);  // "bearing", "count", "vline"
std::optional<PlaceMeasure> ParsePlaceMeasure(const std::string& name);

// How the bearing measure refines its matches (5.1.1).
enum class MatchRefinement {
  kSmallestDistance,  // keep the fraction keep_fraction (at least keep_min) of smallest descriptor distance
  kRansac,            // the rotation with the largest consensus (from its inliers); every match counts,
                      // an outlier at the residual cap (or the RANSAC threshold without one): MSAC
};
const char* MatchRefinementName(MatchRefinement refinement);  // "smallest", "ransac"

// Where the position estimate comes from.
enum class PlaceEstimate {
  kNearestCell,   // the best cell's position (the thesis)
  kInterpolated,  // the mean of the interpolate_k most alike cells within interpolate_radius_m of the
                  // chosen one, weighted by their image similarity
};
const char* PlaceEstimateName(PlaceEstimate estimate);  // "nearest", "interpolated"

// What a view keeps of a panorama.
struct PlaceViewOptions {
  LandmarkExtractorConfig features;  // method kSift or kSurf (the landmarks of the bearing and count measures)
  VlineOptions vline;                // for kVlineTemplate; vline.window_px 80 by default (4.4: larger is better)
  bool keep_vlines = true;           // extract vertical lines too (needed by kVlineTemplate)
  int window_px = 12;                // normalised window side (5.2.1), resampled
  double window_scale = 1.0;         // window spans window_scale x the keypoint size (at least 8 px)
  int signature_width_px = 90;       // compact signature (grey, mean-pooled)
  int signature_height_px = 15;
  void Validate() const;             // throws std::invalid_argument naming the bad option
};

struct PlaceView {
  LandmarkSet landmarks;   // descriptors CV_32F; a memory keeps SIFT's (integers in [0, 255]) as CV_8U
  cv::Mat windows;         // CV_8S, one row of window_px^2 per landmark: (v - mean) / std * 32, clamped
  LandmarkSet vlines;      // vertical lines (method kVline), may be empty
  cv::Mat signature;       // CV_8U signature_height_px x signature_width_px
  int64_t bytes() const;   // memory taken by the view's data
};

// The view of a panorama (8-bit grey or BGR, the model's size). Throws std::invalid_argument on an
// empty image. `mask` (image_mask.hpp; empty: none): masked pixels are filled before anything is
// extracted, no landmark or line lies on them (ExtractLandmarks), and the signature averages the
// usable pixels only. `clearance`, when given, is MaskClearance(mask): computed once by a caller
// whose mask does not change (here once per view otherwise).
PlaceView MakePlaceView(const cv::Mat& panorama, const PlaceViewOptions& options, const cv::Mat& mask = cv::Mat(),
                        const cv::Mat& clearance = cv::Mat());

// Rotational image difference (Franz et al. 1998) of two signatures: the smallest RMS grey-level
// difference over the column shifts of `b`; `shift_cols` gets the best shift of b relative to a
// (a's column c matches b's column c + shift). Signatures of different size throw.
double ImageDifference(const cv::Mat& a, const cv::Mat& b, int* shift_cols = nullptr);

struct PlaceCell {
  int id = -1;
  Pose2 pose;              // where the snapshot was taken (the exploration's pose source)
  int64_t utime = 0;       // when
  PlaceView view;
};

struct PlaceMeasureOptions {
  PlaceMeasure measure = PlaceMeasure::kBearingDifference;
  MatchOptions match;                   // descriptor matching (ratio test, mutual check)
  MatchRefinement refinement = MatchRefinement::kSmallestDistance;
  double keep_fraction = 0.5;           // smallest-distance refinement: share of matches kept
  int keep_min = 8;                     // ... but at least this many (or all there are)
  double ransac_threshold_rad = 0.05;   // RANSAC: inlier bearing residual
  int ransac_iterations = 64;
  // snapnav's robustness to occlusion: a residual counts at most this much in the mean (a
  // mismatch on a passer-by cannot outweigh the landmarks that agree); 0: the thesis' plain mean.
  double residual_cap_rad = 0.2;
  uint64_t ransac_seed = 1;
  double window_min_ncc = 0.6;          // count measure: windows agree above this correlation
  int min_matches = 4;                  // fewer: the view is "not seen" from the cell
  int templates = 6;                    // vline measure: template count (4.4: 6)
  double image_difference_weight = 1.0; // vline measure: rad per (RMS grey level / 100)
  void Validate() const;
};

// The result of comparing the current view with one cell.
struct CellComparison {
  int cell = -1;             // index in the memory
  bool seen = false;         // enough matches (bearing / count) or lines (vline) to compare
  double distance = 0;       // measure's value: rad (bearing, vline) or count (count)
  double dissimilarity = 0;  // lower is closer, comparable across cells: rad (bearing, vline);
                             // 1 - count / query landmarks (count); pi (or 1) when not seen
  double rotation_rad = 0;   // heading of the current view relative to the cell's (ccw)
  int matches = 0;           // matches used
  double image_score = 0;    // normalised dissimilarity over the candidates, [0, 1]
  double spatial_score = 0;  // (distance from the prediction / filter radius)^2 (0 without filter)
  double score = 0;          // combined, lower is better
};

struct DistanceFilterOptions {
  bool enabled = true;
  double radius_m = 2.0;     // spatial score = (distance from the prediction / radius_m)^2, not capped
  double weight = 0.3;       // score = (1 - w) image + w spatial
  double gate_m = 0;         // > 0: cells further than this from the prediction are not chosen
  void Validate() const;
};

struct LocalizerOptions {
  PlaceMeasureOptions measure;
  DistanceFilterOptions filter;
  PlaceEstimate estimate = PlaceEstimate::kInterpolated;
  int interpolate_k = 3;
  double interpolate_power = 2.0;   // weight of a cell = (1 / (image score + 0.02))^power
  double interpolate_radius_m = 0.5;
  // Candidate selection: the best `candidates` cells by vocabulary votes, plus the `near_candidates`
  // cells nearest the prediction. Memories of at most `exhaustive_below` cells are compared whole.
  int candidates = 8;
  int near_candidates = 8;
  int exhaustive_below = 16;
  double min_position_sigma_m = 0.06;  // floor of the reported position std. dev.
  void Validate() const;
};

struct Localization {
  int cell = -1;               // index of the best cell
  int cell_id = -1;
  Pose2 pose;                  // estimate (position per `estimate`, heading = cell + rotation)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  CellComparison best;
  std::vector<CellComparison> compared;  // every candidate, best first
  int candidates = 0;
};

// Hierarchical k-means vocabulary over descriptors with an inverted file: each cell's
// descriptors vote for their words; a query's words score the cells by tf-idf.
struct VocabularyOptions {
  int branching = 8;
  int depth = 4;               // up to branching^depth words
  int max_training = 40000;    // descriptors sampled for training
  int kmeans_iterations = 8;
  uint64_t seed = 1;
  void Validate() const;
};
class VocabularyIndex {
 public:
  explicit VocabularyIndex(const VocabularyOptions& options = {});
  // Trains the tree on the descriptors (CV_32F rows); resets the inverted file.
  void Train(const cv::Mat& descriptors);
  bool trained() const { return !nodes_.empty(); }
  void Add(int cell, const cv::Mat& descriptors);
  // The `k` best cells by tf-idf score (cell, score), best first.
  std::vector<std::pair<int, double>> Query(const cv::Mat& descriptors, int k) const;
  int words() const { return words_; }
  int64_t bytes() const;
  int Word(const float* descriptor) const;

 private:
  struct Node {
    int first_child = -1;  // index of the first of `branching` children; -1: leaf
    int children = 0;
    int word = -1;
  };
  VocabularyOptions options_;
  std::vector<Node> nodes_;
  cv::Mat centres_;  // one row per node (the root's is unused)
  int words_ = 0;
  std::vector<std::vector<std::pair<int, float>>> inverted_;  // word -> (cell, tf)
  std::vector<int> document_frequency_;
  std::vector<float> cell_norm_;
  int cells_ = 0;
  void Build(int node, const cv::Mat& data, int level, cv::RNG& rng);
};

class PlaceCellMemory {
 public:
  explicit PlaceCellMemory(const PlaceViewOptions& view, const PanoramaModel& panorama,
                           const VocabularyOptions& vocabulary = {});

  // Adds a cell (id assigned: the next free one) and returns its index.
  int Add(const Pose2& pose, int64_t utime, PlaceView view);
  // Moves a cell (its pose source corrected its past, e.g. a loop closure); finite poses only.
  void SetPose(int index, const Pose2& pose);
  int size() const { return static_cast<int>(cells_.size()); }
  const std::vector<PlaceCell>& cells() const { return cells_; }
  const PlaceCell& cell(int index) const { return cells_.at(index); }
  const PlaceViewOptions& view_options() const { return view_; }
  const PanoramaModel& panorama() const { return panorama_; }

  // The index (vocabulary; the line templates when the vline measure is used) is built lazily
  // on the first query after cells were added, or now. Rebuild trains the vocabulary again; Add after it only extends the inverted
  // file (the vocabulary is retrained when the memory has doubled since).
  void BuildIndex();
  const VocabularyIndex& vocabulary() const { return vocabulary_; }
  // The vertical-line templates (4.4): descriptors of `count` distinctive lines of the memory.
  const cv::Mat& templates() const { return templates_; }
  void SetTemplateCount(int count);

  // Compares the view with the given cells (indices). Template responses of the view are computed
  // here when the measure needs them.
  std::vector<CellComparison> Compare(const PlaceView& view, const std::vector<int>& cells,
                                      const PlaceMeasureOptions& options) const;
  // The most similar cell: the lowest dissimilarity over the candidates (no filter); nullopt when
  // empty or none is seen.
  std::optional<CellComparison> MostSimilar(const PlaceView& view, const LocalizerOptions& options) const;

  // Localization: candidates, comparison, distance filter (when `predicted` is given and the
  // filter is enabled), estimate. nullopt when the memory is empty or no candidate is seen.
  std::optional<Localization> Localize(const PlaceView& view, const std::optional<Pose2>& predicted,
                                       const LocalizerOptions& options) const;

  // Memory used by the cells and the index.
  int64_t bytes() const;

  // Versioned binary form ("SNAPNAV-PLACECELLS" magic, format version, view options, cells).
  // Parse throws std::runtime_error naming the byte offset of what is wrong (truncated, foreign
  // magic, unsupported version, absurd counts).
  std::vector<uint8_t> Serialize() const;
  // The vocabulary is not stored: it is trained again, with `vocabulary`, on the first query.
  static PlaceCellMemory Parse(const std::vector<uint8_t>& bytes, const VocabularyOptions& vocabulary = {});
  static constexpr uint32_t kFormatVersion = 1;

 private:
  std::vector<int> Candidates(const PlaceView& view, const std::optional<Pose2>& predicted,
                              const LocalizerOptions& options) const;
  std::vector<float> TemplateBearings(const PlaceView& view) const;
  void EnsureIndex() const;      // the vocabulary and its inverted file
  void EnsureTemplates() const;  // the line templates and every cell's responses (vline measure only)

  PlaceViewOptions view_;
  PanoramaModel panorama_;
  std::vector<PlaceCell> cells_;
  int next_id_ = 0;
  int template_count_ = 6;
  mutable VocabularyIndex vocabulary_;
  mutable cv::Mat templates_;
  // Per cell, its responses to the templates (4.4): per template, the bearing of the most similar
  // line in the robot frame (NaN: no line).
  mutable std::vector<std::vector<float>> template_bearings_;
  mutable int indexed_cells_ = 0;   // cells in the inverted file
  mutable int trained_at_ = 0;      // memory size when the vocabulary was trained
  mutable bool templates_stale_ = true;
};

// Exploration (5.1.4): a view becomes a new cell when its dissimilarity to every stored cell
// (the most similar one) exceeds `threshold` (measure units: rad for bearing and vline, fraction
// for count). Returns the new cell's index, or -1 when the view was not novel.
int ExploreStep(PlaceCellMemory& memory, const Pose2& pose, int64_t utime, PlaceView view, double threshold,
                const LocalizerOptions& options, double* novelty = nullptr);

}  // namespace snapnav::nav
