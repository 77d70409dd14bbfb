// libFuzzer target (SNAPNAV_LIBFUZZER=ON, clang): the nodes without images (dead-reckoning,
// laser-slam, navigator, fused-slam) on one memq:// bus; the first byte picks the channel, the
// rest is the payload. Whatever arrives, no crash, and nothing published holds a NaN or an
// infinity.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "dead_reckoning_node.hpp"
#include "fused_slam_node.hpp"
#include "fuzz_samples.hpp"
#include "laser_slam_node.hpp"
#include "navigator_node.hpp"

namespace {

using namespace snapnav;

const char* const kChannels[] = {"ODOMETRY", "LASER_SCAN", "POSE_PLACE_CELLS", "HOMING_VECTOR", "ROUTE"};

struct Nodes {
  glue::Bus bus{"memq://"};
  std::unique_ptr<processes::DeadReckoningNode> dr;
  std::unique_ptr<processes::LaserSlamNode> slam;
  std::unique_ptr<processes::NavigatorNode> navigator;
  std::unique_ptr<processes::FusedSlamNode> fused;
  Nodes() {
    const std::string dir = SNAPNAV_CONFIG_DIR;
    bus.SubscribeRaw(".*", [this](const void* d, size_t n) {
      const std::string& ch = bus.current().channel;
      for (const char* in : kChannels) {
        if (ch == in) return;
      }
      const std::string problem = fuzz::OutputProblem(ch, std::string(static_cast<const char*>(d), n));
      if (!problem.empty()) {
        std::fprintf(stderr, "published: %s\n", problem.c_str());
        std::abort();
      }
    });
    dr = std::make_unique<processes::DeadReckoningNode>(
        bus, processes::DeadReckoningConfig::FromIni(glue::IniFile::Load(dir + "/dead_reckoning.ini"), ""));
    slam = std::make_unique<processes::LaserSlamNode>(
        bus, processes::LaserSlamConfig::FromIni(glue::IniFile::Load(dir + "/laser_slam.ini"), ""));
    navigator = std::make_unique<processes::NavigatorNode>(
        bus, processes::NavigatorConfig::FromIni(glue::IniFile::Load(dir + "/navigator.ini"), ""));
    fused = std::make_unique<processes::FusedSlamNode>(
        bus, processes::FusedSlamConfig::FromIni(glue::IniFile::Load(dir + "/fused_slam.ini"), ""));
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Nodes* nodes = new Nodes();
  if (size < 1) return 0;
  nodes->bus.PublishRaw(kChannels[data[0] % 5], data + 1, size - 1);
  while (nodes->bus.HandleOnce(0)) {
  }
  return 0;
}
