#include "snapnav/glue/landmarks.hpp"

#include <cmath>
#include <stdexcept>

namespace snapnav::glue {
namespace {

constexpr double kDeg = M_PI / 180.0;

void CheckFinite(float v, const char* what) {
  if (!std::isfinite(v)) throw std::invalid_argument(std::string("landmark set: non-finite ") + what);
}

nav::MatchOptions ReadMatching(const IniFile& ini, const std::string& section) {
  nav::MatchOptions m;
  MatchOptionTable().ReadKeys(ini, section, &m);
  return m;
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
  c.method = ReadChoice<nav::LandmarkMethod>(
      ini, "landmarks", "method",
      {{"vline", nav::LandmarkMethod::kVline}, {"sift", nav::LandmarkMethod::kSift}, {"surf", nav::LandmarkMethod::kSurf}});
  c.equalize_histogram = ini.GetBool("landmarks", "equalize_histogram");
  auto& v = c.vline;
  v.blur_sigma_px = ini.GetDouble("vline", "blur_sigma_px");
  v.canny_low = ini.GetDouble("vline", "canny_low");
  v.canny_high = ini.GetDouble("vline", "canny_high");
  v.hough_threshold = ini.GetInt("vline", "hough_threshold");
  v.min_segment_px = ini.GetDouble("vline", "min_segment_px");
  v.max_gap_px = ini.GetDouble("vline", "max_gap_px");
  v.max_tilt_deg = ini.GetDouble("vline", "max_tilt_deg");
  v.cluster_px = ini.GetDouble("vline", "cluster_px");
  v.min_line_px = ini.GetDouble("vline", "min_line_px");
  v.window_px = ini.GetInt("vline", "window_px");
  v.bins = ini.GetInt("vline", "bins");
  v.divided = ini.GetBool("vline", "divided");
  auto& s = c.sift;
  s.max_features = ini.GetInt("sift", "max_features");
  s.octave_layers = ini.GetInt("sift", "octave_layers");
  s.contrast_threshold = ini.GetDouble("sift", "contrast_threshold");
  s.edge_threshold = ini.GetDouble("sift", "edge_threshold");
  s.sigma = ini.GetDouble("sift", "sigma");
  auto& u = c.surf;
  u.hessian_threshold = ini.GetDouble("surf", "hessian_threshold");
  u.octaves = ini.GetInt("surf", "octaves");
  u.intervals = ini.GetInt("surf", "intervals");
  u.init_sample = ini.GetInt("surf", "init_sample");
  u.upright = ini.GetBool("surf", "upright");
  u.max_keypoints = ini.GetInt("surf", "max_keypoints");
  c.surf_pad_px = ini.GetInt("surf", "pad_px");
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
  auto& a = c.alv;
  a.variant = ReadChoice<nav::AlvVariant>(
      ini, "landmark_alv", "variant",
      {{"unit", nav::AlvVariant::kUnit}, {"weighted", nav::AlvVariant::kWeighted}, {"scale", nav::AlvVariant::kScale}});
  a.weight = ReadChoice<nav::MatchWeight>(ini, "landmark_alv", "weight",
                                          {{"score", nav::MatchWeight::kScore}, {"distance", nav::MatchWeight::kDistance}});
  a.top_n = ini.GetInt("landmark_alv", "top_n");
  a.difference = ReadChoice<nav::AlvDifference>(ini, "landmark_alv", "difference",
                                                {{"current_minus_home", nav::AlvDifference::kCurrentMinusHome},
                                                 {"home_minus_current", nav::AlvDifference::kHomeMinusCurrent}});
  a.max_scale_ratio = ini.GetDouble("landmark_alv", "max_scale_ratio");
  a.min_landmarks = ini.GetInt("landmark_alv", "min_landmarks");
  a.consensus = ini.GetBool("landmark_alv", "consensus");
  a.consensus_window_rad = ini.GetDouble("landmark_alv", "consensus_window_deg") * kDeg;
  a.rotation_refine_rad = ini.GetDouble("landmark_alv", "rotation_refine_deg") * kDeg;
  c.rotation = ReadChoice<nav::RotationSource>(ini, "landmark_alv", "rotation",
                                               {{"matches", nav::RotationSource::kMatches}, {"none", nav::RotationSource::kNone}});
  c.rotation_window_rad = ini.GetDouble("landmark_alv", "rotation_window_deg") * kDeg;
  try {
    keypoints.Validate();
    lines.Validate();
    c.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  return c;
}

void PrintLandmarkExtractorSections(std::ostream& out, const nav::LandmarkExtractorConfig& c) {
  const auto& v = c.vline;
  const auto& s = c.sift;
  const auto& u = c.surf;
  const auto b = [](bool x) { return x ? "true" : "false"; };
  out << "[vline]\nblur_sigma_px = " << v.blur_sigma_px << "\ncanny_low = " << v.canny_low
      << "\ncanny_high = " << v.canny_high << "\nhough_threshold = " << v.hough_threshold
      << "\nmin_segment_px = " << v.min_segment_px << "\nmax_gap_px = " << v.max_gap_px
      << "\nmax_tilt_deg = " << v.max_tilt_deg << "\ncluster_px = " << v.cluster_px << "\nmin_line_px = " << v.min_line_px
      << "\nwindow_px = " << v.window_px << "\nbins = " << v.bins << "\ndivided = " << b(v.divided) << "\n"
      << "[sift]\nmax_features = " << s.max_features << "\noctave_layers = " << s.octave_layers
      << "\ncontrast_threshold = " << s.contrast_threshold << "\nedge_threshold = " << s.edge_threshold
      << "\nsigma = " << s.sigma << "\n"
      << "[surf]\nhessian_threshold = " << u.hessian_threshold << "\noctaves = " << u.octaves
      << "\nintervals = " << u.intervals << "\ninit_sample = " << u.init_sample << "\nupright = " << b(u.upright)
      << "\nmax_keypoints = " << u.max_keypoints << "\npad_px = " << c.surf_pad_px << "\n";
}

}  // namespace snapnav::glue
