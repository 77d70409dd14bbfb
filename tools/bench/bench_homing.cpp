// bench-homing: the per-frame costs of HOG homing on one core (thesis chapter 3):
// unwrap of a 640x480 catadioptric frame (precomputed map, against recomputing the map
// per frame as the baseline), and the HOG-ALV homing vector from a 720-column panorama
// (gradients, compass, ALV), against the thesis configuration as the baseline.
// Prints medians of several runs and writes summary.json into --out.
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "bench_timing.hpp"
#include "homing_node.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/homing/unwrap.hpp"

namespace {

using namespace snapnav;

template <class Fn>
double MedianMs(int runs, int per_run, Fn&& fn) {
  return 1000.0 * bench::MedianSecondsPerCall(runs, per_run, fn);
}

int Main(int argc, char** argv) {
  std::string scene_name = "indoor13", out_dir, config_path = SNAPNAV_CONFIG_DIR "/homing.ini";
  int runs = 7, frames = 20;
  glue::Flags flags("bench-homing",
                    "Per-frame cost of HOG homing on one core: unwrap (640x480 -> 720x120) and the HOG-ALV\n"
                    "homing vector, medians of --runs runs, with baselines measured in the same process.");
  flags.AddString("scene", &scene_name, "scene the test images are rendered in");
  flags.AddString("config", &config_path, "homing config");
  flags.AddInt("runs", &runs, "runs per figure");
  flags.AddInt("frames", &frames, "frames per run");
  flags.AddString("out", &out_dir, "folder for summary.json");
  if (!flags.Parse(argc, argv)) return 0;
  if (runs < 1 || frames < 1) throw glue::FlagError("--runs and --frames must be >= 1");
  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), "");
  const auto homing = processes::HomingConfig::FromIni(glue::IniFile::Load(config_path), "");
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  nav::sim::OmniRenderer renderer(scene, sim.camera);
  const auto& cam = sim.camera;

  // Test images: a few poses around the scene's start.
  std::vector<cv::Mat> raws, panos;
  for (int i = 0; i < 8; ++i) {
    const nav::Pose2 pose{scene.start_pose.x() + 0.1 * (i % 4), scene.start_pose.y() + 0.1 * (i / 4), 0.4 * i};
    cv::Mat raw, pano;
    renderer.RenderOmni(pose, {}, &raw);
    raws.push_back(raw);
  }
  const cv::Size raw_size(cam.omni_width_px, cam.omni_height_px);
  const nav::Unwrapper unwrapper(cam.mirror, cam.panorama, raw_size);
  for (const auto& r : raws) {
    cv::Mat p;
    unwrapper.Unwrap(r, &p);
    panos.push_back(p);
  }
  cv::Mat out;
  const double unwrap_ms = MedianMs(runs, frames, [&](int i) { unwrapper.Unwrap(raws[i % raws.size()], &out); });
  const double unwrap_rebuild_ms = MedianMs(runs, std::max(1, frames / 4), [&](int i) {
    const nav::Unwrapper fresh(cam.mirror, cam.panorama, raw_size);  // the map computed per frame
    fresh.Unwrap(raws[i % raws.size()], &out);
  });

  nav::HogHomer homer(homing.homing, homing.panorama);
  homer.SetHome(panos[0]);
  const double homing_ms = MedianMs(runs, frames, [&](int i) { (void)homer.Home(panos[1 + i % (panos.size() - 1)]); });
  nav::HogHomingConfig no_compass = homing.homing;
  no_compass.use_compass = false;
  nav::HogHomer homer_nc(no_compass, homing.panorama);
  homer_nc.SetHome(panos[0]);
  const double no_compass_ms = MedianMs(runs, frames, [&](int i) { (void)homer_nc.Home(panos[1 + i % (panos.size() - 1)]); });
  // The thesis configuration: the compass and the ALV on one descriptor (40 px cells, 8 bins, all).
  nav::HogHomingConfig thesis = homing.homing;
  thesis.hog.cell_size_px = 40;
  thesis.hog.bins = 8;
  thesis.hog.range = nav::OrientationRange::kAll;
  thesis.compass_hog = thesis.hog;
  nav::HogHomer homer_thesis(thesis, homing.panorama);
  homer_thesis.SetHome(panos[0]);
  const double thesis_ms = MedianMs(runs, frames, [&](int i) { (void)homer_thesis.Home(panos[1 + i % (panos.size() - 1)]); });
  cv::Mat gray;
  cv::cvtColor(panos[1], gray, cv::COLOR_BGR2GRAY);
  const double gradients_ms = MedianMs(runs, frames, [&](int) { (void)nav::ComputeGradients(gray); });

  std::cout << std::fixed << std::setprecision(3) << "bench-homing: one core, median of " << runs << " runs x " << frames
            << " frames\n"
            << "  unwrap " << raw_size.width << "x" << raw_size.height << " -> " << cam.panorama.width_px << "x"
            << cam.panorama.height_px << ":              " << unwrap_ms << " ms  (target <= 1 ms)\n"
            << "    baseline, map rebuilt per frame:      " << unwrap_rebuild_ms << " ms  (ratio "
            << std::setprecision(1) << unwrap_rebuild_ms / unwrap_ms << "x)\n"
            << std::setprecision(3) << "  HOG-ALV homing vector (shipped config): " << homing_ms
            << " ms  (target <= 2 ms)\n"
            << "    of which gradients:                   " << gradients_ms << " ms\n"
            << "    without the compass:                  " << no_compass_ms << " ms\n"
            << "    thesis configuration (one descriptor): " << thesis_ms << " ms  (ratio shipped/thesis "
            << std::setprecision(2) << homing_ms / thesis_ms << ")\n";
  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    results::Json j;
    j["runs"] = runs;
    j["frames_per_run"] = frames;
    j["unwrap_ms"] = results::Rounded(unwrap_ms, 4);
    j["unwrap_map_per_frame_ms"] = results::Rounded(unwrap_rebuild_ms, 4);
    j["hog_homing_ms"] = results::Rounded(homing_ms, 4);
    j["hog_gradients_ms"] = results::Rounded(gradients_ms, 4);
    j["hog_homing_without_compass_ms"] = results::Rounded(no_compass_ms, 4);
    j["hog_homing_thesis_config_ms"] = results::Rounded(thesis_ms, 4);
    results::WriteJsonFile((std::filesystem::path(out_dir) / "summary.json").string(), j);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
