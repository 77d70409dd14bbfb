// The place-cell memory's versioned binary form. Little-endian; a 64-bit FNV-1a checksum of
// everything before it closes the data, so a corrupted file is told apart from a valid one.
//
//   "SNAPNAV-PLACECELLS" (18 bytes), u32 version
//   view options: u8 method, i32 sift max_features, i32 window_px, f64 window_scale,
//                 i32 signature width, height, u8 keep_vlines, i32 vline window_px, u8 vline divided
//   panorama model: i32 width, height, f64 bearing_col0, elevation top, bottom
//   i32 template count, i32 next id, u32 cells
//   per cell: i32 id, f64 x, y, theta, i64 utime,
//             landmark set (features), windows (u32 rows, u32 cols, i8 data), landmark set (lines),
//             signature (u32 rows, u32 cols, u8 data)
//   landmark set: u8 method, i32 width, height, u32 count, count x 5 f32 (x, y, strength, scale,
//                 angle), u32 descriptor cols, u8 type (0: u8, 1: f32), count x cols values
//   u64 checksum

#include <cstring>
#include <stdexcept>
#include <string>

#include "snapnav/nav/places/place_cells.hpp"

namespace snapnav::nav {

namespace {
constexpr char kMagic[] = "SNAPNAV-PLACECELLS";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;
constexpr uint32_t kMaxCells = 10000000;
constexpr uint32_t kMaxLandmarks = 100000;
constexpr uint32_t kMaxCols = 4096;

uint64_t Fnv1a(const uint8_t* data, size_t n) {
  uint64_t h = 1469598103934665603ULL;
  for (size_t i = 0; i < n; ++i) {
    h ^= data[i];
    h *= 1099511628211ULL;
  }
  return h;
}

class Writer {
 public:
  template <typename T>
  void Put(T v) {
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // x86 and ARM are little-endian, as the format
    out_.insert(out_.end(), b, b + sizeof(T));
  }
  void Bytes(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out_.insert(out_.end(), b, b + n);
  }
  void Set(const LandmarkSet& set) {
    Put<uint8_t>(static_cast<uint8_t>(set.method));
    Put<int32_t>(set.width_px);
    Put<int32_t>(set.height_px);
    Put<uint32_t>(static_cast<uint32_t>(set.landmarks.size()));
    for (const auto& l : set.landmarks) {
      Put<float>(l.x_px);
      Put<float>(l.y_px);
      Put<float>(l.strength);
      Put<float>(l.scale_px);
      Put<float>(l.angle_deg);
    }
    const cv::Mat d = set.descriptors.isContinuous() ? set.descriptors : set.descriptors.clone();
    Put<uint32_t>(d.empty() ? 0u : static_cast<uint32_t>(d.cols));
    Put<uint8_t>(d.type() == CV_8U ? 0 : 1);
    if (!d.empty()) Bytes(d.data, d.total() * d.elemSize());
  }
  void Image(const cv::Mat& m) {
    const cv::Mat c = m.isContinuous() ? m : m.clone();
    Put<uint32_t>(static_cast<uint32_t>(c.rows));
    Put<uint32_t>(static_cast<uint32_t>(c.cols));
    if (!c.empty()) Bytes(c.data, c.total() * c.elemSize());
  }
  std::vector<uint8_t>& out() { return out_; }

