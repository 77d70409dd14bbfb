// sim: the simulated lab (robot, omni camera, laser, odometry, ground truth).
#include <iostream>

#include "scene_file.hpp"
#include "sim_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/sim.ini";
  std::string scene_override;
  double duration_override = -1;
  int seed_override = -1;
  std::string mode_override;
  glue::Flags flags("sim",
                    "The simulated lab: drives a robot through a scene and publishes its omni camera frames,\n"
                    "laser scans, odometry and ground-truth pose. Scenes: config/scenes/*.scene.");
  flags.AddCommon(&common);
  flags.AddString("scene", &scene_override, "scene name or file (overrides [sim] scene)");
  flags.AddDouble("duration-s", &duration_override, "simulated seconds to run (overrides [sim] duration_s)");
  flags.AddInt("seed", &seed_override, "random seed (overrides [sim] seed)");
  flags.AddString("mode", &mode_override, "realtime | lockstep (overrides [sim] mode)");
  if (!flags.Parse(argc, argv)) return 0;
  auto config = processes::SimConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  if (!scene_override.empty()) config.scene = scene_override;
  if (duration_override >= 0) config.duration_s = duration_override;
  if (seed_override >= 0) config.seed = static_cast<uint64_t>(seed_override);
  if (!mode_override.empty()) {
    if (mode_override != "realtime" && mode_override != "lockstep") throw glue::FlagError("--mode must be realtime or lockstep");
    config.realtime = mode_override == "realtime";
  }
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(config.scene));
  std::cerr << "sim: config " << common.config << "\n";
  config.Print(std::cerr);
  std::cerr << "sim: scene '" << scene.name << "': " << scene.walls.size() << " walls, " << scene.cylinders.size()
            << " cylinders, " << scene.textures.size() << " textures, " << scene.people.count << " people\n";
  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  processes::SimNode node(bus, config, scene);
  node.Run(&std::cerr);
  std::cerr << "sim: done at t=" << (node.utime() - config.start_utime) * 1e-6 << " s: " << node.frames()
            << " frames, " << node.scans() << " scans, " << node.odometry_messages() << " odometry, "
            << node.commands() << " drive commands, " << node.world().collisions() << " blocked steps, "
            << node.world().distance_m() << " m driven\n";
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
