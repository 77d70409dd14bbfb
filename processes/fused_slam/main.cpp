// fused-slam: fused visual + laser SLAM on ODOMETRY, LASER_SCAN and POSE_PLACE_CELLS; publishes the
// fused pose on POSE_EKF (every scan and every visual measurement), the map and a status.
#include <iostream>

#include "fused_slam_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/run_node.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/fused_slam.ini";
  glue::Flags flags("fused-slam",
                    "Fused visual + laser SLAM (thesis 1.2, 5, 6.3.3): the laser SLAM (EKF on the robot pose, odometry\n"
                    "prediction, ICP scan updates against a point map) runs unaltered in its own map frame; the place\n"
                    "cells' poses and covariances, behind a Mahalanobis (chi-square, 3 dof) gate, estimate that map's\n"
                    "offset from the world in every map cell, and the fused pose is the laser's corrected by it.\n"
                    "Visual measurements that are rejected but agree with each other relocalise the filter (a\n"
                    "kidnapping); optionally (suspect_after) scans add no points to the map while they are rejected.\n"
                    "The frame is the place memory's. Publishes the fused pose_t on\n"
                    "every scan (its utime) and every visual measurement (that measurement's utime), the map every\n"
                    "n-th scan and a fused_slam_status_t; counts in the report at exit. Run placecells without its\n"
                    "distance filter so that its fixes do not follow a lost filter.");
  flags.AddCommon(&common);
  if (!flags.Parse(argc, argv)) return 0;
  const auto config = processes::FusedSlamConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  return glue::RunNode<processes::FusedSlamNode>(
      "fused-slam", common.config, config, common.lcm_url, [&](const processes::FusedSlamNode&, const glue::Bus& bus) {
        return "odometry from " + config.odometry_channel + ", scans from " + config.scan_channel +
               ", visual poses from " + config.visual_channel + "; poses on " + config.pose_channel + ", map on " +
               config.map_channel + ", status on " + config.status_channel + " (" + bus.url() + ")";
      });
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
