#pragma once
// Default channel names, in one place. Every process accepts --channel-prefix
// (prepended to every name) and may rename channels in its config.

#include <string>

namespace snapnav::channels {

inline constexpr char kOmniFrame[] = "OMNI_FRAME";              // omni_frame_t, raw catadioptric images
inline constexpr char kPanorama[] = "OMNI_PANORAMA";            // omni_frame_t, unwrapped panoramas
inline constexpr char kLaserScan[] = "LASER_SCAN";              // laser_scan_t
inline constexpr char kOdometry[] = "ODOMETRY";                 // odometry_t
inline constexpr char kDriveCommand[] = "DRIVE_COMMAND";        // drive_command_t
inline constexpr char kPoseGroundTruth[] = "POSE_GROUND_TRUTH"; // pose_t from the simulator
inline constexpr char kPoseDeadReckoning[] = "POSE_DEAD_RECKONING";
inline constexpr char kPoseLaserSlam[] = "POSE_LASER_SLAM";
inline constexpr char kPoseFusedSlam[] = "POSE_EKF";            // fused visual + laser EKF
inline constexpr char kPoseRatslam[] = "POSE_RATSLAM";
inline constexpr char kExperienceMap[] = "EXPERIENCE_MAP";      // experience_map_t (RatSLAM)
inline constexpr char kPosePlaceCells[] = "POSE_PLACE_CELLS";
inline constexpr char kLandmarks[] = "LANDMARKS";               // landmark_set_t (suffix _SIFT, _SURF, ...)
inline constexpr char kHomeSnapshot[] = "HOME_SNAPSHOT";        // omni_frame_t that becomes the home
inline constexpr char kHomingVector[] = "HOMING_VECTOR";        // homing_vector_t
inline constexpr char kPlaceCellMatch[] = "PLACE_CELL_MATCH";   // place_cell_match_t
inline constexpr char kPointMap[] = "POINT_MAP";                // point_map_t
inline constexpr char kRoute[] = "ROUTE";                       // waypoint_route_t
inline constexpr char kNavigatorStatus[] = "NAVIGATOR_STATUS";
inline constexpr char kPointMapFused[] = "POINT_MAP_FUSED";    // point_map_t of fused-slam
inline constexpr char kLaserSlamStatus[] = "LASER_SLAM_STATUS"; // laser_slam_status_t
inline constexpr char kLaserSlamCorrection[] = "LASER_SLAM_CORRECTION"; // pose_correction_t (graph back end)
inline constexpr char kFusedSlamStatus[] = "FUSED_SLAM_STATUS"; // fused_slam_status_t
inline constexpr char kBusCheck[] = "BUS_CHECK";                // omni_frame_t probes of bus-check
inline constexpr char kBusPing[] = "BUS_PING";
inline constexpr char kBusPong[] = "BUS_PONG";
inline constexpr char kSoakFrame[] = "SOAK_FRAME";              // omni_frame_t of the bus-check soak
inline constexpr char kSoakScan[] = "SOAK_SCAN";                // laser_scan_t of the bus-check soak

inline std::string Prefixed(const std::string& prefix, const std::string& name) { return prefix + name; }

}  // namespace snapnav::channels
