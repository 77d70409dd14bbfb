// dead-reckoning: integrates odometry alone and publishes its pose.
#include <iostream>

#include "dead_reckoning_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/dead_reckoning.ini";
  glue::Flags flags("dead-reckoning", "Integrates odometry alone and publishes the pose with its covariance.");
  flags.AddCommon(&common);
  if (!flags.Parse(argc, argv)) return 0;
  const auto config = processes::DeadReckoningConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  return glue::RunNode<processes::DeadReckoningNode>(
      "dead-reckoning", common.config, config, common.lcm_url,
      [](const processes::DeadReckoningNode&, const glue::Bus&) { return std::string(); });
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
