// landmarks: feature landmarks (vertical lines, SIFT, SURF) of omni frames, one set per frame.
#include <iostream>

#include "landmarks_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/landmarks.ini";
  std::string method;
  glue::Flags flags("landmarks",
                    "Feature landmarks of omni frames (thesis 4.1-4.3): each frame (raw, unwrapped here, or panorama;\n"
                    "[landmarks] input) yields one landmark_set_t of vertical lines, SIFT or SURF keypoints on\n"
                    "[channels] landmarks. Run one instance per method for several methods.");
  flags.AddCommon(&common);
  std::string mask;
  flags.AddString("mask", &mask, glue::kMaskFlagHelp);
  flags.AddString("method", &method, "vline | sift | surf (overrides [landmarks] method)");
  if (!flags.Parse(argc, argv)) return 0;
  auto ini = glue::IniFile::Load(common.config);
  glue::ApplyMaskFlag(mask, &ini);
  const auto config = processes::LandmarksConfig::FromIni(ini, common.channel_prefix, method);
  return glue::RunNode<processes::LandmarksNode>(
      "landmarks", common.config, config, common.lcm_url, [&](const processes::LandmarksNode&, const glue::Bus& bus) {
        return "frames from " + config.input_channel() + ", " + nav::LandmarkMethodName(config.extractor.method) +
               " landmarks on " + config.landmarks_channel + " (" + bus.url() + ")";
      });
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
