// bench-ratslam (./snapnav bench ratslam): the cost of RatSLAM's updates on one core, with the
// shipped configuration (config/ratslam.ini), at several map sizes.
//
// Views are real: grey panoramas of a simulated scene (--scene, default the corridor) rendered at
// random poses on its route (positions along the route's legs, any heading), so the stored templates
// are as alike as a building's. The map grows by feeding views (each either a new template or a
// familiar one) with 5 odometry steps of 1.2 cm between views (50 Hz odometry, 10 Hz frames at
// 0.3 m/s). At each size (templates and experiences) the timing runs on a copy of that RatSlam:
// a cycle is one view (a pose 1-2 cm and 1 degree off a stored one, so the map keeps its size)
// and the 5 odometry steps after it (the pose-cell step, the experience map action and its
// relaxation). Figures: median over --runs of the mean ms per OnImage and per OnOdometry, the ms
// per second of sensor data at 10 Hz frames and 50 Hz odometry (the share of a core), and the pose-
// cell step alone (a settled packet; and after familiar views injected energy).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "bench_timing.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/ratslam_options.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

constexpr int kOdometryPerFrame = 5;     // 50 Hz odometry, 10 Hz frames
constexpr double kStepM = 0.3 / 50;      // 0.3 m/s
constexpr double kFrameHz = 10, kOdometryHz = 50;

// A random pose on the route: a random point of a random leg, a random heading.
nav::Pose2 RandomPose(const std::vector<Eigen::Vector2d>& route, std::mt19937_64& rng) {
  std::uniform_int_distribution<size_t> leg(0, route.size() - 1);
  std::uniform_real_distribution<double> u(0, 1), heading(-M_PI, M_PI);
  const size_t i = leg(rng);
  const Eigen::Vector2d p = route[i] + u(rng) * (route[(i + 1) % route.size()] - route[i]);
  return {p.x(), p.y(), heading(rng)};
}

