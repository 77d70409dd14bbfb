// dead-reckoning: integrates odometry alone and publishes its pose.
#include <iostream>

#include "dead_reckoning_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/dead_reckoning.ini";
  glue::Flags flags("dead-reckoning", "Integrates odometry alone and publishes the pose with its covariance.");
  flags.AddCommon(&common);
  if (!flags.Parse(argc, argv)) return 0;
  const auto config = processes::DeadReckoningConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  std::cerr << "dead-reckoning: config " << common.config << "\n";
  config.Print(std::cerr);
  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  processes::DeadReckoningNode node(bus, config);
  bus.Run();
  std::cerr << "dead-reckoning: published " << node.published() << " poses\n";
  for (const auto& [reason, n] : node.rejected()) std::cerr << "dead-reckoning:   rejected (" << reason << "): " << n << "\n";
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
