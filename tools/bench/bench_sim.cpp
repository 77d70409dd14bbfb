// bench-sim: omni frames rendered per second at 640x480 (raw catadioptric and
// panorama) and laser scans per second, on the shipped indoor scene. Prints the
// median of several runs and writes summary.json into --out.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <vector>

#include "bench_timing.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace {

using namespace snapnav;

template <class Fn>
double MedianRate(int runs, int per_run, Fn&& fn) {
  return 1.0 / bench::MedianSecondsPerCall(runs, per_run, fn);
}

int Main(int argc, char** argv) {
  std::string scene_name = "indoor13", out_dir;
  int runs = 5, frames = 30;
  glue::Flags flags("bench-sim", "Rendering and laser throughput of the simulator on one core (median of --runs).");
  flags.AddString("scene", &scene_name, "scene");
  flags.AddInt("runs", &runs, "runs per figure");
  flags.AddInt("frames", &frames, "frames (and 10x scans) per run");
  flags.AddString("out", &out_dir, "folder for summary.json");
  if (!flags.Parse(argc, argv)) return 0;
  const auto config = processes::SimConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), "");
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  nav::sim::OmniRenderer renderer(scene, config.camera);
  nav::sim::World world(scene, config.drive_options, config.laser, 1);
  cv::Mat image;
  auto pose = [&](int i) {
    return nav::Pose2{scene.start_pose.x() + 0.01 * (i % 50), scene.start_pose.y() + 0.005 * (i % 30), 0.05 * i};
  };
  const double raw_fps = MedianRate(runs, frames, [&](int i) { renderer.RenderOmni(pose(i), {}, &image); });
  const double raw_msg_fps = MedianRate(runs, frames, [&](int i) {
    renderer.RenderOmni(pose(i), {}, &image);
    auto f = glue::ImageToFrame(image, omni_frame_t::RGB8);
    (void)f;
  });
  const double pano_fps = MedianRate(runs, frames, [&](int i) { renderer.RenderPanorama(pose(i), {}, &image); });
  const double scans_ps = MedianRate(runs, frames * 10, [&](int i) {
    world.SetTruePose(pose(i));
    auto r = world.Scan();
    (void)r;
  });
  std::cout << "scene " << scene.name << ", one core, median of " << runs << " runs\n"
            << std::fixed << std::setprecision(1)
            << "  raw omni " << config.camera.omni_width_px << "x" << config.camera.omni_height_px
            << " frames/s:            " << raw_fps << "  (" << 1000 / raw_fps << " ms)\n"
            << "  raw omni + rgb8 message frames/s:    " << raw_msg_fps << "\n"
            << "  panorama " << config.camera.panorama.width_px << "x" << config.camera.panorama.height_px
            << " frames/s:            " << pano_fps << "  (" << 1000 / pano_fps << " ms)\n"
            << "  laser scans/s (" << config.laser.beams << " beams):         " << scans_ps << "\n";
  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    std::ofstream json(std::filesystem::path(out_dir) / "summary.json");
    json << std::fixed << std::setprecision(2) << "{\n  \"scene\": \"" << scene.name << "\",\n  \"runs\": " << runs
         << ",\n  \"omni_frames_per_second\": " << raw_fps << ",\n  \"omni_message_frames_per_second\": " << raw_msg_fps
         << ",\n  \"panorama_frames_per_second\": " << pano_fps << ",\n  \"laser_scans_per_second\": " << scans_ps
         << "\n}\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
