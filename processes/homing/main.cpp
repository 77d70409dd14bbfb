// homing: snapshot homing with HOG landmarks; publishes one homing vector per omni frame.
#include <iostream>
#include <stdexcept>

#include "homing_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/homing.ini";
  std::string home_image;
  bool home_first_flag = false;
  glue::Flags flags("homing",
                    "Snapshot homing with HOG landmarks (thesis chapter 3). Compares each omni frame (raw, unwrapped\n"
                    "here, or panorama; [homing] input) with the home snapshot and publishes one homing_vector_t per\n"
                    "frame. The home comes from HOME_SNAPSHOT, an image file, or the first frame ([homing] home).");
  flags.AddCommon(&common);
  std::string mask;
  flags.AddString("mask", &mask, glue::kMaskFlagHelp);
  flags.AddString("home-image", &home_image,
                  "image file of the home snapshot (sets [homing] home = image; relative to the working folder)");
  flags.AddBool("home-first", &home_first_flag, "the first frame becomes the home (sets [homing] home = first)");
  if (!flags.Parse(argc, argv)) return 0;

  auto ini = glue::IniFile::Load(common.config);
  glue::ApplyMaskFlag(mask, &ini);
  auto config = processes::HomingConfig::FromIni(ini, common.channel_prefix);
  if (!home_image.empty()) {
    config.home = processes::HomeSource::kImage;
    config.home_image = home_image;
    try {
      config.Validate();
    } catch (const std::invalid_argument& e) {
      throw glue::FlagError(std::string("--home-image: ") + e.what());
    }
  }
  if (home_first_flag) {
    if (!home_image.empty()) throw glue::FlagError("--home-first and --home-image exclude each other");
    config.home = processes::HomeSource::kFirst;
    config.home_image.clear();
    try {
      config.Validate();
    } catch (const std::invalid_argument& e) {
      throw glue::FlagError(std::string("--home-first: ") + e.what());
    }
  }
  return glue::RunNode<processes::HomingNode>(
      "homing", common.config, config, common.lcm_url, [&](const processes::HomingNode& node, const glue::Bus& bus) {
        return "frames from " + config.input_channel() + ", home snapshots from " + config.home_snapshot_channel +
               ", vectors on " + config.homing_vector_channel + " (" + bus.url() + ")" +
               (node.has_home() ? ", home image loaded" : "");
      });
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
