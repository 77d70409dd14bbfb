// placecells: place-cell memory and localization; explores a memory file or localizes in one.
#include <iostream>
#include <stdexcept>

#include "placecells_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/placecells.ini";
  std::string mode, memory;
  glue::Flags flags("placecells",
                    "Place cells (thesis 4.4, 5.1, 5.2). explore: omni frames unlike every stored cell become new\n"
                    "cells at the pose of [channels] explore_pose; the memory file is written every\n"
                    "[placecells] save_every_cells new cells and on exit (an existing file is extended).\n"
                    "localize: the memory file is loaded and each processed frame gives the best cell\n"
                    "(place_cell_match_t on [channels] match) and a pose with covariance (pose_t on [channels] pose).\n"
                    "Frames are processed at most every min_interval_s of message time or min_travel_m of odometry.");
  flags.AddCommon(&common);
  std::string mask;
  flags.AddString("mask", &mask, glue::kMaskFlagHelp);
  flags.AddString("mode", &mode, "explore | localize (overrides [placecells] mode)");
  flags.AddString("memory", &memory, "place-cell memory file (overrides [placecells] memory_file)");
  if (!flags.Parse(argc, argv)) return 0;

  auto ini = glue::IniFile::Load(common.config);
  glue::ApplyMaskFlag(mask, &ini);
  auto config = processes::PlaceCellsConfig::FromIni(ini, common.channel_prefix);
  if (!mode.empty()) {
    if (mode == "explore") {
      config.mode = processes::PlaceCellsMode::kExplore;
    } else if (mode == "localize") {
      config.mode = processes::PlaceCellsMode::kLocalize;
    } else {
      throw glue::FlagError("--mode '" + mode + "': expected explore | localize");
    }
  }
  if (!memory.empty()) config.memory_file = memory;
  try {
    config.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(std::string("--mode/--memory: ") + e.what());
  }
  return glue::RunNode<processes::PlaceCellsNode>(
      "placecells", common.config, config, common.lcm_url,
      [&](const processes::PlaceCellsNode&, const glue::Bus& bus) {
        const bool explore = config.mode == processes::PlaceCellsMode::kExplore;
        return std::string(processes::PlaceCellsModeName(config.mode)) + ", frames from " + config.input_channel() +
               ", odometry from " + config.odometry_channel +
               (explore ? ", cell poses from " + config.explore_pose_channel + ", matches on " + config.match_channel
                        : ", matches on " + config.match_channel + ", poses on " + config.pose_channel) +
               " (" + bus.url() + ")";
      },
      std::cerr);
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
