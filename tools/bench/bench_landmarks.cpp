// bench-landmarks: the per-frame cost of homing with feature landmarks on one core (thesis
// 4.1-4.3): extraction, matching against the home set and the landmark ALV, per 720-column
// panorama, for vertical lines, SIFT (OpenCV) and SURF (snapnav's), and our SURF against
// OpenCV's SIFT on the same images. Medians of several runs; summary.json into --out.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <vector>

#include "bench_timing.hpp"
#include "homing_node.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace {

using namespace snapnav;

int Main(int argc, char** argv) {
  std::string scene_name = "indoor13", out_dir, config_path = SNAPNAV_CONFIG_DIR "/landmarks.ini",
              homing_path = SNAPNAV_CONFIG_DIR "/homing.ini";
  int runs = 7, frames = 10;
  glue::Flags flags("bench-landmarks",
                    "Per-frame cost of landmark homing on one core: extraction + matching + landmark ALV per\n"
                    "720-column panorama for vertical lines, SIFT and SURF (targets 10, 60 and 30 ms), and our SURF\n"
                    "against OpenCV's SIFT on the same images (target >= 2x). Medians of --runs runs.");
  flags.AddString("scene", &scene_name, "scene the test panoramas are rendered in");
  flags.AddString("config", &config_path, "landmarks config (extractors)");
  flags.AddString("homing-config", &homing_path, "homing config (matching, landmark ALV)");
  flags.AddInt("runs", &runs, "runs per figure");
  flags.AddInt("frames", &frames, "frames per run");
  flags.AddString("out", &out_dir, "folder for summary.json and bench.md");
  if (!flags.Parse(argc, argv)) return 0;
  if (runs < 1 || frames < 1) throw glue::FlagError("--runs and --frames must be >= 1");
  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), "");
  const auto homing = processes::HomingConfig::FromIni(glue::IniFile::Load(homing_path), "");
  const auto base = glue::ReadLandmarkExtractor(glue::IniFile::Load(config_path));
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  nav::sim::OmniRenderer renderer(scene, sim.camera);
  // Panoramas around the grid centre: the home and views up to 0.6 m away at other headings.
  const auto& grid = scene.grid;
  const Eigen::Vector2d centre = grid.Position(grid.nx / 2, grid.ny / 2);
  std::vector<cv::Mat> panos;
  for (int i = 0; i < 9; ++i) {
    const double r = i == 0 ? 0.0 : 0.2 + 0.05 * i, a = 0.7 * i;
    cv::Mat p;
    renderer.RenderPanorama({centre.x() + r * std::cos(a), centre.y() + r * std::sin(a), i == 0 ? 0.0 : 0.3 * i - 1.2},
                            {}, &p);
    panos.push_back(p);
  }
  struct Figure {
    nav::LandmarkMethod method;
    double extract_ms = 0, total_ms = 0, landmarks = 0, target_ms = 0;
  };
  std::vector<Figure> figures = {{nav::LandmarkMethod::kVline, 0, 0, 0, 10},
                                 {nav::LandmarkMethod::kSift, 0, 0, 0, 60},
                                 {nav::LandmarkMethod::kSurf, 0, 0, 0, 30}};
  for (auto& f : figures) {
    nav::LandmarkExtractorConfig c = base;
    c.method = f.method;
    nav::LandmarkHomer homer(homing.landmark_homing(f.method), homing.panorama);
    homer.SetHome(nav::ExtractLandmarks(panos[0], c));
    double count = 0;
    for (size_t i = 1; i < panos.size(); ++i) count += nav::ExtractLandmarks(panos[i], c).size();
    f.landmarks = count / (panos.size() - 1);
    auto view = [&](int i) -> const cv::Mat& { return panos[1 + i % (panos.size() - 1)]; };
    f.extract_ms = 1000 * bench::MedianSecondsPerCall(runs, frames, [&](int i) { (void)nav::ExtractLandmarks(view(i), c); });
    f.total_ms = 1000 * bench::MedianSecondsPerCall(runs, frames, [&](int i) {
      (void)homer.Home(nav::ExtractLandmarks(view(i), c));
    });
    std::cerr << "bench-landmarks: " << nav::LandmarkMethodName(f.method) << " done\n";
  }
  const double ratio = figures[1].total_ms / figures[2].total_ms;
  std::ostringstream md;
  md << std::fixed << std::setprecision(2) << "# Landmark homing per 720x120 panorama, one core (median of " << runs
     << " runs x " << frames << " frames, scene " << scene.name << ")\n\n"
     << "| method | landmarks/view | extraction [ms] | extraction + matching + ALV [ms] | target [ms] | met |\n"
     << "|---|---|---|---|---|---|\n";
  for (const auto& f : figures) {
    md << "| " << nav::LandmarkMethodName(f.method) << " | " << std::setprecision(1) << f.landmarks << std::setprecision(2)
       << " | " << f.extract_ms << " | " << f.total_ms << " | " << f.target_ms << " | "
       << (f.total_ms <= f.target_ms ? "yes" : "no") << " |\n";
  }
  md << "\nOur SURF against OpenCV's SIFT on the same panoramas (extraction + matching + ALV): " << ratio
     << "x faster (target >= 2x: " << (ratio >= 2 ? "met" : "missed") << ").\n";
  std::cout << md.str();
  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    std::ofstream(std::filesystem::path(out_dir) / "bench.md") << md.str();
    results::Json j;
    j["runs"] = runs;
    j["frames_per_run"] = frames;
    for (const auto& f : figures) {
      const std::string m = nav::LandmarkMethodName(f.method);
      j[m + "_landmarks_per_view"] = results::Rounded(f.landmarks, 4);
      j[m + "_extraction_ms"] = results::Rounded(f.extract_ms, 4);
      j[m + "_ms_per_frame"] = results::Rounded(f.total_ms, 4);
    }
    j["surf_speedup_vs_sift"] = results::Rounded(ratio, 4);
    results::WriteJsonFile((std::filesystem::path(out_dir) / "summary.json").string(), j);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
