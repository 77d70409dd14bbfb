// omni-camera: publishes raw catadioptric frames from a camera, a video file or an image folder.
#include <iostream>

#include "omni_camera_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/omni_camera.ini";
  int max_frames = 0;
  glue::Flags flags("omni-camera",
                    "Captures raw catadioptric images with OpenCV from a camera device, a video file or a folder of\n"
                    "images ([camera] source) and publishes them as omni_frame_t (RAW_OMNI) with the mirror\n"
                    "calibration. utime is the wall-clock capture time, for files and folders too (live source).");
  flags.AddCommon(&common);
  std::string mask;
  flags.AddString("mask", &mask, glue::kMaskFlagHelp);
  flags.AddInt("max-frames", &max_frames, "stop after publishing this many frames (0: no limit)");
  if (!flags.Parse(argc, argv)) return 0;
  if (max_frames < 0) throw glue::FlagError("--max-frames must be >= 0");

  auto ini = glue::IniFile::Load(common.config);
  glue::ApplyMaskFlag(mask, &ini);
  const auto config = processes::OmniCameraConfig::FromIni(ini, common.channel_prefix);
  std::cerr << "omni-camera: config " << common.config << "\n";
  config.Print(std::cerr);
  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  processes::OmniCameraNode node(bus, config, &std::cerr);
  std::cerr << "omni-camera: capturing from " << node.source_description() << ", publishing on " << config.frame_channel
            << " (" << bus.url() << ")\n";
  const auto stop = node.Run(max_frames);
  std::cerr << "omni-camera: ";
  node.Report(std::cerr);
  bus.ReportStats(std::cerr);
  if (stop == processes::OmniCameraNode::StopReason::kEndOfSource && node.published() == 0) {
    std::cerr << "omni-camera: error: " << node.source_description() << " gave no usable frame\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
