// bench-sim: omni frames rendered per second at 640x480 (raw catadioptric and
// panorama) and laser scans per second, on the shipped indoor scene; the frames as
// messages: JPEG encode (sim) and decode (each subscriber) ms per frame and bytes per frame
// at several qualities, beside raw RGB8. Prints the median of several runs and writes
// summary.json into --out.
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <vector>

#include "bench_timing.hpp"
#include "results.hpp"
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
  std::string scene_name = "indoor13", out_dir, qualities_text = "75,80,85,90,95";
  int runs = 5, frames = 30;
  glue::Flags flags("bench-sim", "Rendering and laser throughput of the simulator on one core (median of --runs).");
  flags.AddString("scene", &scene_name, "scene");
  flags.AddInt("runs", &runs, "runs per figure");
  flags.AddInt("frames", &frames, "frames (and 10x scans) per run");
  flags.AddString("out", &out_dir, "folder for summary.json");
  flags.AddString("jpeg-qualities", &qualities_text, "JPEG qualities to time (comma-separated, 1..100)");
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
  // The realistic camera (housing, lens reflection, vignetting, colour cast, noise, soft rim,
  // robot parts, window, auto-exposure, its own JPEG, motion blur at the route's 0.3 m/s while
  // turning 0.3 rad/s) against the clean one: the goal is at most 30 % more time.
  nav::sim::OmniCameraOptions realistic_camera = config.camera;
  realistic_camera.optics = nav::sim::CameraOpticsPreset("realistic");
  realistic_camera.optics.jpeg_quality = config.jpeg_quality;  // as sim sets it
  nav::sim::OmniRenderer realistic(scene, realistic_camera);
  const nav::sim::CameraMotion moving{0.3, 0.3};
  const double realistic_fps =
      MedianRate(runs, frames, [&](int i) { realistic.RenderOmni(pose(i), {}, &image, moving); });
  // Clean and realistic interleaved per run, so that a busy machine slows both alike. Two ratios:
  // the image (the realistic camera's decoded JPEG against the clean render: what an evaluation
  // pays), and the published frame (render + JPEG message: the clean camera's frame encoded by sim,
  // the realistic camera's own JPEG bytes: what sim pays per frame).
  std::vector<double> ratios, frame_ratios;
  std::vector<uint8_t> camera_bytes;
  for (int r = 0; r < runs; ++r) {
    const double clean_s = bench::MedianSecondsPerCall(1, frames, [&](int i) { renderer.RenderOmni(pose(i), {}, &image); });
    const double real_s =
        bench::MedianSecondsPerCall(1, frames, [&](int i) { realistic.RenderOmni(pose(i), {}, &image, moving); });
    ratios.push_back(real_s / clean_s);
    const double clean_frame_s = bench::MedianSecondsPerCall(1, frames, [&](int i) {
      renderer.RenderOmni(pose(i), {}, &image);
      auto f = glue::ImageToFrame(image, omni_frame_t::JPEG, config.jpeg_quality);
      (void)f;
    });
    const double real_frame_s = bench::MedianSecondsPerCall(
        1, frames, [&](int i) { realistic.RenderOmni(pose(i), {}, &image, moving, &camera_bytes); });
    frame_ratios.push_back(real_frame_s / clean_frame_s);
  }
  std::sort(ratios.begin(), ratios.end());
  std::sort(frame_ratios.begin(), frame_ratios.end());
  const double realistic_ratio = ratios[ratios.size() / 2];
  const double realistic_frame_ratio = frame_ratios[frame_ratios.size() / 2];
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
  // The frames as messages: encoded by sim, decoded by every subscriber (glue's ImageToFrame and
  // FrameToImage, as the processes do), over 20 views of the scene.
  std::vector<cv::Mat> views(20);
  for (int i = 0; i < 20; ++i) renderer.RenderOmni(pose(7 * i), {}, &views[i]);
  struct Codec {
    std::string name;
    int8_t encoding;
    int quality;
    double encode_ms = 0, decode_ms = 0, bytes = 0;
  };
  std::vector<Codec> codecs{{"rgb8", omni_frame_t::RGB8, 0}};
  for (const auto& q : glue::SplitList(qualities_text)) {
    const int quality = std::stoi(q);
    if (quality < 1 || quality > 100) throw glue::FlagError("--jpeg-qualities: " + q + " is not in 1..100");
    codecs.push_back({"jpeg" + q, omni_frame_t::JPEG, quality});
  }
  for (auto& c : codecs) {
    std::vector<omni_frame_t> encoded;
    for (const auto& v : views) encoded.push_back(glue::ImageToFrame(v, c.encoding, std::max(c.quality, 1)));
    for (const auto& f : encoded) c.bytes += f.data_size / static_cast<double>(encoded.size());
    c.encode_ms = 1000 * bench::MedianSecondsPerCall(runs, frames, [&](int i) {
      auto f = glue::ImageToFrame(views[i % views.size()], c.encoding, std::max(c.quality, 1));
      (void)f;
    });
    c.decode_ms = 1000 * bench::MedianSecondsPerCall(runs, frames, [&](int i) {
      const cv::Mat m = glue::FrameToImage(encoded[i % encoded.size()]);
      (void)m;
    });
  }
  std::cout << "scene " << scene.name << ", one core, median of " << runs << " runs\n"
            << std::fixed << std::setprecision(1)
            << "  raw omni " << config.camera.omni_width_px << "x" << config.camera.omni_height_px
            << " frames/s:            " << raw_fps << "  (" << 1000 / raw_fps << " ms)\n"
            << "  raw omni, realistic camera frames/s: " << realistic_fps << "  (" << 1000 / realistic_fps
            << " ms; image: " << std::setprecision(2) << realistic_ratio
            << "x the clean camera's time; published JPEG frame: " << realistic_frame_ratio
            << "x; medians of interleaved runs; goal <= 1.30)\n"
            << std::setprecision(1)
            << "  raw omni + rgb8 message frames/s:    " << raw_msg_fps << "\n"
            << "  panorama " << config.camera.panorama.width_px << "x" << config.camera.panorama.height_px
            << " frames/s:            " << pano_fps << "  (" << 1000 / pano_fps << " ms)\n"
            << "  laser scans/s (" << config.laser.beams << " beams):         " << scans_ps << "\n"
            << "  frames as messages (shipped: " << glue::FrameEncodingName(config.encoding)
            << (config.encoding == omni_frame_t::JPEG ? " quality " + std::to_string(config.jpeg_quality) : std::string())
            << "), per 640x480 frame:\n"
            << "    encoding   bytes      encode ms  decode ms  at 10 Hz: encode + 5 subscribers' decodes (% of one core)\n";
  // ms per frame x 10 frames/s = ms per second of work; / 1000 ms x 100 %: the same number as a percentage.
  for (const auto& c : codecs) {
    std::cout << "    " << std::left << std::setw(10) << c.name << std::right << std::setw(8) << std::setprecision(0)
              << c.bytes << std::setprecision(2) << std::setw(12) << c.encode_ms << std::setw(11) << c.decode_ms
              << std::setprecision(1) << std::setw(12) << c.encode_ms + 5 * c.decode_ms << "\n";
  }
  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    results::Json j;
    j["scene"] = scene.name;
    j["runs"] = runs;
    j["omni_frames_per_second"] = results::Rounded(raw_fps, 2);
    j["omni_realistic_frames_per_second"] = results::Rounded(realistic_fps, 2);
    j["omni_realistic_time_ratio"] = results::Rounded(realistic_ratio, 3);
    j["omni_realistic_frame_time_ratio"] = results::Rounded(realistic_frame_ratio, 3);
    j["omni_message_frames_per_second"] = results::Rounded(raw_msg_fps, 2);
    j["panorama_frames_per_second"] = results::Rounded(pano_fps, 2);
    j["laser_scans_per_second"] = results::Rounded(scans_ps, 2);
    for (const auto& c : codecs) {
      j[c.name + "_frame_bytes"] = results::Rounded(c.bytes, 2);
      j[c.name + "_encode_ms"] = results::Rounded(c.encode_ms, 2);
      j[c.name + "_decode_ms"] = results::Rounded(c.decode_ms, 2);
    }
    results::WriteJsonFile((std::filesystem::path(out_dir) / "summary.json").string(), j);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
