// sim: the simulated lab (robot, omni camera, laser, odometry, ground truth).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>

#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string scene_override;
  double duration_override = -1;
  int seed_override = -1;
  std::string mode_override, drive_override, encoding_override, start_time_override, frame_times_path;
  double clock_offset_override = std::nan("");
  double realtime_factor_override = std::nan("");
  int jpeg_quality_override = -1;
  glue::Flags flags("sim",
                    "The simulated lab: drives a robot through a scene and publishes its omni camera frames,\n"
                    "laser scans, odometry and ground-truth pose. Scenes: config/scenes/*.scene.");
  flags.AddCommon(&common);
  flags.AddString("scene", &scene_override, "scene name or file (overrides [sim] scene)");
  flags.AddDouble("duration-s", &duration_override, "simulated seconds to run (overrides [sim] duration_s)");
  flags.AddInt("seed", &seed_override, "random seed (overrides [sim] seed)");
  flags.AddString("mode", &mode_override, "realtime | lockstep (overrides [sim] mode)");
  flags.AddString("drive", &drive_override,
                  "route | grid | commands | still (overrides [sim] drive); grid: every node of the scene's grid,\n"
                  "row by row, once (an exploration drive), then the run ends");
  flags.AddDouble("realtime-factor", &realtime_factor_override,
                  "realtime: simulated seconds per wall-clock second, 0.01..100; 0.5: half as fast as life, every rate\n"
                  "and every utime as at 1 (overrides [sim] realtime_factor)");
  flags.AddString("encoding", &encoding_override, "frames: gray8 | rgb8 | jpeg | png (overrides [camera] encoding)");
  flags.AddInt("jpeg-quality", &jpeg_quality_override, "JPEG quality 1..100 (overrides [camera] jpeg_quality)");
  flags.AddString("start-time-s", &start_time_override,
                  "utime of the first message [s since the epoch], or now: the wall clock (overrides [sim] start_time_s)");
  flags.AddString("frame-times", &frame_times_path,
                  "write each raw frame's utime and the wall-clock time it was handed to the bus to this CSV file\n"
                  "(utime,publish_utime): with a subscriber's receive times (latency-probe --frames-csv), its time on the bus");
  flags.AddDouble("clock-offset-s", &clock_offset_override,
                  "added to every utime it publishes: a robot whose clock is off (overrides [sim] clock_offset_s)");
  if (!flags.Parse(argc, argv)) return 0;
  auto config = processes::SimConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  if (!scene_override.empty()) config.scene = scene_override;
  if (duration_override >= 0) config.duration_s = duration_override;
  if (seed_override >= 0) config.seed = static_cast<uint64_t>(seed_override);
  if (!mode_override.empty()) {
    if (mode_override != "realtime" && mode_override != "lockstep") throw glue::FlagError("--mode must be realtime or lockstep");
    config.realtime = mode_override == "realtime";
  }
  if (!std::isnan(realtime_factor_override)) config.realtime_factor = realtime_factor_override;
  if (!drive_override.empty()) {
    if (drive_override != "route" && drive_override != "grid" && drive_override != "commands" && drive_override != "still") {
      throw glue::FlagError("--drive must be route, grid, commands or still, got '" + drive_override + "'");
    }
    config.drive = drive_override;
  }
  if (!encoding_override.empty()) {
    try {
      config.encoding = glue::ParseFrameEncoding(encoding_override);
    } catch (const std::invalid_argument& e) {
      throw glue::FlagError(std::string("--encoding: ") + e.what());
    }
  }
  if (jpeg_quality_override >= 0) config.jpeg_quality = jpeg_quality_override;
  if (start_time_override == "now") {
    config.start_at_wall_clock = true;
  } else if (!start_time_override.empty()) {
    char* end = nullptr;
    const double s = std::strtod(start_time_override.c_str(), &end);
    if (*end != '\0' || !(s >= 0)) throw glue::FlagError("--start-time-s expects seconds >= 0 or now, got '" + start_time_override + "'");
    config.start_at_wall_clock = false;
    config.start_utime = static_cast<int64_t>(s * 1e6);
  }
  if (!std::isnan(clock_offset_override)) config.clock_offset_us = std::llround(clock_offset_override * 1e6);
  try {
    config.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(config.scene));
  std::cerr << "sim: config " << common.config << "\n";
  config.Print(std::cerr);
  std::cerr << "sim: scene '" << scene.name << "': " << scene.walls.size() << " walls, " << scene.cylinders.size()
            << " cylinders, " << scene.textures.size() << " textures, " << scene.people.count << " people\n";
  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  processes::SimNode node(bus, config, scene);
  std::ofstream frame_times;
  if (!frame_times_path.empty()) {
    frame_times.open(frame_times_path);
    if (!frame_times) throw glue::FlagError("--frame-times: cannot write " + frame_times_path);
    frame_times << "utime,publish_utime\n";
    node.LogFramePublishTimes(&frame_times);
  }
  node.Run(&std::cerr);
  std::cerr << "sim: done at t=" << (node.utime() - node.start_utime()) * 1e-6 << " s: " << node.frames()
            << " frames, " << node.scans() << " scans, " << node.odometry_messages() << " odometry, "
            << node.commands() << " drive commands, " << node.stale_commands() << " ignored as stale, "
            << node.watchdog_stops() << " watchdog stops, " << node.world().collisions() << " blocked steps, "
            << node.world().distance_m() << " m driven\n";
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
