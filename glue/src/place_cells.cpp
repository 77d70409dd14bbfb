#include "snapnav/glue/place_cells.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <vector>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/landmarks.hpp"

namespace snapnav::glue {
namespace {

constexpr double kDeg = M_PI / 180.0;

const char* Bool(bool b) { return b ? "true" : "false"; }

// Wraps a libnav validation error as a config error naming the file, the section and the key.
template <class F>
void Validated(const IniFile& ini, const char* section, F&& validate) {
  try {
    validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError("[" + std::string(section) + "] " + e.what());
  }
}

int ReadNonNegativeInt(const IniFile& ini, const std::string& section, const std::string& key) {
  const int v = ini.GetInt(section, key);
  if (v < 0) ini.FailKey(section, key, "must be >= 0");
  return v;
}

std::string ErrnoText() { return std::strerror(errno); }

}  // namespace

nav::PlaceViewOptions ReadPlaceViewOptions(const IniFile& ini) {
  nav::PlaceViewOptions o;
  o.features = ReadLandmarkExtractor(ini);
  if (o.features.method != nav::LandmarkMethod::kSift && o.features.method != nav::LandmarkMethod::kSurf) {
    // Read again for the line number and the choices.
    ReadChoice<int>(ini, "landmarks", "method", {{"sift", 0}, {"surf", 1}});
  }
  o.keep_vlines = ini.GetBool("place_view", "keep_vlines");
  o.vline = o.features.vline;
  o.vline.window_px = ini.GetInt("place_view", "vline_window_px");
  o.window_px = ini.GetInt("place_view", "window_px");
  o.window_scale = ini.GetDouble("place_view", "window_scale");
  o.signature_width_px = ini.GetInt("place_view", "signature_width_px");
  o.signature_height_px = ini.GetInt("place_view", "signature_height_px");
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
  m.match.ratio = ini.GetDouble("matching", "ratio");
  m.match.mutual = ini.GetBool("matching", "mutual");
  m.match.relaxed_second_best = ini.GetBool("matching", "relaxed_second_best");
  m.match.max_distance = ini.GetDouble("matching", "max_distance");
  m.match.max_x_displacement_px = ini.GetDouble("matching", "max_x_displacement_px");

  m.measure = ReadChoice<nav::PlaceMeasure>(ini, "measure", "measure",
                                            {{"bearing", nav::PlaceMeasure::kBearingDifference},
                                             {"count", nav::PlaceMeasure::kMatchCount},
                                             {"vline", nav::PlaceMeasure::kVlineTemplate}});
  m.refinement = ReadChoice<nav::MatchRefinement>(
      ini, "measure", "refinement",
      {{"smallest", nav::MatchRefinement::kSmallestDistance}, {"ransac", nav::MatchRefinement::kRansac}});
  m.keep_fraction = ini.GetDouble("measure", "keep_fraction");
  m.keep_min = ini.GetInt("measure", "keep_min");
  m.ransac_threshold_rad = ini.GetDouble("measure", "ransac_threshold_deg") * kDeg;
  m.ransac_iterations = ini.GetInt("measure", "ransac_iterations");
  m.residual_cap_rad = ini.GetDouble("measure", "residual_cap_rad");
  m.ransac_seed = static_cast<uint64_t>(ReadNonNegativeInt(ini, "measure", "ransac_seed"));
  m.window_min_ncc = ini.GetDouble("measure", "window_min_ncc");
  m.min_matches = ini.GetInt("measure", "min_matches");
  m.templates = ini.GetInt("measure", "templates");
  m.image_difference_weight = ini.GetDouble("measure", "image_difference_weight");

  auto& f = o.filter;
  f.enabled = ini.GetBool("distance_filter", "enabled");
  f.radius_m = ini.GetDouble("distance_filter", "radius_m");
  f.weight = ini.GetDouble("distance_filter", "weight");
  f.gate_m = ini.GetDouble("distance_filter", "gate_m");

  o.estimate = ReadChoice<nav::PlaceEstimate>(
      ini, "localizer", "estimate",
      {{"nearest", nav::PlaceEstimate::kNearestCell}, {"interpolated", nav::PlaceEstimate::kInterpolated}});
  o.interpolate_k = ini.GetInt("localizer", "interpolate_k");
  o.interpolate_power = ini.GetDouble("localizer", "interpolate_power");
  o.interpolate_radius_m = ini.GetDouble("localizer", "interpolate_radius_m");
  o.candidates = ini.GetInt("localizer", "candidates");
  o.near_candidates = ini.GetInt("localizer", "near_candidates");
  o.exhaustive_below = ini.GetInt("localizer", "exhaustive_below");
  o.min_position_sigma_m = ini.GetDouble("localizer", "min_position_sigma_m");
  Validated(ini, "matching", [&] { m.match.Validate(); });
  Validated(ini, "measure", [&] { m.Validate(); });
  Validated(ini, "distance_filter", [&] { f.Validate(); });
  Validated(ini, "localizer", [&] { o.Validate(); });
  return o;
}

nav::VocabularyOptions ReadVocabularyOptions(const IniFile& ini) {
  nav::VocabularyOptions o;
  o.branching = ini.GetInt("vocabulary", "branching");
  o.depth = ini.GetInt("vocabulary", "depth");
  o.max_training = ini.GetInt("vocabulary", "max_training");
  o.kmeans_iterations = ini.GetInt("vocabulary", "kmeans_iterations");
  o.seed = static_cast<uint64_t>(ReadNonNegativeInt(ini, "vocabulary", "seed"));
  Validated(ini, "vocabulary", [&] { o.Validate(); });
  return o;
}

void PrintPlaceViewOptions(std::ostream& out, const nav::PlaceViewOptions& o) {
  out << "[landmarks]\nmethod = " << nav::LandmarkMethodName(o.features.method)
      << "\nequalize_histogram = " << Bool(o.features.equalize_histogram) << "\n";
  PrintLandmarkExtractorSections(out, o.features);
  out << "[place_view]\nkeep_vlines = " << Bool(o.keep_vlines) << "\nvline_window_px = " << o.vline.window_px
      << "\nwindow_px = " << o.window_px << "\nwindow_scale = " << o.window_scale
      << "\nsignature_width_px = " << o.signature_width_px << "\nsignature_height_px = " << o.signature_height_px
      << "\n";
}

void PrintLocalizerOptions(std::ostream& out, const nav::LocalizerOptions& o) {
  const auto& m = o.measure;
  const auto& f = o.filter;
  out << "[matching]\nratio = " << m.match.ratio << "\nmutual = " << Bool(m.match.mutual)
      << "\nrelaxed_second_best = " << Bool(m.match.relaxed_second_best) << "\nmax_distance = " << m.match.max_distance
      << "\nmax_x_displacement_px = " << m.match.max_x_displacement_px << "\n"
      << "[measure]\nmeasure = " << nav::PlaceMeasureName(m.measure)
      << "\nrefinement = " << nav::MatchRefinementName(m.refinement) << "\nkeep_fraction = " << m.keep_fraction
      << "\nkeep_min = " << m.keep_min << "\nransac_threshold_deg = " << m.ransac_threshold_rad / kDeg
      << "\nransac_iterations = " << m.ransac_iterations << "\nresidual_cap_rad = " << m.residual_cap_rad << "\nransac_seed = " << m.ransac_seed
      << "\nwindow_min_ncc = " << m.window_min_ncc << "\nmin_matches = " << m.min_matches
      << "\ntemplates = " << m.templates << "\nimage_difference_weight = " << m.image_difference_weight << "\n"
      << "[distance_filter]\nenabled = " << Bool(f.enabled) << "\nradius_m = " << f.radius_m
      << "\nweight = " << f.weight << "\ngate_m = " << f.gate_m << "\n"
      << "[localizer]\nestimate = " << nav::PlaceEstimateName(o.estimate) << "\ninterpolate_k = " << o.interpolate_k
      << "\ninterpolate_power = " << o.interpolate_power << "\ninterpolate_radius_m = " << o.interpolate_radius_m
      << "\ncandidates = " << o.candidates
      << "\nnear_candidates = " << o.near_candidates << "\nexhaustive_below = " << o.exhaustive_below
      << "\nmin_position_sigma_m = " << o.min_position_sigma_m << "\n";
}

void PrintVocabularyOptions(std::ostream& out, const nav::VocabularyOptions& o) {
  out << "[vocabulary]\nbranching = " << o.branching << "\ndepth = " << o.depth << "\nmax_training = " << o.max_training
      << "\nkmeans_iterations = " << o.kmeans_iterations << "\nseed = " << o.seed << "\n";
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