 private:
  std::vector<uint8_t> out_;
};

class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& in, size_t end) : in_(in), end_(end) {}
  [[noreturn]] void Fail(const std::string& what, size_t at) const {
    throw std::runtime_error("place-cell memory: " + what + " at byte " + std::to_string(at));
  }
  template <typename T>
  T Get(const char* what) {
    if (pos_ + sizeof(T) > end_) Fail(std::string("truncated: ") + what + " missing", pos_);
    T v;
    std::memcpy(&v, in_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  uint32_t Count(const char* what, uint32_t max) {
    const size_t at = pos_;
    const uint32_t n = Get<uint32_t>(what);
    if (n > max) Fail(std::string(what) + " " + std::to_string(n) + " exceeds " + std::to_string(max), at);
    return n;
  }
  void Bytes(void* out, size_t n, const char* what) {
    if (n > end_ - pos_) Fail(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes", pos_);
    std::memcpy(out, in_.data() + pos_, n);
    pos_ += n;
  }
  LandmarkSet Set(const char* what) {
    LandmarkSet set;
    const size_t at = pos_;
    const uint8_t method = Get<uint8_t>(what);
    if (method > 3) Fail(std::string(what) + ": unknown landmark method " + std::to_string(method), at);
    set.method = static_cast<LandmarkMethod>(method);
    set.width_px = Get<int32_t>(what);
    set.height_px = Get<int32_t>(what);
    const uint32_t n = Count("landmark count", kMaxLandmarks);
    set.landmarks.resize(n);
    for (auto& l : set.landmarks) {
      l.x_px = Get<float>(what);
      l.y_px = Get<float>(what);
      l.strength = Get<float>(what);
      l.scale_px = Get<float>(what);
      l.angle_deg = Get<float>(what);
    }
    const uint32_t cols = Count("descriptor length", kMaxCols);
    const size_t type_at = pos_;
    const uint8_t type = Get<uint8_t>(what);
    if (type > 1) Fail(std::string(what) + ": unknown descriptor type " + std::to_string(type), type_at);
    if (n > 0 && cols > 0) {
      set.descriptors.create(static_cast<int>(n), static_cast<int>(cols), type == 0 ? CV_8U : CV_32F);
      Bytes(set.descriptors.data, set.descriptors.total() * set.descriptors.elemSize(), "descriptors");
    } else if (n > 0) {
      Fail(std::string(what) + ": landmarks without descriptors", type_at);
    }
    return set;
  }
  cv::Mat Image(int type, uint32_t max_rows, const char* what) {
    const uint32_t rows = Count(what, max_rows);
    const uint32_t cols = Count(what, kMaxCols);
    cv::Mat m;
    if (rows > 0 && cols > 0) {
      m.create(static_cast<int>(rows), static_cast<int>(cols), type);
      Bytes(m.data, m.total() * m.elemSize(), what);
    }
    return m;
  }
  size_t pos() const { return pos_; }

 private:
  const std::vector<uint8_t>& in_;
  size_t end_;
  size_t pos_ = 0;
};
}  // namespace

std::vector<uint8_t> PlaceCellMemory::Serialize() const {
  Writer w;
  w.Bytes(kMagic, kMagicSize);
  w.Put<uint32_t>(kFormatVersion);
  w.Put<uint8_t>(static_cast<uint8_t>(view_.features.method));
  w.Put<int32_t>(view_.features.sift.max_features);
  w.Put<int32_t>(view_.window_px);
  w.Put<double>(view_.window_scale);
  w.Put<int32_t>(view_.signature_width_px);
  w.Put<int32_t>(view_.signature_height_px);
  w.Put<uint8_t>(view_.keep_vlines ? 1 : 0);
  w.Put<int32_t>(view_.vline.window_px);
  w.Put<uint8_t>(view_.vline.divided ? 1 : 0);
  w.Put<int32_t>(panorama_.width_px);
  w.Put<int32_t>(panorama_.height_px);
  w.Put<double>(panorama_.bearing_col0_rad);
  w.Put<double>(panorama_.elevation_top_rad);
  w.Put<double>(panorama_.elevation_bottom_rad);
  w.Put<int32_t>(template_count_);
  w.Put<int32_t>(next_id_);
  w.Put<uint32_t>(static_cast<uint32_t>(cells_.size()));
  for (const auto& c : cells_) {
    w.Put<int32_t>(c.id);
    w.Put<double>(c.pose.x_m);
    w.Put<double>(c.pose.y_m);
    w.Put<double>(c.pose.theta_rad);
    w.Put<int64_t>(c.utime);
    w.Set(c.view.landmarks);
    w.Image(c.view.windows);
    w.Set(c.view.vlines);
    w.Image(c.view.signature);
  }
  w.Put<uint64_t>(Fnv1a(w.out().data(), w.out().size()));
  return std::move(w.out());
}

PlaceCellMemory PlaceCellMemory::Parse(const std::vector<uint8_t>& bytes, const VocabularyOptions& vocabulary) {
  if (bytes.size() < kMagicSize || std::memcmp(bytes.data(), kMagic, kMagicSize) != 0) {
    throw std::runtime_error("place-cell memory: not a snapnav place-cell memory (no \"" + std::string(kMagic) +
                             "\" magic) at byte 0");
  }
  Reader header(bytes, bytes.size());
  {
    uint8_t skip[kMagicSize];
    header.Bytes(skip, kMagicSize, "magic");
  }
  const size_t version_at = header.pos();
  const uint32_t version = header.Get<uint32_t>("format version");
  if (version != kFormatVersion) {
    throw std::runtime_error("place-cell memory: format version " + std::to_string(version) + " is not supported (this build reads " +
                             std::to_string(kFormatVersion) + ") at byte " + std::to_string(version_at));
  }
  if (bytes.size() < kMagicSize + 4 + 8) header.Fail("truncated: no checksum", bytes.size());
  const size_t body_end = bytes.size() - 8;
  Reader r(bytes, body_end);
  {
    uint8_t skip[kMagicSize + 4];
    r.Bytes(skip, sizeof(skip), "header");
  }
  PlaceViewOptions view;
  const size_t method_at = r.pos();
  const uint8_t method = r.Get<uint8_t>("feature method");
  if (method != static_cast<uint8_t>(LandmarkMethod::kSift) && method != static_cast<uint8_t>(LandmarkMethod::kSurf)) {
    r.Fail("feature method " + std::to_string(method) + " is neither SIFT nor SURF", method_at);
  }
  view.features.method = static_cast<LandmarkMethod>(method);
  view.features.sift.max_features = r.Get<int32_t>("sift max_features");
  view.window_px = r.Get<int32_t>("window_px");
  view.window_scale = r.Get<double>("window_scale");
  view.signature_width_px = r.Get<int32_t>("signature width");
  view.signature_height_px = r.Get<int32_t>("signature height");
  view.keep_vlines = r.Get<uint8_t>("keep_vlines") != 0;
  view.vline.window_px = r.Get<int32_t>("vline window_px");
  view.vline.divided = r.Get<uint8_t>("vline divided") != 0;
  PanoramaModel panorama;
  panorama.width_px = r.Get<int32_t>("panorama width");
  panorama.height_px = r.Get<int32_t>("panorama height");
  panorama.bearing_col0_rad = r.Get<double>("panorama bearing");
  panorama.elevation_top_rad = r.Get<double>("panorama elevation");
  panorama.elevation_bottom_rad = r.Get<double>("panorama elevation");
  const size_t options_end = r.pos();
  const int32_t templates = r.Get<int32_t>("template count");
  const int32_t next_id = r.Get<int32_t>("next id");
  const uint32_t n = r.Count("cell count", kMaxCells);
  // The checksum: a flipped bit anywhere is told apart from a valid file.
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + body_end, 8);
  std::optional<PlaceCellMemory> memory;
  try {
    memory.emplace(view, panorama, vocabulary);
    memory->SetTemplateCount(templates);
  } catch (const std::invalid_argument& e) {
    r.Fail(std::string("invalid options (") + e.what() + ")", options_end);
  }
  for (uint32_t i = 0; i < n; ++i) {
    const size_t cell_at = r.pos();
    PlaceCell c;
    c.id = r.Get<int32_t>("cell id");
    c.pose.x_m = r.Get<double>("cell pose");
    c.pose.y_m = r.Get<double>("cell pose");
    c.pose.theta_rad = r.Get<double>("cell pose");
    c.utime = r.Get<int64_t>("cell utime");
    c.view.landmarks = r.Set("cell landmarks");
    c.view.windows = r.Image(CV_8S, kMaxLandmarks, "cell windows");
    c.view.vlines = r.Set("cell lines");
    c.view.signature = r.Image(CV_8U, kMaxCols, "cell signature");
    const int id = c.id;
    try {
      memory->Add(c.pose, c.utime, std::move(c.view));
    } catch (const std::invalid_argument& e) {
      r.Fail("cell " + std::to_string(i) + " is invalid (" + e.what() + ")", cell_at);
    }
    memory->cells_.back().id = id;
  }
  if (r.pos() != body_end) r.Fail(std::to_string(body_end - r.pos()) + " unexpected bytes after the last cell", r.pos());
  if (Fnv1a(bytes.data(), body_end) != stored) {
    throw std::runtime_error("place-cell memory: checksum mismatch (the file is corrupt) at byte " + std::to_string(body_end));
  }
  memory->next_id_ = next_id;
  return std::move(*memory);
}

}  // namespace snapnav::nav
