#include "snapnav/glue/landmarks.hpp"

#include <cmath>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace snapnav::glue {
namespace {

void CheckFinite(float v, const char* what) {
  if (!std::isfinite(v)) throw std::invalid_argument(std::string("landmark set: non-finite ") + what);
}

nav::MatchOptions ReadMatching(const IniFile& ini, const std::string& section) {
  nav::MatchOptions m;
  MatchOptionTable().ReadKeys(ini, section, &m);
  return m;
}

// The keys of [vline], [sift], [surf] and [landmark_alv], declared once: read, printed and described
// from here.
using Extractor = nav::LandmarkExtractorConfig;

// [landmarks]: which extractor, and the histogram equalisation before it (HOG is homing's own, not
// one of these).
const OptionTable<Extractor>& ExtractorTable() {
  static const auto table =
      OptionTable<Extractor>()
          .Choice("method", &Extractor::method,
                  {nav::LandmarkMethod::kVline, nav::LandmarkMethod::kSift, nav::LandmarkMethod::kSurf},
                  nav::LandmarkMethodName)
          .Flag("equalize_histogram", &Extractor::equalize_histogram);
  return table;
}

const OptionTable<Extractor>& VlineTable() {
  static const auto table =
      OptionTable<Extractor>()
          .Number("blur_sigma_px", "px", [](auto& c) -> auto& { return c.vline.blur_sigma_px; })
          .Number("canny_low", "", [](auto& c) -> auto& { return c.vline.canny_low; })
          .Number("canny_high", "", [](auto& c) -> auto& { return c.vline.canny_high; })
          .Number("hough_threshold", "", [](auto& c) -> auto& { return c.vline.hough_threshold; })
          .Number("min_segment_px", "px", [](auto& c) -> auto& { return c.vline.min_segment_px; })
          .Number("max_gap_px", "px", [](auto& c) -> auto& { return c.vline.max_gap_px; })
          .Number("max_tilt_deg", "deg", [](auto& c) -> auto& { return c.vline.max_tilt_deg; })
          .Number("cluster_px", "px", [](auto& c) -> auto& { return c.vline.cluster_px; })
          .Number("min_line_px", "px", [](auto& c) -> auto& { return c.vline.min_line_px; })
          .Number("window_px", "px", [](auto& c) -> auto& { return c.vline.window_px; })
          .Number("bins", "", [](auto& c) -> auto& { return c.vline.bins; })
          .Flag("divided", [](auto& c) -> auto& { return c.vline.divided; });
  return table;
}

const OptionTable<Extractor>& SiftTable() {
  static const auto table =
      OptionTable<Extractor>()
          .Number("max_features", "", [](auto& c) -> auto& { return c.sift.max_features; })
          .Number("octave_layers", "", [](auto& c) -> auto& { return c.sift.octave_layers; })
          .Number("contrast_threshold", "", [](auto& c) -> auto& { return c.sift.contrast_threshold; })
          .Number("edge_threshold", "", [](auto& c) -> auto& { return c.sift.edge_threshold; })
          .Number("sigma", "px", [](auto& c) -> auto& { return c.sift.sigma; });
  return table;
}

const OptionTable<Extractor>& SurfTable() {
  static const auto table =
      OptionTable<Extractor>()
          .Number("hessian_threshold", "", [](auto& c) -> auto& { return c.surf.hessian_threshold; })
          .Number("octaves", "", [](auto& c) -> auto& { return c.surf.octaves; })
          .Number("intervals", "", [](auto& c) -> auto& { return c.surf.intervals; })
          .Number("init_sample", "", [](auto& c) -> auto& { return c.surf.init_sample; })
          .Flag("upright", [](auto& c) -> auto& { return c.surf.upright; })
          .Number("max_keypoints", "", [](auto& c) -> auto& { return c.surf.max_keypoints; })
          .Number("pad_px", "px", &Extractor::surf_pad_px);
  return table;
}

const OptionTable<nav::LandmarkHomingConfig>& LandmarkAlvTable() {
  using C = nav::LandmarkHomingConfig;
  static const auto table =
      OptionTable<C>()
          .Choice("variant", [](auto& c) -> auto& { return c.alv.variant; },
                  {nav::AlvVariant::kUnit, nav::AlvVariant::kWeighted, nav::AlvVariant::kScale}, nav::AlvVariantName)
          .Choice("weight", [](auto& c) -> auto& { return c.alv.weight; },
                  {nav::MatchWeight::kScore, nav::MatchWeight::kDistance}, nav::MatchWeightName)
          .Number("top_n", "", [](auto& c) -> auto& { return c.alv.top_n; })
          .Choice("difference", [](auto& c) -> auto& { return c.alv.difference; },
                  std::vector<std::pair<std::string, nav::AlvDifference>>{
                      {"current_minus_home", nav::AlvDifference::kCurrentMinusHome},
                      {"home_minus_current", nav::AlvDifference::kHomeMinusCurrent}})
          .Number("max_scale_ratio", "", [](auto& c) -> auto& { return c.alv.max_scale_ratio; })
          .Number("min_landmarks", "", [](auto& c) -> auto& { return c.alv.min_landmarks; })
          .Flag("consensus", [](auto& c) -> auto& { return c.alv.consensus; })
          .Degrees("consensus_window_deg", [](auto& c) -> auto& { return c.alv.consensus_window_rad; })
          .Degrees("rotation_refine_deg", [](auto& c) -> auto& { return c.alv.rotation_refine_rad; })
          .Choice("rotation", &C::rotation,
                  std::vector<std::pair<std::string, nav::RotationSource>>{{"matches", nav::RotationSource::kMatches},
                                                                          {"none", nav::RotationSource::kNone}})
          .Degrees("rotation_window_deg", &C::rotation_window_rad);
  return table;
}

}  // namespace

