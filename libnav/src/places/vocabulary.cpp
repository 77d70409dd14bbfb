// Vocabulary tree (hierarchical k-means, Nister and Stewenius 2006) with an inverted file and
// tf-idf scoring: the place-cell memory's candidate selection.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "snapnav/nav/places/place_cells.hpp"

namespace snapnav::nav {

void VocabularyOptions::Validate() const {
  if (branching < 2 || branching > 64) throw std::invalid_argument("vocabulary: branching must be in [2, 64]");
  if (depth < 1 || depth > 8) throw std::invalid_argument("vocabulary: depth must be in [1, 8]");
  if (max_training < branching) throw std::invalid_argument("vocabulary: max_training must be at least branching");
  if (kmeans_iterations < 1) throw std::invalid_argument("vocabulary: kmeans_iterations must be at least 1");
}

VocabularyIndex::VocabularyIndex(const VocabularyOptions& options) : options_(options) { options_.Validate(); }

namespace {

// Lloyd's k-means with k-means++ seeding from `rng`: deterministic for a seed, unlike
// cv::kmeans which draws from the thread's global generator.
void KMeans(const cv::Mat& data, int k, int iterations, cv::RNG& rng, cv::Mat* centres, std::vector<int>* labels) {
  const int n = data.rows;
  centres->create(k, data.cols, CV_32F);
  std::vector<float> nearest(n, std::numeric_limits<float>::max());
  int first = rng.uniform(0, n);
  data.row(first).copyTo(centres->row(0));
  for (int c = 1; c < k; ++c) {
    double total = 0;
    for (int i = 0; i < n; ++i) {
      const float d = static_cast<float>(cv::norm(data.row(i), centres->row(c - 1), cv::NORM_L2SQR));
      nearest[i] = std::min(nearest[i], d);
      total += nearest[i];
    }
    double pick = rng.uniform(0.0, 1.0) * total;
    int chosen = n - 1;
    for (int i = 0; i < n; ++i) {
      pick -= nearest[i];
      if (pick <= 0) {
        chosen = i;
        break;
      }
    }
    data.row(chosen).copyTo(centres->row(c));
  }
  labels->assign(n, 0);
  cv::Mat dist, idx;
  for (int it = 0; it < iterations; ++it) {
    cv::batchDistance(data, *centres, dist, CV_32F, idx, cv::NORM_L2SQR, 1);
    bool changed = it == 0;
    for (int i = 0; i < n; ++i) {
      const int l = idx.at<int>(i, 0);
      if ((*labels)[i] != l) changed = true;
      (*labels)[i] = l;
    }
    if (!changed) break;
    cv::Mat sums = cv::Mat::zeros(k, data.cols, CV_64F);
    std::vector<int> counts(k, 0);
    for (int i = 0; i < n; ++i) {
      const int l = (*labels)[i];
      ++counts[l];
      const float* row = data.ptr<float>(i);
      double* s = sums.ptr<double>(l);
      for (int j = 0; j < data.cols; ++j) s[j] += row[j];
    }
    for (int c = 0; c < k; ++c) {
      if (counts[c] == 0) continue;  // keeps its old centre
      const double* s = sums.ptr<double>(c);
      float* out = centres->ptr<float>(c);
      for (int j = 0; j < data.cols; ++j) out[j] = static_cast<float>(s[j] / counts[c]);
    }
  }
}

}  // namespace

void VocabularyIndex::Train(const cv::Mat& descriptors) {
  if (descriptors.empty() || descriptors.type() != CV_32F) {
    throw std::invalid_argument("vocabulary: training needs CV_32F descriptors");
  }
  cv::RNG rng(options_.seed);
  cv::Mat data;
  if (descriptors.rows > options_.max_training) {
    std::vector<int> order(descriptors.rows);
    std::iota(order.begin(), order.end(), 0);
    for (int i = 0; i < options_.max_training; ++i) std::swap(order[i], order[rng.uniform(i, descriptors.rows)]);
    data.create(options_.max_training, descriptors.cols, CV_32F);
    for (int i = 0; i < options_.max_training; ++i) descriptors.row(order[i]).copyTo(data.row(i));
  } else {
    data = descriptors;
  }
  nodes_.assign(1, Node{});
  centres_ = cv::Mat::zeros(1, descriptors.cols, CV_32F);
  words_ = 0;
  Build(0, data, 0, rng);
  inverted_.assign(words_, {});
  document_frequency_.assign(words_, 0);
  cell_norm_.clear();
  cells_ = 0;
}

void VocabularyIndex::Build(int node, const cv::Mat& data, int level, cv::RNG& rng) {
  const int k = options_.branching;
  if (level == options_.depth || data.rows < 2 * k) {
    nodes_[node].word = words_++;
    return;
  }
  cv::Mat centres;
  std::vector<int> labels;
  KMeans(data, k, options_.kmeans_iterations, rng, &centres, &labels);
  const int first = static_cast<int>(nodes_.size());
  nodes_[node].first_child = first;
  nodes_[node].children = k;
  nodes_.resize(nodes_.size() + k);
  cv::vconcat(centres_, centres, centres_);
  for (int c = 0; c < k; ++c) {
    std::vector<int> members;
    for (int i = 0; i < data.rows; ++i) {
      if (labels[i] == c) members.push_back(i);
    }
    cv::Mat subset(static_cast<int>(members.size()), data.cols, CV_32F);
    for (size_t i = 0; i < members.size(); ++i) data.row(members[i]).copyTo(subset.row(static_cast<int>(i)));
    Build(first + c, subset, level + 1, rng);
  }
}

int VocabularyIndex::Word(const float* descriptor) const {
  if (nodes_.empty()) throw std::logic_error("vocabulary: not trained");
  const int dims = centres_.cols;
  int node = 0;
  while (nodes_[node].first_child >= 0) {
    const int first = nodes_[node].first_child;
    int best = first;
    float best_d = std::numeric_limits<float>::max();
    for (int c = first; c < first + nodes_[node].children; ++c) {
      const float* centre = centres_.ptr<float>(c);
      float d = 0;
      for (int j = 0; j < dims; ++j) {
        const float e = descriptor[j] - centre[j];
        d += e * e;
      }
      if (d < best_d) {
        best_d = d;
        best = c;
      }
    }
    node = best;
  }
  return nodes_[node].word;
}

namespace {
std::vector<std::pair<int, float>> WordHistogram(const VocabularyIndex& vocabulary, const cv::Mat& descriptors) {
  std::vector<int> words;
  words.reserve(descriptors.rows);
  cv::Mat row_f;
  for (int i = 0; i < descriptors.rows; ++i) {
    if (descriptors.type() == CV_32F) {
      words.push_back(vocabulary.Word(descriptors.ptr<float>(i)));
    } else {
      descriptors.row(i).convertTo(row_f, CV_32F);
      words.push_back(vocabulary.Word(row_f.ptr<float>(0)));
    }
  }
  std::sort(words.begin(), words.end());
  std::vector<std::pair<int, float>> histogram;
  for (size_t i = 0; i < words.size();) {
    size_t j = i;
    while (j < words.size() && words[j] == words[i]) ++j;
    histogram.emplace_back(words[i], static_cast<float>(j - i) / words.size());
    i = j;
  }
  return histogram;
}
}  // namespace

void VocabularyIndex::Add(int cell, const cv::Mat& descriptors) {
  if (!trained()) throw std::logic_error("vocabulary: Add before Train");
  if (cell < 0) throw std::invalid_argument("vocabulary: negative cell index");
  if (static_cast<int>(cell_norm_.size()) <= cell) cell_norm_.resize(cell + 1, 0.0f);
  double norm = 0;
  if (!descriptors.empty()) {
    for (const auto& [word, tf] : WordHistogram(*this, descriptors)) {
      inverted_[word].emplace_back(cell, tf);
      ++document_frequency_[word];
      norm += static_cast<double>(tf) * tf;
    }
  }
  cell_norm_[cell] = static_cast<float>(std::sqrt(norm));
  cells_ = std::max(cells_, cell + 1);
}

std::vector<std::pair<int, double>> VocabularyIndex::Query(const cv::Mat& descriptors, int k) const {
  std::vector<std::pair<int, double>> out;
  if (!trained() || descriptors.empty() || k <= 0) return out;
  std::vector<double> score(cells_, 0.0);
  for (const auto& [word, tf] : WordHistogram(*this, descriptors)) {
    const int df = document_frequency_[word];
    if (df == 0) continue;
    const double idf = std::log(static_cast<double>(cells_) / df);
    const double w = tf * idf * idf;
    for (const auto& [cell, cell_tf] : inverted_[word]) score[cell] += w * cell_tf;
  }
  for (int c = 0; c < cells_; ++c) {
    if (score[c] > 0 && cell_norm_[c] > 0) out.emplace_back(c, score[c] / cell_norm_[c]);
  }
  const size_t keep = std::min<size_t>(k, out.size());
  std::partial_sort(out.begin(), out.begin() + keep, out.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  out.resize(keep);
  return out;
}

int64_t VocabularyIndex::bytes() const {
  int64_t b = static_cast<int64_t>(nodes_.size() * sizeof(Node)) + static_cast<int64_t>(centres_.total() * centres_.elemSize());
  for (const auto& list : inverted_) b += static_cast<int64_t>(list.capacity() * sizeof(std::pair<int, float>));
  b += static_cast<int64_t>(document_frequency_.size() * sizeof(int) + cell_norm_.size() * sizeof(float));
  return b;
}

}  // namespace snapnav::nav
