// calibrate-mirror: the [mirror] calibration of an omnidirectional camera from its images
// (docs/calibration.md): the mirror's rim by a robust circle fit on edges, the inner radius at
// the camera's own reflection, the elevations from the mirror's profile, and the mask of the
// robot's own parts (from frames taken while the robot moves, or a mask image given).
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "calibrate_mirror.hpp"
#include "frame_source.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/homing/mirror_calibration.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
constexpr double kDeg = M_PI / 180;

std::vector<cv::Mat> DeviceFrames(int device, int count) {
  processes::FrameSourceOptions o;
  o.source.kind = processes::SourceKind::kDevice;
  o.source.device_index = device;
  auto source = processes::OpenFrameSource(o);
  std::vector<cv::Mat> frames;
  std::string error;
  int failures = 0;
  while (static_cast<int>(frames.size()) < count) {
    cv::Mat image;
    const auto status = source->Read(&image, &error);
    if (status == processes::ReadStatus::kEnd) break;
    if (status == processes::ReadStatus::kFailed) {
      if (++failures > 50) throw std::runtime_error(source->description() + ": " + error);
      continue;
    }
    frames.push_back(image.clone());
  }
  if (frames.empty()) throw std::runtime_error(source->description() + " gave no frames");
  return frames;
}

cv::Mat ReadImage(const std::string& path) {
  if (!fs::exists(path)) throw std::runtime_error(path + ": no such file");
  if (fs::is_directory(path)) throw std::runtime_error(path + ": a folder, not an image");
  cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) throw std::runtime_error(path + ": not an image OpenCV can read (PNG, JPEG, ...)");
  return image;
}

// The folder an output file goes into, made when it does not exist (as every tool's --out).
void MakeParentFolder(const std::string& path) {
  const fs::path parent = fs::absolute(path).parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw std::runtime_error("cannot make the folder " + parent.string() + " for " + path + ": " + ec.message());
}