const OptionTable<nav::MatchOptions>& MatchOptionTable() {
  using M = nav::MatchOptions;
  static const auto table = OptionTable<M>()
                                .Number("ratio", "", &M::ratio)
                                .Flag("mutual", &M::mutual)
                                .Flag("relaxed_second_best", &M::relaxed_second_best)
                                .Number("max_distance", "", &M::max_distance)
                                .Number("max_x_displacement_px", "px", &M::max_x_displacement_px);
  return table;
}

landmark_set_t LandmarkSetToMsg(const nav::LandmarkSet& set, const nav::PanoramaModel& panorama, int64_t utime,
                                const std::string& sensor_name) {
  if (set.width_px != panorama.width_px || set.height_px != panorama.height_px) {
    throw std::invalid_argument("landmark set of a " + std::to_string(set.width_px) + "x" + std::to_string(set.height_px) +
                                " panorama, the model is " + std::to_string(panorama.width_px) + "x" +
                                std::to_string(panorama.height_px));
  }
  landmark_set_t msg;
  msg.utime = utime;
  msg.sensor_name = sensor_name;
  msg.method = static_cast<int8_t>(set.method);
  msg.panorama_width_px = set.width_px;
  msg.panorama_height_px = set.height_px;
  msg.nlandmarks = set.size();
  msg.descriptor_length = set.empty() ? 0 : set.descriptors.cols;
  for (int i = 0; i < set.size(); ++i) {
    const auto& l = set.landmarks[i];
    msg.bearings_rad.push_back(static_cast<float>(panorama.BearingOfColumn(l.x_px)));
    msg.rows_px.push_back(l.y_px);
    msg.strengths.push_back(l.strength);
    msg.scales_px.push_back(l.scale_px);
    const float* row = set.descriptors.ptr<float>(i);
    msg.descriptors.emplace_back(row, row + msg.descriptor_length);
  }
  return msg;
}

