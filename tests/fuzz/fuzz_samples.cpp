#include "fuzz_samples.hpp"

#include <cmath>

#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/occupancy_grid_msg.hpp"

namespace snapnav::fuzz {

drive_command_t SampleDriveCommand() {
  drive_command_t m{};
  m.utime = 1700000000000000;
  m.source = "navigator";
  m.linear_velocity_mps = 0.2;
  m.angular_velocity_radps = -0.3;
  return m;
}

experience_map_t SampleExperienceMap() {
  experience_map_t m{};
  m.utime = 1700000000000000;
  m.estimator = "ratslam";
  m.frame = "map";
  m.templates = 2;
  m.loop_closures = 1;
  m.current_experience = 1;
  m.robot_x_m = 1.1;
  m.robot_y_m = 0.2;
  m.robot_theta_rad = 0.3;
  m.nexperiences = 2;
  m.x_m = {0, 1};
  m.y_m = {0, 0.2};
  m.theta_rad = {0, 0.3};
  m.view_template = {0, 1};
  m.nlinks = 2;
  m.link_from = {0, 1};
  m.link_to = {1, 0};
  m.link_loop_closure = {0, 1};
  return m;
}

fused_slam_status_t SampleFusedSlamStatus() {
  fused_slam_status_t m{};
  m.utime = 1700000000000000;
  m.state = fused_slam_status_t::TRACKING;
  m.last_outcome = fused_slam_status_t::ACCEPTED;
  m.last_mahalanobis2 = 1.5;
  m.scans = 100;
  m.visual_accepted = 20;
  m.visual_rejected = 1;
  m.map_points = 500;
  m.last_fit = 0.9;
  m.x_m = 3.5;
  m.y_m = 3.0;
  m.theta_rad = 0.1;
  m.position_sigma_m = 0.01;
  return m;
}

laser_slam_status_t SampleLaserSlamStatus() {
  laser_slam_status_t m{};
  m.utime = 1700000000000000;
  m.outcome = laser_slam_status_t::ACCEPTED;
  m.prediction = laser_slam_status_t::STALE;
  m.predictions = 2;
  m.widened = true;
  m.mahalanobis2 = 3.2;
  m.gate_mahalanobis2 = 16.27;
  m.ambiguity = 0.05;
  m.fit = 0.9;
  m.kernel = 0.7;
  m.points = 600;
  m.matches = 580;
  m.position_sigma_m = 0.02;
  m.heading_sigma_deg = 0.4;
  m.scans = 100;
  m.accepted = 95;
  m.gated = 3;
  m.ambiguous = 1;
  m.no_match = 1;
  m.map_points = 4000;
  m.backend = laser_slam_status_t::BACKEND_GRAPH;
  m.keyframes = 120;
  m.loop_candidates = 40;
  m.loop_accepted = 12;
  m.loop_rejected = 28;
  m.corrections = 6;
  m.corrected = true;
  m.correction_m = 0.35;
  m.correction_deg = 2.5;
  m.correction_utime = 1700000000000000;
  return m;
}

homing_vector_t SampleHomingVector() {
  homing_vector_t m{};
  m.utime = 1700000000000000;
  m.method = landmark_set_t::HOG;
  m.alv_variant = "hog";
  m.valid = true;
  m.direction_rad = 0.5f;
  m.magnitude = 0.8f;
  m.compass_rotation_rad = -0.1f;
  m.nlandmarks_used = 12;
  return m;
}

landmark_set_t SampleLandmarkSet() {
  landmark_set_t m{};
  m.utime = 1700000000000000;
  m.sensor_name = "omni";
  m.method = landmark_set_t::SURF;
  m.panorama_width_px = 720;
  m.panorama_height_px = 120;
  m.nlandmarks = 3;
  m.descriptor_length = 4;
  for (int i = 0; i < 3; ++i) {
    m.bearings_rad.push_back(-1.0f + i);
    m.rows_px.push_back(20.0f + 10 * i);
    m.strengths.push_back(1.0f + i);
    m.scales_px.push_back(2.0f + i);
    m.descriptors.push_back({0.1f * i, 0.2f, 0.3f, 0.4f});
  }
  return m;
}

laser_scan_t SampleLaserScan(int beams) {
  laser_scan_t m{};
  m.utime = 1700000000000000;
  m.sensor_name = "hokuyo";
  m.sensor_x_m = 0.1f;
  m.angle_min_rad = -2.0944f;
  m.angle_increment_rad = 4.1888f / static_cast<float>(beams - 1);
  m.range_min_m = 0.02f;
  m.range_max_m = 5.6f;
  m.nranges = beams;
  for (int i = 0; i < beams; ++i) m.ranges_m.push_back(1.0f + 0.05f * static_cast<float>(i % 7));
  m.nintensities = 0;
  return m;
}

navigator_status_t SampleNavigatorStatus() {
  navigator_status_t m{};
  m.utime = 1700000000000000;
  m.state = navigator_status_t::DRIVING;
  m.route_name = "thesis1";
  m.nwaypoints = 5;
  m.waypoint_index = 2;
  m.waypoint_x_m = 1;
  m.waypoint_y_m = 2;
  m.distance_to_waypoint_m = 0.5;
  m.x_m = 1.2;
  m.y_m = 2.2;
  m.position_sigma_m = 0.05;
  m.linear_velocity_mps = 0.2;
  return m;
}

odometry_t SampleOdometry() {
  odometry_t m{};
  m.utime = 1700000000020000;
  m.sensor_name = "sim";
  m.x_m = 1.0;
  m.y_m = 2.0;
  m.theta_rad = 0.3;
  m.delta_x_m = 0.006;
  m.delta_y_m = 0.0;
  m.delta_theta_rad = 0.001;
  m.delta_t_s = 0.02;
  m.linear_velocity_mps = 0.3;
  m.angular_velocity_radps = 0.05;
  return m;
}

omni_frame_t SampleOmniFrame() {
  omni_frame_t m{};
  m.utime = 1700000000000000;
  m.sensor_name = "omni";
  m.kind = omni_frame_t::RAW_OMNI;
  m.width = 4;
  m.height = 3;
  m.row_stride = 4;
  m.encoding = omni_frame_t::GRAY8;
  m.mirror_center_x_px = 2;
  m.mirror_center_y_px = 1.5f;
  m.mirror_inner_radius_px = 0.2f;
  m.mirror_outer_radius_px = 1.4f;
  m.mirror_elevation_inner_rad = -0.7f;
  m.mirror_elevation_outer_rad = 0.35f;
  m.data_size = 12;
  for (int i = 0; i < 12; ++i) m.data.push_back(static_cast<uint8_t>(20 * i));
  return m;
}

place_cell_match_t SamplePlaceCellMatch() {
  place_cell_match_t m{};
  m.utime = 1700000000000000;
  m.cell_id = 7;
  m.distance_measure = place_cell_match_t::BEARING_DIFFERENCE;
  m.distance = 0.05f;
  m.score = 0.1f;
  m.ncandidates = 20;
  m.x_m = 1;
  m.y_m = 2;
  m.theta_rad = 0.5;
  return m;
}

point_map_t SamplePointMap() {
  point_map_t m{};
  m.utime = 1700000000000000;
  m.estimator = "laser_slam";
  m.resolution_m = 0.05f;
  m.npoints = 3;
  m.x_m = {1, 2, 3};
  m.y_m = {-1, 0, 1};
  return m;
}

occupancy_grid_t SampleOccupancyGrid() {
  occupancy_grid_t m{};
  m.utime = 1700000000000000;
  m.frame = "map";
  m.source = "laser_slam";
  m.resolution_m = 0.05f;
  m.origin_x_m = -1;
  m.origin_y_m = -2;
  m.origin_theta_rad = 0;
  m.width = 3;
  m.height = 2;
  m.ncells = 6;
  m.cells = {-1, 0, 100, 50, 0, -1};
  return m;
}

localization_status_t SampleLocalizationStatus() {
  localization_status_t m{};
  m.utime = 1700000000000000;
  m.state = localization_status_t::LOCALIZED;
  m.score = 0.9;
  m.global_score = 0.7;
  m.global_ambiguity = 0.3;
  m.global_candidates = 1000;
  m.global_ms = 12;
  m.position_sigma_m = 0.02;
  m.heading_sigma_deg = 0.5;
  m.scans = 10;
  m.global_searches = 2;
  m.relocalizations = 1;
  m.map = "map.yaml";
  return m;
}

map_request_t SampleMapRequest() {
  map_request_t m{};
  m.utime = 1700000000000000;
  m.requester = "map-export";
  return m;
}

pose_correction_t SamplePoseCorrection() {
  pose_correction_t m{};
  m.utime = 1700000000000000;
  m.pose_channel = "POSE_EKF";  // the shipped placecells.ini's explore pose
  m.corrections = 1;
  m.ranges = 2;
  m.from_utime = {1700000000000000 - 1000000, 1700000000000000 - 500000};
  m.x_m = {0, 0.1};
  m.y_m = {0, -0.05};
  m.theta_rad = {0, 0.02};
  return m;
}

pose_t SamplePose() {
  pose_t m{};
  m.utime = 1700000000000000;
  m.estimator = "place_cells";
  m.frame = "map";
  m.x_m = 3.5;
  m.y_m = 3.0;
  m.theta_rad = 0.1;
  m.covariance[0] = m.covariance[4] = 0.01;
  m.covariance[8] = 0.003;
  return m;
}

waypoint_route_t SampleRoute() {
  waypoint_route_t m{};
  m.utime = 1700000000000000;
  m.name = "square";
  m.loop = true;
  m.tolerance_m = 0.1f;
  m.nwaypoints = 4;
  m.x_m = {2, 3, 3, 2};
  m.y_m = {2, 2, 3, 3};
  return m;
}

namespace {

bool AllFinite(std::initializer_list<double> values) {
  for (const double x : values) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}
template <class V>
bool AllFinite(const std::vector<V>& values) {
  for (const auto& x : values) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

template <class Msg>
TypeCase Case(const Msg& sample) {
  return {Msg::getTypeName(), glue::Encode(sample),
          [](const std::string& bytes, std::string* error) -> std::optional<std::string> {
            auto m = glue::Decode<Msg>(bytes.data(), bytes.size(), error);
            if (!m) return std::nullopt;
            return glue::Encode(*m);
          }};
}

}  // namespace

std::vector<TypeCase> AllTypes() {
  return {Case(SampleDriveCommand()), Case(SampleHomingVector()),    Case(SampleLandmarkSet()),
          Case(SampleLaserScan()),    Case(SampleNavigatorStatus()), Case(SampleOdometry()),
          Case(SampleOmniFrame()),    Case(SamplePlaceCellMatch()),  Case(SamplePointMap()),
          Case(SamplePose()),         Case(SampleRoute()),           Case(SampleExperienceMap()),
          Case(SampleFusedSlamStatus()), Case(SampleLaserSlamStatus()), Case(SampleOccupancyGrid()),
          Case(SampleLocalizationStatus()), Case(SampleMapRequest()), Case(SamplePoseCorrection())};
}

// "" when the published payload decodes and holds only finite numbers; else what is wrong.
std::string OutputProblem(const std::string& channel, const std::string& payload) {
  const auto fp = glue::PayloadFingerprint(payload.data(), payload.size());
  if (!fp) return channel + ": short payload";
  std::string error;
  auto bad = [&](bool ok, const char* type) { return ok ? std::string() : channel + ": non-finite " + type; };
  if (*fp == static_cast<uint64_t>(pose_t::getHash())) {
    const auto m = glue::Decode<pose_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    bool ok = AllFinite({m->x_m, m->y_m, m->theta_rad});
    for (const double c : m->covariance) ok = ok && std::isfinite(c);
    return bad(ok, "pose_t");
  }
  if (*fp == static_cast<uint64_t>(point_map_t::getHash())) {
    const auto m = glue::Decode<point_map_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(std::isfinite(m->resolution_m) && AllFinite(m->x_m) && AllFinite(m->y_m), "point_map_t");
  }
  if (*fp == static_cast<uint64_t>(landmark_set_t::getHash())) {
    const auto m = glue::Decode<landmark_set_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    bool ok = AllFinite(m->bearings_rad) && AllFinite(m->rows_px) && AllFinite(m->strengths) && AllFinite(m->scales_px);
    for (const auto& d : m->descriptors) ok = ok && AllFinite(d);
    return bad(ok, "landmark_set_t");
  }
  if (*fp == static_cast<uint64_t>(homing_vector_t::getHash())) {
    const auto m = glue::Decode<homing_vector_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->direction_rad, m->magnitude, m->compass_rotation_rad}), "homing_vector_t");
  }
  if (*fp == static_cast<uint64_t>(place_cell_match_t::getHash())) {
    const auto m = glue::Decode<place_cell_match_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->distance, m->score, m->x_m, m->y_m, m->theta_rad}), "place_cell_match_t");
  }
  if (*fp == static_cast<uint64_t>(drive_command_t::getHash())) {
    const auto m = glue::Decode<drive_command_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->linear_velocity_mps, m->angular_velocity_radps}), "drive_command_t");
  }
  if (*fp == static_cast<uint64_t>(navigator_status_t::getHash())) {
    const auto m = glue::Decode<navigator_status_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->waypoint_x_m, m->waypoint_y_m, m->distance_to_waypoint_m, m->heading_error_rad, m->x_m,
                          m->y_m, m->theta_rad, m->position_sigma_m, m->linear_velocity_mps, m->angular_velocity_radps}),
               "navigator_status_t");
  }
  if (*fp == static_cast<uint64_t>(experience_map_t::getHash())) {
    const auto m = glue::Decode<experience_map_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->robot_x_m, m->robot_y_m, m->robot_theta_rad}) && AllFinite(m->x_m) &&
                   AllFinite(m->y_m) && AllFinite(m->theta_rad),
               "experience_map_t");
  }
  if (*fp == static_cast<uint64_t>(fused_slam_status_t::getHash())) {
    const auto m = glue::Decode<fused_slam_status_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->last_mahalanobis2, m->last_fit, m->x_m, m->y_m, m->theta_rad, m->position_sigma_m}),
               "fused_slam_status_t");
  }
  if (*fp == static_cast<uint64_t>(laser_slam_status_t::getHash())) {
    const auto m = glue::Decode<laser_slam_status_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->mahalanobis2, m->gate_mahalanobis2, m->ambiguity, m->fit, m->kernel, m->position_sigma_m,
                          m->heading_sigma_deg, m->correction_m, m->correction_deg}),
               "laser_slam_status_t");
  }
  if (*fp == static_cast<uint64_t>(occupancy_grid_t::getHash())) {
    const auto m = glue::Decode<occupancy_grid_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    if (const auto problem = glue::CheckOccupancyGrid(*m)) return channel + ": malformed occupancy_grid_t: " + problem->reason;
    return "";
  }
  if (*fp == static_cast<uint64_t>(localization_status_t::getHash())) {
    const auto m = glue::Decode<localization_status_t>(payload.data(), payload.size(), &error);
    if (!m) return channel + ": " + error;
    return bad(AllFinite({m->score, m->global_score, m->global_ambiguity, m->global_ms, m->position_sigma_m, m->heading_sigma_deg}),
               "localization_status_t");
  }
  return channel + ": unexpected output type";
}


}  // namespace snapnav::fuzz
