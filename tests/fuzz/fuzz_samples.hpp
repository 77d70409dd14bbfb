#pragma once
// Valid sample messages of every snapnav type (small arrays, so sweeps over every byte are
// cheap), and each type's decoder behind one signature, for the fuzz tests.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "snapnav/drive_command_t.hpp"
#include "snapnav/experience_map_t.hpp"
#include "snapnav/fused_slam_status_t.hpp"
#include "snapnav/laser_slam_status_t.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/navigator_status_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/place_cell_match_t.hpp"
#include "snapnav/localization_status_t.hpp"
#include "snapnav/map_request_t.hpp"
#include "snapnav/pose_correction_t.hpp"
#include "snapnav/occupancy_grid_t.hpp"
#include "snapnav/point_map_t.hpp"
#include "snapnav/pose_t.hpp"
#include "snapnav/waypoint_route_t.hpp"

namespace snapnav::fuzz {

drive_command_t SampleDriveCommand();
experience_map_t SampleExperienceMap();
fused_slam_status_t SampleFusedSlamStatus();
laser_slam_status_t SampleLaserSlamStatus();
homing_vector_t SampleHomingVector();
landmark_set_t SampleLandmarkSet();
laser_scan_t SampleLaserScan(int beams = 16);
navigator_status_t SampleNavigatorStatus();
odometry_t SampleOdometry();
omni_frame_t SampleOmniFrame();
place_cell_match_t SamplePlaceCellMatch();
point_map_t SamplePointMap();
occupancy_grid_t SampleOccupancyGrid();
localization_status_t SampleLocalizationStatus();
map_request_t SampleMapRequest();
pose_correction_t SamplePoseCorrection();  // for the shipped placecells.ini's explore pose channel
pose_t SamplePose();
waypoint_route_t SampleRoute();

// One lcm type: its name, a valid encoded sample, and its decoder. `decode` returns nullopt
// with the reason when glue::Decode rejects the bytes, else the message encoded again.
struct TypeCase {
  std::string name;
  std::string sample;
  std::function<std::optional<std::string>(const std::string& bytes, std::string* error)> decode;
};
// Every type of lcmtypes/.
std::vector<TypeCase> AllTypes();

// "" when a payload a node published decodes and holds only finite numbers (the output types:
// pose_t, point_map_t, landmark_set_t, homing_vector_t, place_cell_match_t, drive_command_t,
// navigator_status_t, experience_map_t, fused_slam_status_t); else what is wrong.
std::string OutputProblem(const std::string& channel, const std::string& payload);

}  // namespace snapnav::fuzz