nav::LandmarkSet LandmarkSetFromMsg(const landmark_set_t& msg, const nav::PanoramaModel& panorama) {
  if (msg.method < landmark_set_t::VLINE || msg.method > landmark_set_t::SURF) {
    throw std::invalid_argument("landmark set: method " + std::to_string(msg.method) + " is not vline, sift or surf");
  }
  if (msg.panorama_width_px != panorama.width_px || msg.panorama_height_px != panorama.height_px) {
    throw std::invalid_argument("landmark set: from a " + std::to_string(msg.panorama_width_px) + "x" +
                                std::to_string(msg.panorama_height_px) + " panorama, the model is " +
                                std::to_string(panorama.width_px) + "x" + std::to_string(panorama.height_px));
  }
  if (msg.nlandmarks < 0 || msg.descriptor_length < 0) throw std::invalid_argument("landmark set: negative counts");
  const size_t n = static_cast<size_t>(msg.nlandmarks);
  if (msg.bearings_rad.size() != n || msg.rows_px.size() != n || msg.strengths.size() != n ||
      msg.scales_px.size() != n || msg.descriptors.size() != n) {
    throw std::invalid_argument("landmark set: arrays do not have nlandmarks entries");
  }
  if (n > 0 && msg.descriptor_length == 0) throw std::invalid_argument("landmark set: landmarks without descriptors");
  nav::LandmarkSet set;
  set.method = static_cast<nav::LandmarkMethod>(msg.method);
  set.width_px = msg.panorama_width_px;
  set.height_px = msg.panorama_height_px;
  if (n == 0) return set;
  set.descriptors.create(static_cast<int>(n), msg.descriptor_length, CV_32F);
  set.landmarks.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    CheckFinite(msg.bearings_rad[i], "bearing");
    CheckFinite(msg.rows_px[i], "row");
    CheckFinite(msg.strengths[i], "strength");
    CheckFinite(msg.scales_px[i], "scale");
    if (msg.descriptors[i].size() != static_cast<size_t>(msg.descriptor_length)) {
      throw std::invalid_argument("landmark set: descriptor row " + std::to_string(i) + " has the wrong length");
    }
    float* row = set.descriptors.ptr<float>(static_cast<int>(i));
    for (int k = 0; k < msg.descriptor_length; ++k) {
      CheckFinite(msg.descriptors[i][k], "descriptor value");
      row[k] = msg.descriptors[i][k];
    }
    nav::Landmark l;
    l.x_px = static_cast<float>(panorama.ColumnOfBearing(msg.bearings_rad[i]));
    l.y_px = msg.rows_px[i];
    l.strength = msg.strengths[i];
    l.scale_px = msg.scales_px[i];
    set.landmarks.push_back(l);
  }
  return set;
}

nav::LandmarkExtractorConfig ReadLandmarkExtractor(const IniFile& ini) {
  nav::LandmarkExtractorConfig c;
  ExtractorTable().ReadKeys(ini, "landmarks", &c);
  VlineTable().ReadKeys(ini, "vline", &c);
  SiftTable().ReadKeys(ini, "sift", &c);
  SurfTable().ReadKeys(ini, "surf", &c);
  try {
    c.vline.Validate();
    c.sift.Validate();
    c.surf.Validate();
    c.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  return c;
}

nav::LandmarkHomingConfig ReadLandmarkHoming(const IniFile& ini, nav::LandmarkMethod method) {
  nav::LandmarkHomingConfig c;
  const auto keypoints = ReadMatching(ini, "matching");
  const auto lines = ReadMatching(ini, "vline_matching");
  c.match = method == nav::LandmarkMethod::kVline ? lines : keypoints;
  LandmarkAlvTable().ReadKeys(ini, "landmark_alv", &c);
  try {
    keypoints.Validate();
    lines.Validate();
    c.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  return c;
}

void PrintLandmarkExtractorKeys(std::ostream& out, const nav::LandmarkExtractorConfig& c) {
  ExtractorTable().Print(out, c);
}

void PrintLandmarkExtractorSections(std::ostream& out, const nav::LandmarkExtractorConfig& c) {
  out << "[vline]\n";
  VlineTable().Print(out, c);
  out << "[sift]\n";
  SiftTable().Print(out, c);
  out << "[surf]\n";
  SurfTable().Print(out, c);
}

void PrintLandmarkAlv(std::ostream& out, const nav::LandmarkHomingConfig& c) {
  out << "[landmark_alv]\n";
  LandmarkAlvTable().Print(out, c);
}

}  // namespace snapnav::glue
