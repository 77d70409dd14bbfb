// gridgen: renders an image database over a scene's grid (thesis Appendix A):
// one image per grid position at a random heading (or one given heading; plus optional extra
// random headings),
// as a folder of PNGs (one file per grid cell), a CSV of positions and
// headings, and an LCM log of the same frames with their ground-truth poses.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>

#include <opencv2/imgcodecs.hpp>

#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/log_writer.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

int Main(int argc, char** argv) {
  std::string config_path = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string scene_name = "indoor13";
  std::string out_dir;
  std::string heading_text = "random";
  int random_headings = 0;
  int seed = 1;
  bool panorama = false;
  bool no_raw = false;
  glue::Flags flags("gridgen",
                    "Renders a grid image database of a scene: OUT/images/<ix>_<iy>.png (raw omni images) with\n"
                    "their calibration OUT/camera.ini ([mirror], [panorama]),\n"
                    "OUT/panoramas/<ix>_<iy>.png with --panorama, OUT/positions.csv and OUT/grid.lcmlog.\n"
                    "Camera, mirror, panorama and image effects come from the sim config.");
  flags.AddString("config", &config_path, "sim config (camera, mirror, panorama, effects)");
  flags.AddString("scene", &scene_name, "scene name or file");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddString("heading-deg", &heading_text,
                  "robot heading at every grid position [deg], or random: each position its own (seeded), as a "
                  "robot placed by hand stands");
  flags.AddInt("random-headings", &random_headings, "extra images per position at random headings");
  flags.AddInt("seed", &seed, "seed for random headings and image effects");
  flags.AddBool("panorama", &panorama, "also write panoramas rendered directly");
  flags.AddBool("no-raw", &no_raw, "do not write raw omni images (panoramas only)");
  if (!flags.Parse(argc, argv)) return 0;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (no_raw && !panorama) throw glue::FlagError("--no-raw needs --panorama");
  if (random_headings < 0) throw glue::FlagError("--random-headings must be >= 0");
  const bool heading_random = heading_text == "random";
  double heading_deg = 0;
  if (!heading_random) {
    size_t used = 0;
    try {
      heading_deg = std::stod(heading_text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != heading_text.size() || !std::isfinite(heading_deg)) {
      throw glue::FlagError("--heading-deg: '" + heading_text + "' is neither a number of degrees nor random");
    }
  }

  auto config = processes::SimConfig::FromIni(glue::IniFile::Load(config_path), "");
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  if (scene.grid.nx < 1 || scene.grid.ny < 1) throw std::runtime_error("scene '" + scene.name + "' defines no grid");
  nav::sim::OmniRenderer renderer(scene, config.camera);
  std::mt19937_64 rng(static_cast<uint64_t>(seed));
  std::uniform_real_distribution<double> random_heading(-M_PI, M_PI);

  fs::create_directories(fs::path(out_dir) / "images");
  if (panorama) fs::create_directories(fs::path(out_dir) / "panoramas");
  if (!no_raw) {
    // The raw images' calibration (the one their frames carry), so that the folder can be read
    // back on its own (eval homing --grid, eval localization --grid).
    std::ofstream camera(fs::path(out_dir) / "camera.ini");
    camera << "; the calibration of images/ (gridgen, camera preset " << config.camera_preset << ")\n";
    glue::PrintMirrorConfig(camera, config.camera.ReportedMirror());
    camera << "\n";
    glue::PrintPanoramaConfig(camera, config.camera.panorama);
  }
  std::ofstream csv(fs::path(out_dir) / "positions.csv");
  csv << "file,ix,iy,x_m,y_m,heading_rad,utime\n" << std::setprecision(9);
  glue::LogWriter log((fs::path(out_dir) / "grid.lcmlog").string());

  const int per_cell = 1 + random_headings;
  const int total = scene.grid.nx * scene.grid.ny * per_cell;
  int done = 0;
  cv::Mat image;
  for (int iy = 0; iy < scene.grid.ny; ++iy) {
    for (int ix = 0; ix < scene.grid.nx; ++ix) {
      const Eigen::Vector2d p = scene.grid.Position(ix, iy);
      for (int k = 0; k < per_cell; ++k) {
        const double heading = (k == 0 && !heading_random) ? heading_deg * M_PI / 180 : random_heading(rng);
        const nav::Pose2 pose{p.x(), p.y(), heading};
        const std::string stem = std::to_string(ix) + "_" + std::to_string(iy) + (k ? "_r" + std::to_string(k) : "");
        const int64_t utime = config.start_utime + static_cast<int64_t>(done) * 100000;
        auto emit = [&](bool raw) {
          if (raw) renderer.RenderOmni(pose, {}, &image); else renderer.RenderPanorama(pose, {}, &image);
          nav::sim::ApplyImageEffects(config.effects, rng, &image);
          const fs::path file = fs::path(out_dir) / (raw ? "images" : "panoramas") / (stem + ".png");
          if (!cv::imwrite(file.string(), image)) throw std::runtime_error("cannot write " + file.string());
          omni_frame_t f = glue::ImageToFrame(image, omni_frame_t::PNG);
          f.utime = utime;
          f.sensor_name = "gridgen";
          f.kind = raw ? omni_frame_t::RAW_OMNI : omni_frame_t::PANORAMA;
          if (raw) glue::SetMirror(config.camera.ReportedMirror(), &f); else glue::SetPanorama(config.camera.panorama, &f);
          log.Write(raw ? channels::kOmniFrame : channels::kPanorama, f);
          return file.filename().string();
        };
        // The pose first: a process that looks up each frame's pose when the frame arrives
        // (placecells --mode explore on file://grid.lcmlog) finds it.
        log.Write(channels::kPoseGroundTruth,
                  glue::ToPoseMsg(utime, "ground_truth", "map", pose, Eigen::Matrix3d::Zero()));
        std::string name;
        if (!no_raw) name = "images/" + emit(true);
        if (panorama) {
          const std::string pano = "panoramas/" + emit(false);
          if (name.empty()) name = pano;
        }
        csv << name << "," << ix << "," << iy << "," << p.x() << "," << p.y() << "," << heading << "," << utime << "\n";
        if (++done % 20 == 0 || done == total) std::cerr << "gridgen: " << done << "/" << total << " positions\r" << std::flush;
      }
    }
  }
  std::cerr << "\ngridgen: scene '" << scene.name << "', " << scene.grid.nx << "x" << scene.grid.ny << " grid, "
            << scene.grid.spacing_m << " m spacing: " << done << " positions written to " << out_dir << " ("
            << log.events() << " log events)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
