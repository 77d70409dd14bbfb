// laser-slam: 2D laser SLAM on ODOMETRY and LASER_SCAN; publishes one pose per scan and the map.
#include <iostream>

#include "laser_slam_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/laser_slam.ini";
  glue::Flags flags("laser-slam",
                    "2D laser SLAM (thesis 5.3.1): odometry predicts an EKF on the robot pose, each laser scan is\n"
                    "matched to a point map by ICP and updates it. Publishes one pose_t per scan (utime of the scan)\n"
                    "and every n-th scan the map as point_map_t. Messages are processed in arrival order.");
  flags.AddCommon(&common);
  if (!flags.Parse(argc, argv)) return 0;
  const auto config = processes::LaserSlamConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  std::cerr << "laser-slam: config " << common.config << "\n";
  config.Print(std::cerr);
  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  processes::LaserSlamNode node(bus, config);
  std::cerr << "laser-slam: odometry from " << config.odometry_channel << ", scans from " << config.scan_channel
            << ", poses on " << config.pose_channel << ", map on " << config.map_channel << " (" << bus.url() << ")\n";
  bus.Run();
  node.Report(std::cerr);
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