int Main(int argc, char** argv) {
  int device = -1, frames_wanted = 0;
  std::string log_path, channel = "OMNI_FRAME", out_path, png_path, mask_path, mask_out;
  std::string template_path = SNAPNAV_CONFIG_DIR "/omni_camera.ini";
  double rim_deg = NAN, centre_deg = NAN, min_radius_frac = -1, max_radius_frac = -1, max_std = 0,
         holder_max_frac = -1;
  int grow_px = 2;
  glue::Flags flags(
      "calibrate-mirror",
      "The [mirror] calibration of a catadioptric camera from its images: the mirror's rim (a robust\n"
      "circle fit on the image's edges), the inner radius (the camera's own reflection), the elevations\n"
      "from the mirror's profile, and the mask of the robot's own parts (pixels that stay the same over\n"
      "frames while the robot moves: --log or --device; or a mask image: --mask). Prints the section and\n"
      "the fit's residual; warns when the fit is poor. docs/calibration.md.\n"
      "  calibrate-mirror IMAGE [--out FILE.ini] [--png OVERLAY.png]\n"
      "  calibrate-mirror --log LOG [--channel OMNI_FRAME] [--frames 60] ...\n"
      "  calibrate-mirror --device N [--frames 30] ...");
  flags.AllowPositional("IMAGE", "a raw catadioptric image (PNG, JPEG, ...)");
  flags.AddInt("device", &device, "camera device N (/dev/videoN): --frames frames from it", "");
  flags.AddString("log", &log_path, "an LCM log: --frames raw frames of --channel, spread over it");
  flags.AddString("channel", &channel, "--log: the channel of the raw omni frames");
  flags.AddInt("frames", &frames_wanted, "frames to use (--log: 60, --device: 30)");
  flags.AddString("mask", &mask_path, "a mask image of the robot's parts (black = masked) instead of finding one");
  flags.AddString("config", &template_path,
                  "the config --out copies, its [mirror] replaced (and its profile the default)");
  flags.AddString("out", &out_path,
                  "write the config with the calibrated [mirror] here (the mask as FILE_mask.png beside it)");
  flags.AddString("mask-out", &mask_out, "where the found mask goes (default: beside --out)");
  flags.AddString("png", &png_path, "write an overlay to check by eye: the rim, the inner circle, the mask tinted");
  flags.AddDouble("elevation-rim-deg", &rim_deg,
                  "the mirror's profile: elevation seen at the rim [deg] (default: --config's)");
  flags.AddDouble("elevation-centre-deg", &centre_deg,
                  "the mirror's profile: elevation of the linear model at the centre [deg] (default: --config's)");
  flags.AddDouble("min-radius-frac", &min_radius_frac, "smallest rim radius, of the image's smaller side (default 0.15)");
  flags.AddDouble("max-radius-frac", &max_radius_frac, "largest rim radius, of the image's smaller side (default 0.75)");
  flags.AddDouble("holder-max-frac", &holder_max_frac,
                  "where the band inside the strongest circle is flat (a ring holding the mirror), look for the "
                  "mirror's edge this far inside it, of its radius (default 0.12; 0: off)");
  flags.AddDouble("mask-max-std", &max_std,
                  "mask: grey-level std. dev. below which a pixel is the robot's (0: 3x the noise)");
  flags.AddInt("mask-grow-px", &grow_px, "mask: margin added around the robot's parts [px]");
  if (!flags.Parse(argc, argv)) return 0;
  const int sources = static_cast<int>(!flags.positional().empty()) + (device >= 0) + !log_path.empty();
  if (sources != 1 || flags.positional().size() > 1) {
    throw glue::FlagError("give one input: IMAGE, --device N or --log LOG (see --help)");
  }

  // The profile: the template's [mirror], or the flags.
  const auto ini = glue::IniFile::Load(template_path);
  nav::MirrorProfile profile;
  if (ini.Has("mirror", "elevation_outer_deg")) profile = nav::MirrorProfile::FromMirror(glue::ReadMirrorConfig(ini));
  if (!std::isnan(rim_deg)) profile.elevation_rim_rad = rim_deg * kDeg;
  if (!std::isnan(centre_deg)) profile.elevation_centre_rad = centre_deg * kDeg;
  try {
    profile.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }

  std::vector<cv::Mat> frames;
  std::string input;
  if (!log_path.empty()) {
    frames = calibrate::LogFrames(log_path, channel, frames_wanted > 0 ? frames_wanted : 60);
    input = log_path + " (" + std::to_string(frames.size()) + " frames of " + channel + ")";
  } else if (device >= 0) {
    frames = DeviceFrames(device, frames_wanted > 0 ? frames_wanted : 30);
    input = "device " + std::to_string(device) + " (" + std::to_string(frames.size()) + " frames)";
  } else {
    frames.push_back(ReadImage(flags.positional()[0]));
    input = flags.positional()[0];
  }
  const cv::Mat mean = calibrate::MeanImage(frames);

  nav::MirrorSearchOptions search;
  if (min_radius_frac > 0) search.min_radius_frac = min_radius_frac;
  if (max_radius_frac > 0) search.max_radius_frac = max_radius_frac;
  if (holder_max_frac != -1) search.holder_max_frac = holder_max_frac;
  std::string why;
  const auto cal = nav::CalibrateMirror(mean, profile, search, &why);
  if (!cal) throw std::runtime_error(input + ": " + why);

  // The mask: given, or from the frames.
  cv::Mat mask;
  std::string mask_note;
  if (!mask_path.empty()) {
    mask = glue::LoadMask(mask_path, mean.size());
    mask_note = "given (" + mask_path + ")";
  } else if (frames.size() >= 3) {
    nav::OcclusionOptions oo;
    oo.max_std_grey = max_std;
    oo.grow_px = grow_px;
    nav::OcclusionStats st;
    mask = nav::SelfOcclusionMask(frames, cal->mirror, oo, &st);
    std::ostringstream s;
    s << std::fixed << std::setprecision(1) << 100 * st.masked_fraction << " % of the ring, from " << st.frames
      << " frames (noise " << st.noise_grey << " grey levels, threshold " << st.threshold_grey
      << ", the scene's median change " << st.scene_median_std << ")";
    mask_note = s.str();
    if (st.scene_median_std < 2 * st.threshold_grey) {
      std::cerr << "calibrate-mirror: warning: the scene hardly changes over the frames (median std. dev. "
                << st.scene_median_std << "): the robot must move while recording, or the mask takes the scene too\n";
    }
  } else {
    mask_note = "none (one image: record frames while the robot moves, --log or --device, or give --mask)";
  }

  const nav::MirrorModel& m = cal->mirror;
  std::cout << std::fixed << std::setprecision(2) << "calibrate-mirror: " << input << " (" << mean.cols << "x"
            << mean.rows << ")\n"
            << "rim:   centre (" << cal->rim.center_x_px << ", " << cal->rim.center_y_px << ") px, radius "
            << cal->rim.radius_px << " px; residual " << std::setprecision(3) << cal->rim.rms_px << " px RMS over "
            << cal->rim.inliers << " edge points; inlier fraction " << std::setprecision(2) << cal->rim.inlier_fraction
            << "; seen over " << std::setprecision(0) << 100 * cal->rim.coverage << " % of its circumference\n"
            << std::setprecision(2);
  if (cal->inner) {
    std::cout << "inner: the camera's reflection, radius " << cal->inner->radius_px << " px (residual "
              << std::setprecision(3) << cal->inner->rms_px << " px RMS, seen over " << std::setprecision(0)
              << 100 * cal->inner->coverage << " %); the useful ring starts at " << std::setprecision(2)
              << m.inner_radius_px << " px\n";
  } else {
    std::cout << "inner: no reflection of the camera found; the useful ring starts at " << m.inner_radius_px << " px\n";
  }
  std::cout << "elevations: " << m.elevation_inner_rad / kDeg << " deg at the inner radius, "
            << m.elevation_outer_rad / kDeg << " deg at the rim (profile: " << profile.elevation_rim_rad / kDeg
            << " deg at the rim, " << profile.elevation_centre_rad / kDeg << " deg at the centre)\n"
            << "mask:  " << mask_note << "\n";
  for (const auto& w : cal->warnings) std::cerr << "calibrate-mirror: warning: " << w << "\n";

  std::string mask_file;
  if (!mask.empty()) {
    if (!mask_path.empty()) {
      mask_file = fs::absolute(mask_path).lexically_normal().string();
    } else if (!mask_out.empty() || !out_path.empty()) {
      mask_file = !mask_out.empty() ? mask_out : (fs::path(out_path).replace_extension().string() + "_mask.png");
      MakeParentFolder(mask_file);
      if (!cv::imwrite(mask_file, mask)) throw std::runtime_error("cannot write " + mask_file);
      std::cout << "wrote " << mask_file << "\n";
    }
  }
  // The mask key as the config will read it: relative to the config's folder when beside it.
  std::string mask_key = mask_file;
  if (!mask_file.empty() && !out_path.empty()) {
    const fs::path rel = fs::absolute(mask_file).lexically_relative(fs::absolute(out_path).parent_path());
    if (!rel.empty() && rel.string().rfind("..", 0) != 0) mask_key = rel.string();
  }
  std::cout << "\n";
  glue::PrintMirrorConfig(std::cout, m, mask_key, "mirror");
  if (!out_path.empty()) {
    std::ifstream in(template_path);
    std::stringstream text;
    text << in.rdbuf();
    bool mask_written = false;
    const std::string out_text = calibrate::WithMirrorSection(text.str(), m, mask_key, &mask_written);
    MakeParentFolder(out_path);
    std::ofstream out(out_path);
    out << out_text;
    if (!out) throw std::runtime_error("cannot write " + out_path);
    std::cout << "wrote " << out_path << " (" << template_path << " with this [mirror])\n";
    if (!mask_written && !mask_key.empty()) {
      std::cerr << "calibrate-mirror: note: " << template_path << "'s [mirror] has no mask key: the mask is not in "
                << out_path
                << " (the processes that read frames take it: homing, landmarks, placecells, ratslam, viewer)\n";
    }
  }
  if (!png_path.empty()) {
    MakeParentFolder(png_path);
    if (!cv::imwrite(png_path, nav::DrawCalibrationOverlay(mean, m, mask, cal->holder)))
      throw std::runtime_error("cannot write " + png_path);
    std::cout << "wrote " << png_path << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