int Main(int argc, char** argv) {
  std::string out_dir = "logs/bench-ratslam", scene_name = "corridor";
  std::string ratslam_config = SNAPNAV_CONFIG_DIR "/ratslam.ini", sim_config = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string sizes_text = "100,500,2000";
  int runs = 5, cycles = 40;
  glue::Flags flags("bench-ratslam",
                    "RatSLAM's cost per update on one core (run it under taskset -c 0): ms per OnImage and per\n"
                    "OnOdometry at several map sizes, with real panoramas of a simulated scene and the shipped\n"
                    "[ratslam] configuration; the share of a core at 10 Hz frames and 50 Hz odometry.\n"
                    "Writes bench.json and bench.md into --out.");
  flags.AddString("out", &out_dir, "output folder");
  flags.AddString("scene", &scene_name, "scene whose route the views are rendered on");
  flags.AddString("ratslam-config", &ratslam_config, "RatSLAM configuration (its [ratslam] section)");
  flags.AddString("config", &sim_config, "simulator configuration (camera)");
  flags.AddString("sizes", &sizes_text, "map sizes to time at, in templates (comma-separated, increasing)");
  flags.AddInt("runs", &runs, "timing runs per figure (the median is reported)");
  flags.AddInt("cycles", &cycles, "view + odometry cycles per run");
  if (!flags.Parse(argc, argv)) return 0;
  if (runs < 1 || cycles < 1) throw glue::FlagError("--runs and --cycles must be >= 1");
  std::vector<int> sizes;
  for (const std::string& s : glue::SplitList(sizes_text)) sizes.push_back(std::stoi(s));
  if (sizes.empty() || !std::is_sorted(sizes.begin(), sizes.end())) throw glue::FlagError("--sizes: increasing sizes");

  const nav::RatSlamOptions options = glue::ReadRatSlamOptions(glue::IniFile::Load(ratslam_config));
  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(sim_config), "");
  const nav::sim::Scene scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  if (scene.route.size() < 2) throw std::runtime_error("scene " + scene_name + " has no route");
  nav::sim::OmniRenderer renderer(scene, sim.camera);
  auto render = [&](const nav::Pose2& pose) {
    cv::Mat image, gray;
    renderer.RenderPanorama(pose, {}, &image);
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
    return gray;
  };
  std::cerr << "bench-ratslam: " << scene_name << " panoramas " << sim.camera.panorama.width_px << "x"
            << sim.camera.panorama.height_px << ", templates " << options.local_view.template_x_size << "x"
            << options.local_view.template_y_size << ", pose cells " << options.pose_cells.pc_dim_xy << "^2 x "
            << options.pose_cells.pc_dim_th << "\n";

  std::mt19937_64 rng(11);
  std::normal_distribution<double> jitter(0.0, 0.015), turn(0.0, 1.0 * M_PI / 180);
  nav::RatSlam slam(options, {});
  std::vector<nav::Pose2> stored;  // poses whose views were fed
  const nav::Pose2 step{kStepM, 0, 0.002};

  struct Row {
    int templates = 0;
    size_t experiences = 0, links = 0;
    double image_ms = 0, odometry_ms = 0, load = 0;
  };
  std::vector<Row> rows;
  int64_t fed = 0;
  for (const int size : sizes) {
    while (slam.templates() < size) {
      const nav::Pose2 pose = RandomPose(scene.route, rng);
      slam.OnImage(render(pose));
      stored.push_back(pose);
      for (int k = 0; k < kOdometryPerFrame; ++k) slam.OnOdometry(step, 1.0 / kOdometryHz);
      if (++fed % 200 == 0) std::cerr << "bench-ratslam: " << slam.templates() << " templates\r" << std::flush;
      if (fed > 20 * static_cast<int64_t>(size) + 1000) throw std::runtime_error("the map does not grow to " + std::to_string(size) + " templates");
    }
    // Query views near stored poses, rendered before timing.
    std::vector<cv::Mat> queries;
    std::uniform_int_distribution<size_t> pick(0, stored.size() - 1);
    for (int i = 0; i < cycles; ++i) {
      const nav::Pose2& p = stored[pick(rng)];
      queries.push_back(render({p.x_m + jitter(rng), p.y_m + jitter(rng), p.theta_rad + turn(rng)}));
    }
    std::vector<double> image_s, odometry_s;
    for (int r = 0; r < runs; ++r) {
      nav::RatSlam copy = slam;
      double t_image = 0, t_odometry = 0;
      for (int i = 0; i < cycles; ++i) {
        auto t0 = std::chrono::steady_clock::now();
        copy.OnImage(queries[static_cast<size_t>(i)]);
        auto t1 = std::chrono::steady_clock::now();
        for (int k = 0; k < kOdometryPerFrame; ++k) copy.OnOdometry(step, 1.0 / kOdometryHz);
        auto t2 = std::chrono::steady_clock::now();
        t_image += std::chrono::duration<double>(t1 - t0).count();
        t_odometry += std::chrono::duration<double>(t2 - t1).count();
      }
      image_s.push_back(t_image / cycles);
      odometry_s.push_back(t_odometry / (cycles * kOdometryPerFrame));
    }
    std::sort(image_s.begin(), image_s.end());
    std::sort(odometry_s.begin(), odometry_s.end());
    Row row;
    row.templates = slam.templates();
    row.experiences = slam.experience_map().experiences().size();
    row.links = slam.experience_map().links().size();
    row.image_ms = 1e3 * image_s[image_s.size() / 2];
    row.odometry_ms = 1e3 * odometry_s[odometry_s.size() / 2];
    row.load = (row.image_ms * kFrameHz + row.odometry_ms * kOdometryHz) / 1000.0;
    rows.push_back(row);
    std::cerr << "bench-ratslam: " << row.templates << " templates, " << row.experiences << " experiences: "
              << row.image_ms << " ms per image, " << row.odometry_ms << " ms per odometry\n";
  }

  // The pose-cell step alone: a settled packet, and several packets after injections.
  nav::PoseCellNetwork cells(options.pose_cells);
  for (int i = 0; i < 50; ++i) cells.OnOdometry(0, 0, 0);
  const double settled_ms = 1e3 * bench::MedianSecondsPerCall(runs, 200, [&](int) { cells.OnOdometry(kStepM, 0, 0.002); });
  const int d = options.pose_cells.pc_dim_xy, t = options.pose_cells.pc_dim_th;
  nav::PoseCellNetwork busy(options.pose_cells);
  for (int k = 0; k < 4; ++k) busy.Inject((k * 5) % d, (k * 7) % d, (k * 9) % t, 0.3);
  for (int i = 0; i < 3; ++i) busy.OnOdometry(0, 0, 0);
  const int busy_active = busy.peak().active_cells;
  const double busy_ms = 1e3 * bench::MedianSecondsPerCall(runs, 50, [&](int i) {
    if (i % 10 == 0) {
      for (int k = 0; k < 4; ++k) busy.Inject((k * 5 + i) % d, (k * 7) % d, (k * 9) % t, 0.3);
    }
    busy.OnOdometry(kStepM, 0, 0.002);
  });

  fs::create_directories(out_dir);
  std::ostringstream md;
  results::Json json;
  json["scene"] = scene_name;
  json["runs"] = runs;
  json["cycles"] = cycles;
  json["pose_cells_active"] = results::Rounded(cells.peak().active_cells, 4);
  json["pose_cell_step_ms"] = results::Rounded(settled_ms, 4);
  json["pose_cell_step_busy_ms"] = results::Rounded(busy_ms, 4);
  json["pose_cell_busy_active"] = results::Rounded(busy_active, 4);
  md << "# bench-ratslam\n\n" << scene_name << " panoramas, " << options.local_view.template_x_size << "x"
     << options.local_view.template_y_size << " templates, " << d << "x" << d << "x" << t
     << " pose cells; one core; median of " << runs << " runs of " << cycles << " cycles (a view and "
     << kOdometryPerFrame << " odometry steps).\n\n"
     << "| templates | experiences | links | ms per image | ms per odometry | share of a core at 10 Hz + 50 Hz |\n"
        "|---|---|---|---|---|---|\n";
  for (const Row& r : rows) {
    const std::string at = "_at_" + std::to_string(r.templates);
    json["ms_per_image" + at] = results::Rounded(r.image_ms, 4);
    json["ms_per_odometry" + at] = results::Rounded(r.odometry_ms, 4);
    json["core_load" + at] = results::Rounded(r.load, 4);
    md << std::fixed << std::setprecision(3) << "| " << r.templates << " | " << r.experiences << " | " << r.links
       << " | " << r.image_ms << " | " << r.odometry_ms << " | " << std::setprecision(1) << 100 * r.load << " % |\n";
  }
  md << std::fixed << std::setprecision(3) << "\nPose-cell step alone (excitation, inhibition, normalisation, path "
     << "integration, best cell): " << settled_ms << " ms with one packet (" << cells.peak().active_cells
     << " active cells), " << busy_ms << " ms with injected packets (" << busy_active << " active cells).\n";
  results::WriteJsonFile((fs::path(out_dir) / "bench.json").string(), json);
  std::ofstream(fs::path(out_dir) / "bench.md") << md.str();
  std::cout << md.str();
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
