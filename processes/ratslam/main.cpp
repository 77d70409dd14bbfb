// ratslam: RatSLAM (Milford and Wyeth 2010, as OpenRatSLAM) on OMNI_FRAME and ODOMETRY; publishes
// the pose and the experience map.
#include <iostream>

#include "ratslam_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/ratslam.ini";
  glue::Flags flags("ratslam",
                    "RatSLAM (Milford and Wyeth 2010; the algorithm of OpenRatSLAM): omni frames (raw, unwrapped\n"
                    "here, or panoramas) become view templates, odometry drives the pose-cell attractor network,\n"
                    "and the experience map closes loops and relaxes. Publishes pose_t (estimator \"ratslam\", the\n"
                    "input's utime) per frame and/or odometry message ([node] pose_on) and experience_map_t every\n"
                    "[node] experience_map_interval_s of message time. The first odometry message fixes the start:\n"
                    "the map frame is the odometry frame. [ratslam] keys are OpenRatSLAM's (see config/ratslam.ini).");
  flags.AddCommon(&common);
  std::string mask;
  flags.AddString("mask", &mask, glue::kMaskFlagHelp);
  if (!flags.Parse(argc, argv)) return 0;
  auto ini = glue::IniFile::Load(common.config);
  glue::ApplyMaskFlag(mask, &ini);
  const auto config = processes::RatSlamConfig::FromIni(ini, common.channel_prefix);
  return glue::RunNode<processes::RatSlamNode>(
      "ratslam", common.config, config, common.lcm_url,
      [&](const processes::RatSlamNode&, const glue::Bus& bus) {
        std::string line = "frames from " + config.input_channel() + ", odometry from " + config.odometry_channel +
                           ", poses on " + config.pose_channel + ", experience map on " +
                           config.experience_map_channel + " (" + bus.url() + ")";
        if (bus.url().rfind("file://", 0) == 0) {
          line += "\nratslam: reading a log: LCM cannot publish on a file:// URL, so every pose and map counts as\n"
                  "ratslam: a failed publish (internal error); record the outputs with lcm-logger on a live bus";
        }
        return line;
      },
      std::cerr);
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
