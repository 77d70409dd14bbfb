// laser-slam: 2D laser SLAM on ODOMETRY and LASER_SCAN; publishes one pose per scan, the point map
// and the occupancy grid. With --mode localize --map FILE: the pose in a saved map instead.
#include <iostream>
#include <sstream>

#include "laser_slam_node.hpp"
#include "localize_node.hpp"
#include "map_export.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/laser_slam.ini";
  std::string mode = "slam", map_path;
  glue::Flags flags("laser-slam",
                    "2D laser SLAM (thesis 5.3.1): odometry predicts an EKF on the robot pose, each laser scan is\n"
                    "matched to a point map by ICP and updates it. Publishes one pose_t per scan (utime of the scan),\n"
                    "every n-th scan the map as point_map_t, and the map as an occupancy grid (occupancy_grid_t,\n"
                    "[grid] every_s and on a map_request_t). Messages are processed in arrival order.\n"
                    "--mode localize --map FILE: the pose in a saved map (map-export's map.yaml + map.pgm, its\n"
                    "map.gridmap, or MRPT's keyframes: a .simplemap as icp-slam writes it), the map never changed:\n"
                    "from an unknown start a global search over the whole map\n"
                    "(branch and bound, every heading) until a pose is unambiguous, then tracking with the EKF and\n"
                    "scan matcher; a sustained collapse of the scans' fit searches again. Poses only while localized,\n"
                    "localization_status_t (lost / localized, scores) on every scan, the saved map on the grid\n"
                    "channel ([localize] in the config; docs/localization.md).");
  flags.AddCommon(&common);
  flags.AddString("mode", &mode, "slam (build the map) | localize (in the saved map --map)");
  flags.AddString("map", &map_path, "--mode localize: the saved map, map.yaml (ROS map_server: YAML + PGM), map.gridmap or map.simplemap (MRPT)");
  if (!flags.Parse(argc, argv)) return 0;
  if (mode != "slam" && mode != "localize") throw glue::FlagError("--mode must be slam or localize, got '" + mode + "'");
  if (mode == "localize" && map_path.empty()) throw glue::FlagError("--mode localize needs --map FILE (map.yaml, map.gridmap or map.simplemap)");
  if (mode == "slam" && !map_path.empty()) throw glue::FlagError("--map is for --mode localize");
  const auto config = processes::LaserSlamConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  if (mode == "localize") {
    const nav::OccupancyCells map = map::ReadMapFile(map_path, config.grid.grid);
    std::cerr << "laser-slam: map " << map_path << ": " << map.width << " x " << map.height << " cells of " << map.resolution_m
              << " m from (" << map.origin_x_m << ", " << map.origin_y_m << "): " << map.occupied << " occupied, " << map.free
              << " free, " << map.unknown << " unknown\n";
    return glue::RunNode<processes::LocalizeNode>(
        "laser-slam", common.config, config, common.lcm_url,
        [&](const processes::LocalizeNode& node, const glue::Bus& bus) {
          const auto& g = node.localizer().global();
          std::ostringstream line;
          line << "localize: global search over " << g.free_cells() << " free cells of "
               << config.localize.options.global.resolution_m << " m (" << g.memory_bytes() / 1024
               << " KiB), tracking on " << node.localizer().map_points() << " map points\nlaser-slam: odometry from "
               << config.odometry_channel << ", scans from " << config.scan_channel << ", poses on " << config.pose_channel
               << ", status on " << config.localize.status_channel << ", map on " << config.grid.channel << " ("
               << bus.url() << ")";
          return line.str();
        },
        map, map_path);
  }
  return glue::RunNode<processes::LaserSlamNode>(
      "laser-slam", common.config, config, common.lcm_url, [&](const processes::LaserSlamNode&, const glue::Bus& bus) {
        return "odometry from " + config.odometry_channel + ", scans from " + config.scan_channel + ", poses on " +
               config.pose_channel + ", map on " + config.map_channel + ", grid on " + config.grid.channel + " (" +
               bus.url() + ")";
      });
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
