#include "snapnav/glue/place_cells.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <ostream>
#include <vector>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/landmarks.hpp"

namespace snapnav::glue {
namespace {

// Wraps a libnav validation error as a config error naming the file, the section and the key.
template <class F>
void Validated(const IniFile& ini, const char* section, F&& validate) {
  try {
    validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError("[" + std::string(section) + "] " + e.what());
  }
}

std::string ErrnoText() { return std::strerror(errno); }

// The keys of [place_view], [measure], [distance_filter], [localizer] and [vocabulary], declared once:
// read, printed and described from here ([matching] is MatchOptionTable, landmarks.hpp).
const OptionTable<nav::PlaceViewOptions>& PlaceViewTable() {
  using O = nav::PlaceViewOptions;
  static const auto table = OptionTable<O>()
                                .Flag("keep_vlines", &O::keep_vlines)
                                .Number("vline_window_px", "px", [](auto& o) -> auto& { return o.vline.window_px; })
                                .Number("window_px", "px", &O::window_px)
                                .Number("window_scale", "", &O::window_scale)
                                .Number("signature_width_px", "px", &O::signature_width_px)
                                .Number("signature_height_px", "px", &O::signature_height_px);
  return table;
}

const OptionTable<nav::PlaceMeasureOptions>& MeasureTable() {
  using O = nav::PlaceMeasureOptions;
  static const auto table =
      OptionTable<O>()
          .Choice("measure", &O::measure,
                  std::vector<std::pair<std::string, nav::PlaceMeasure>>{{"bearing", nav::PlaceMeasure::kBearingDifference},
                                                                        {"count", nav::PlaceMeasure::kMatchCount},
                                                                        {"vline", nav::PlaceMeasure::kVlineTemplate}})
          .Choice("refinement", &O::refinement,
                  std::vector<std::pair<std::string, nav::MatchRefinement>>{
                      {"smallest", nav::MatchRefinement::kSmallestDistance}, {"ransac", nav::MatchRefinement::kRansac}})
          .Number("keep_fraction", "", &O::keep_fraction)
          .Number("keep_min", "", &O::keep_min)
          .Degrees("ransac_threshold_deg", &O::ransac_threshold_rad)
          .Number("ransac_iterations", "", &O::ransac_iterations)
          .Number("residual_cap_rad", "rad", &O::residual_cap_rad)
          .Number("ransac_seed", "", &O::ransac_seed)
          .Number("window_min_ncc", "", &O::window_min_ncc)
          .Number("min_matches", "", &O::min_matches)
          .Number("templates", "", &O::templates)
          .Number("image_difference_weight", "", &O::image_difference_weight);
  return table;
}

const OptionTable<nav::DistanceFilterOptions>& DistanceFilterTable() {
  using O = nav::DistanceFilterOptions;
  static const auto table = OptionTable<O>()
                                .Flag("enabled", &O::enabled)
                                .Number("radius_m", "m", &O::radius_m)
                                .Number("weight", "", &O::weight)
                                .Number("gate_m", "m", &O::gate_m);
  return table;
}

const OptionTable<nav::LocalizerOptions>& LocalizerTable() {
  using O = nav::LocalizerOptions;
  static const auto table =
      OptionTable<O>()
          .Choice("estimate", &O::estimate,
                  std::vector<std::pair<std::string, nav::PlaceEstimate>>{{"nearest", nav::PlaceEstimate::kNearestCell},
                                                                         {"interpolated", nav::PlaceEstimate::kInterpolated}})
          .Number("interpolate_k", "", &O::interpolate_k)
          .Number("interpolate_power", "", &O::interpolate_power)
          .Number("interpolate_radius_m", "m", &O::interpolate_radius_m)
          .Number("candidates", "", &O::candidates)
          .Number("near_candidates", "", &O::near_candidates)
          .Number("exhaustive_below", "", &O::exhaustive_below)
          .Number("min_position_sigma_m", "m", &O::min_position_sigma_m);
  return table;
}

const OptionTable<nav::VocabularyOptions>& VocabularyTable() {
  using O = nav::VocabularyOptions;
  static const auto table = OptionTable<O>()
                                .Number("branching", "", &O::branching)
                                .Number("depth", "", &O::depth)
                                .Number("max_training", "", &O::max_training)
                                .Number("kmeans_iterations", "", &O::kmeans_iterations)
                                .Number("seed", "", &O::seed);
  return table;
}


}  // namespace

nav::PlaceViewOptions ReadPlaceViewOptions(const IniFile& ini) {
  nav::PlaceViewOptions o;
  o.features = ReadLandmarkExtractor(ini);
  if (o.features.method != nav::LandmarkMethod::kSift && o.features.method != nav::LandmarkMethod::kSurf) {
    // Read again for the line number and the choices.
    ReadChoice<int>(ini, "landmarks", "method", {{"sift", 0}, {"surf", 1}});
  }
  o.vline = o.features.vline;
  PlaceViewTable().ReadKeys(ini, "place_view", &o);
  Validated(ini, "place_view", [&] {
    // The [vline] options with this section's window: a window the check refuses is vline_window_px.
    try {
      o.vline.Validate();
    } catch (const std::invalid_argument& e) {
      if (std::string(e.what()).find("window_px") != std::string::npos)
        ini.FailKey("place_view", "vline_window_px", e.what());
      throw;
    }
    o.Validate();
  });
  return o;
}

nav::LocalizerOptions ReadLocalizerOptions(const IniFile& ini) {
  nav::LocalizerOptions o;
  auto& m = o.measure;
  MatchOptionTable().ReadKeys(ini, "matching", &m.match);

  MeasureTable().ReadKeys(ini, "measure", &m);
  auto& f = o.filter;
  DistanceFilterTable().ReadKeys(ini, "distance_filter", &f);
  LocalizerTable().ReadKeys(ini, "localizer", &o);
  Validated(ini, "matching", [&] { m.match.Validate(); });
  Validated(ini, "measure", [&] { m.Validate(); });
  Validated(ini, "distance_filter", [&] { f.Validate(); });
  Validated(ini, "localizer", [&] { o.Validate(); });
  return o;
}

nav::VocabularyOptions ReadVocabularyOptions(const IniFile& ini) {
  nav::VocabularyOptions o;
  VocabularyTable().ReadKeys(ini, "vocabulary", &o);
  Validated(ini, "vocabulary", [&] { o.Validate(); });
  return o;
}

void PrintPlaceViewOptions(std::ostream& out, const nav::PlaceViewOptions& o) {
  out << "[landmarks]\n";
  PrintLandmarkExtractorKeys(out, o.features);
  PrintLandmarkExtractorSections(out, o.features);
  out << "[place_view]\n";
  PlaceViewTable().Print(out, o);
}

void PrintLocalizerOptions(std::ostream& out, const nav::LocalizerOptions& o) {
  out << "[matching]\n";
  MatchOptionTable().Print(out, o.measure.match);
  out << "[measure]\n";
  MeasureTable().Print(out, o.measure);
  out << "[distance_filter]\n";
  DistanceFilterTable().Print(out, o.filter);
  out << "[localizer]\n";
  LocalizerTable().Print(out, o);
}

void PrintVocabularyOptions(std::ostream& out, const nav::VocabularyOptions& o) {
  out << "[vocabulary]\n";
  VocabularyTable().Print(out, o);
}

nav::PlaceCellMemory LoadPlaceMemory(const std::string& path, const nav::VocabularyOptions& vocabulary) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw PlaceMemoryError("place-cell memory " + path + ": cannot open: " + ErrnoText());
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw PlaceMemoryError("place-cell memory " + path + ": read failed: " + ErrnoText());
  try {
    return nav::PlaceCellMemory::Parse(bytes, vocabulary);
  } catch (const std::exception& e) {
    // Parse names the byte offset of what is wrong.
    std::string why = e.what();
    const std::string prefix = "place-cell memory: ";
    if (why.compare(0, prefix.size(), prefix) == 0) why.erase(0, prefix.size());
    throw PlaceMemoryError("place-cell memory " + path + " (" + std::to_string(bytes.size()) + " bytes): " + why);
  }
}

void SavePlaceMemory(const nav::PlaceCellMemory& memory, const std::string& path) {
  const std::vector<uint8_t> bytes = memory.Serialize();
  const std::filesystem::path target(path);
  const std::string tmp = (target.parent_path() / ("." + target.filename().string() + ".tmp." +
                                                   std::to_string(static_cast<long>(::getpid()))))
                              .string();
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw PlaceMemoryError("place-cell memory " + path + ": cannot create " + tmp + ": " + ErrnoText());
  auto fail = [&](const std::string& what) {
    const std::string why = ErrnoText();
    ::close(fd);
    ::unlink(tmp.c_str());
    throw PlaceMemoryError("place-cell memory " + path + ": " + what + " " + tmp + " failed: " + why);
  };
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("writing");
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) fail("flushing");
  if (::close(fd) != 0) {
    const std::string why = ErrnoText();
    ::unlink(tmp.c_str());
    throw PlaceMemoryError("place-cell memory " + path + ": closing " + tmp + " failed: " + why);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = ErrnoText();
    ::unlink(tmp.c_str());
    throw PlaceMemoryError("place-cell memory " + path + ": renaming " + tmp + " failed: " + why);
  }
  // The rename itself reaches the disk with the folder.
  const std::string dir = target.parent_path().empty() ? "." : target.parent_path().string();
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

place_cell_match_t ToPlaceCellMatchMsg(int64_t utime, const nav::Localization& loc, const nav::PlaceCell& cell,
                                       nav::PlaceMeasure measure) {
  if (cell.id != loc.cell_id) {
    throw std::invalid_argument("place cell match: cell " + std::to_string(cell.id) + " is not the best cell " +
                                std::to_string(loc.cell_id));
  }
  place_cell_match_t m{};
  m.utime = utime;
  m.cell_id = loc.cell_id;
  m.distance_measure = static_cast<int8_t>(measure);
  m.distance = static_cast<float>(loc.best.distance);
  m.score = static_cast<float>(loc.best.score);
  m.ncandidates = loc.candidates;
  m.x_m = cell.pose.x_m;
  m.y_m = cell.pose.y_m;
  m.theta_rad = cell.pose.theta_rad;
  return m;
}

place_cell_match_t NoPlaceCellMatchMsg(int64_t utime, nav::PlaceMeasure measure, int candidates) {
  place_cell_match_t m{};
  m.utime = utime;
  m.cell_id = -1;
  m.distance_measure = static_cast<int8_t>(measure);
  m.ncandidates = candidates;
  return m;
}

pose_t ToPlaceCellPoseMsg(int64_t utime, const nav::Localization& loc) {
  return ToPoseMsg(utime, kPlaceCellsEstimator, kPlaceCellsFrame, loc.pose, loc.covariance);
}

}  // namespace snapnav::glue
