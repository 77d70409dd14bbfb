// Encode/decode round trips of every message type; bad payloads are errors, not crashes.
#include <gtest/gtest.h>

#include <cmath>

#include "snapnav/drive_command_t.hpp"
#include "snapnav/experience_map_t.hpp"
#include "snapnav/fused_slam_status_t.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/place_cell_match_t.hpp"
#include "snapnav/point_map_t.hpp"
#include "snapnav/pose_t.hpp"
#include "snapnav/waypoint_route_t.hpp"

namespace snapnav {
namespace {

using glue::Decode;
using glue::Encode;

omni_frame_t SampleFrame() {
  omni_frame_t m;
  m.utime = 123456789;
  m.sensor_name = "omni";
  m.kind = omni_frame_t::RAW_OMNI;
  m.width = 4;
  m.height = 3;
  m.row_stride = 4;
  m.encoding = omni_frame_t::GRAY8;
  m.mirror_center_x_px = 2.5f;
  m.mirror_center_y_px = 1.5f;
  m.mirror_inner_radius_px = 0.5f;
  m.mirror_outer_radius_px = 1.5f;
  m.mirror_elevation_inner_rad = -0.7f;
  m.mirror_elevation_outer_rad = 0.5f;
  m.bearing_col0_rad = 0.0f;
  m.elevation_top_rad = m.elevation_bottom_rad = 0.0f;
  m.data_size = 12;
  m.data.resize(12);
  for (int i = 0; i < 12; ++i) m.data[i] = static_cast<uint8_t>(i * 20);
  return m;
}

laser_scan_t SampleScan() {
  laser_scan_t m;
  m.utime = 42;
  m.sensor_name = "hokuyo";
  m.sensor_x_m = 0.1f;
  m.sensor_y_m = 0;
  m.sensor_theta_rad = 0;
  m.angle_min_rad = static_cast<float>(-2.0944);
  m.angle_increment_rad = static_cast<float>(4.1888 / 680);
  m.time_increment_s = 0;
  m.range_min_m = 0.02f;
  m.range_max_m = 5.6f;
  m.nranges = 681;
  m.ranges_m.resize(681);
  for (int i = 0; i < 681; ++i) m.ranges_m[i] = 0.5f + 0.001f * i;
  m.nintensities = 0;
  return m;
}

template <class Msg>
Msg RoundTrip(const Msg& m) {
  const std::string bytes = Encode(m);
  std::string error;
  auto out = Decode<Msg>(bytes.data(), bytes.size(), &error);
  EXPECT_TRUE(out.has_value()) << error;
  return out.value_or(Msg{});
}

TEST(LcmTypes, OmniFrameRoundTrip) {
  const auto m = SampleFrame();
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.utime, m.utime);
  EXPECT_EQ(r.sensor_name, "omni");
  EXPECT_EQ(r.width, 4);
  EXPECT_EQ(r.encoding, omni_frame_t::GRAY8);
  EXPECT_FLOAT_EQ(r.mirror_outer_radius_px, 1.5f);
  EXPECT_FLOAT_EQ(r.mirror_elevation_outer_rad, 0.5f);
  EXPECT_EQ(r.data, m.data);
}

TEST(LcmTypes, LaserScanRoundTrip) {
  const auto m = SampleScan();
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.nranges, 681);
  EXPECT_EQ(r.ranges_m, m.ranges_m);
  EXPECT_FLOAT_EQ(r.range_max_m, 5.6f);
  EXPECT_EQ(r.nintensities, 0);
}

TEST(LcmTypes, OdometryRoundTrip) {
  odometry_t m{};
  m.utime = 7;
  m.sensor_name = "wheels";
  m.x_m = 1.5;
  m.theta_rad = -0.25;
  m.delta_x_m = 0.01;
  m.delta_theta_rad = 0.002;
  m.delta_t_s = 0.1;
  m.linear_velocity_mps = 0.1;
  const auto r = RoundTrip(m);
  EXPECT_DOUBLE_EQ(r.x_m, 1.5);
  EXPECT_DOUBLE_EQ(r.theta_rad, -0.25);
  EXPECT_DOUBLE_EQ(r.delta_theta_rad, 0.002);
  EXPECT_EQ(r.sensor_name, "wheels");
}

TEST(LcmTypes, PoseRoundTrip) {
  pose_t m{};
  m.utime = 9;
  m.estimator = "laser_slam";
  m.frame = "map";
  m.x_m = 3;
  m.y_m = -2;
  m.theta_rad = 1;
  for (int i = 0; i < 9; ++i) m.covariance[i] = i * 0.1;
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.estimator, "laser_slam");
  EXPECT_EQ(r.frame, "map");
  EXPECT_DOUBLE_EQ(r.covariance[8], 0.8);
}

TEST(LcmTypes, LandmarkSetRoundTripWith2dDescriptors) {
  landmark_set_t m{};
  m.utime = 11;
  m.sensor_name = "omni";
  m.method = landmark_set_t::SURF;
  m.panorama_width_px = 720;
  m.panorama_height_px = 120;
  m.nlandmarks = 3;
  m.bearings_rad = {0.1f, 0.2f, 0.3f};
  m.rows_px = {10, 20, 30};
  m.strengths = {1, 2, 3};
  m.scales_px = {1.6f, 3.2f, 6.4f};
  m.descriptor_length = 64;
  m.descriptors.assign(3, std::vector<float>(64));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 64; ++j) m.descriptors[i][j] = i + j / 64.0f;
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.method, landmark_set_t::SURF);
  EXPECT_EQ(r.descriptors, m.descriptors);
  EXPECT_EQ(r.bearings_rad, m.bearings_rad);
}

TEST(LcmTypes, HomingVectorRoundTrip) {
  homing_vector_t m{};
  m.utime = 5;
  m.method = landmark_set_t::SIFT;
  m.alv_variant = "weighted";
  m.valid = true;
  m.direction_rad = 2.0f;
  m.magnitude = 0.5f;
  m.compass_rotation_rad = -0.1f;
  m.nlandmarks_used = 20;
  const auto r = RoundTrip(m);
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(r.alv_variant, "weighted");
  EXPECT_EQ(r.nlandmarks_used, 20);
  EXPECT_FLOAT_EQ(r.compass_rotation_rad, -0.1f);
}

TEST(LcmTypes, PlaceCellMatchRoundTrip) {
  place_cell_match_t m{};
  m.utime = 1;
  m.cell_id = 17;
  m.distance_measure = place_cell_match_t::MATCH_COUNT;
  m.distance = 12;
  m.score = 0.3f;
  m.ncandidates = 100;
  m.x_m = 0.4;
  m.y_m = 0.6;
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.cell_id, 17);
  EXPECT_EQ(r.distance_measure, place_cell_match_t::MATCH_COUNT);
  EXPECT_DOUBLE_EQ(r.y_m, 0.6);
}

TEST(LcmTypes, DriveCommandPointMapRouteRoundTrip) {
  drive_command_t d{};
  d.utime = 3;
  d.source = "navigator";
  d.linear_velocity_mps = 0.2;
  d.angular_velocity_radps = -0.5;
  EXPECT_DOUBLE_EQ(RoundTrip(d).angular_velocity_radps, -0.5);

  point_map_t p{};
  p.utime = 4;
  p.estimator = "laser_slam";
  p.resolution_m = 0.05f;
  p.npoints = 2;
  p.x_m = {1, 2};
  p.y_m = {3, 4};
  EXPECT_EQ(RoundTrip(p).y_m, p.y_m);

  waypoint_route_t w{};
  w.utime = 5;
  w.name = "square";
  w.loop = true;
  w.tolerance_m = 0.15f;
  w.nwaypoints = 4;
  w.x_m = {0, 1, 1, 0};
  w.y_m = {0, 0, 1, 1};
  const auto rw = RoundTrip(w);
  EXPECT_TRUE(rw.loop);
  EXPECT_EQ(rw.x_m, w.x_m);
}

TEST(LcmTypes, ExperienceMapRoundTripAndBadLinkCount) {
  experience_map_t m{};
  m.utime = 6;
  m.estimator = "ratslam";
  m.frame = "map";
  m.templates = 12;
  m.loop_closures = 1;
  m.current_experience = 2;
  m.robot_x_m = 0.5;
  m.nexperiences = 3;
  m.x_m = {0, 1, 0.1};
  m.y_m = {0, 0, 0.05};
  m.theta_rad = {0, 1.5, 3.1};
  m.view_template = {0, 4, 11};
  m.nlinks = 3;
  m.link_from = {0, 1, 2};
  m.link_to = {1, 2, 0};
  m.link_loop_closure = {0, 0, 1};
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.theta_rad, m.theta_rad);
  EXPECT_EQ(r.view_template, m.view_template);
  EXPECT_EQ(r.link_loop_closure, m.link_loop_closure);
  EXPECT_EQ(r.current_experience, 2);
  // Every truncation is refused.
  const std::string bytes = Encode(m);
  for (size_t n = 0; n < bytes.size(); ++n) {
    std::string error;
    EXPECT_FALSE(Decode<experience_map_t>(bytes.data(), n, &error).has_value()) << n;
  }
}

TEST(LcmTypes, FusedSlamStatusRoundTrip) {
  fused_slam_status_t m{};
  m.utime = 9;
  m.state = fused_slam_status_t::SUSPECT;
  m.last_outcome = fused_slam_status_t::REJECTED;
  m.last_mahalanobis2 = 259.2;
  m.consecutive_rejections = 3;
  m.agreeing_rejections = 2;
  m.visual_accepted = 40;
  m.visual_rejected = 7;
  m.relocalizations = 1;
  m.map_points = 1234;
  m.x_m = 29.0;
  m.position_sigma_m = 0.2;
  const auto r = RoundTrip(m);
  EXPECT_EQ(r.state, fused_slam_status_t::SUSPECT);
  EXPECT_EQ(r.last_outcome, fused_slam_status_t::REJECTED);
  EXPECT_DOUBLE_EQ(r.last_mahalanobis2, 259.2);
  EXPECT_EQ(r.agreeing_rejections, 2);
  EXPECT_EQ(r.visual_rejected, 7);
  EXPECT_EQ(r.map_points, 1234);
  EXPECT_DOUBLE_EQ(r.x_m, 29.0);
}

TEST(LcmTypes, EveryTruncationIsAnErrorNotACrash) {
  const std::string bytes = Encode(SampleScan());
  for (size_t n = 0; n < bytes.size(); ++n) {
    std::string error;
    EXPECT_FALSE(Decode<laser_scan_t>(bytes.data(), n, &error).has_value()) << "prefix of " << n << " bytes";
    EXPECT_FALSE(error.empty());
  }
}

TEST(LcmTypes, WrongTypeIsReportedByName) {
  const std::string bytes = Encode(SampleFrame());
  std::string error;
  EXPECT_FALSE(Decode<laser_scan_t>(bytes.data(), bytes.size(), &error).has_value());
  EXPECT_NE(error.find("wrong type"), std::string::npos) << error;
  EXPECT_NE(error.find("laser_scan_t"), std::string::npos) << error;
}

TEST(LcmTypes, TrailingBytesAreAnError) {
  std::string bytes = Encode(SampleFrame()) + "xx";
  std::string error;
  EXPECT_FALSE(Decode<omni_frame_t>(bytes.data(), bytes.size(), &error).has_value());
  EXPECT_NE(error.find("trailing"), std::string::npos) << error;
}

// The count of an array is patched to 2^31 - 1 or negative: the hardened
// decoder rejects it before allocating.
TEST(LcmTypes, AbsurdOrNegativeCountsAreRejectedWithoutAllocating) {
  const auto scan = SampleScan();
  std::string bytes = Encode(scan);
  // nranges sits right before the 681 floats; find it by its value.
  const char want[4] = {0, 0, 0x02, static_cast<char>(0xA9)};  // 681 big-endian
  const size_t pos = bytes.find(std::string(want, 4));
  ASSERT_NE(pos, std::string::npos);
  for (const uint32_t count : {0x7fffffffu, 0x80000000u, 0xffffffffu, 682u}) {
    std::string bad = bytes;
    for (int i = 0; i < 4; ++i) bad[pos + i] = static_cast<char>((count >> (24 - 8 * i)) & 0xff);
    std::string error;
    EXPECT_FALSE(Decode<laser_scan_t>(bad.data(), bad.size(), &error).has_value()) << count;
  }
}

TEST(LcmTypes, CorruptStringLengthIsRejected) {
  std::string bytes = Encode(SampleFrame());
  // sensor_name length (5 = "omni" + NUL) follows fingerprint (8) and utime (8).
  for (const uint32_t len : {0u, 0xffffffffu, 0x7fffffffu}) {
    std::string bad = bytes;
    for (int i = 0; i < 4; ++i) bad[16 + i] = static_cast<char>((len >> (24 - 8 * i)) & 0xff);
    std::string error;
    EXPECT_FALSE(Decode<omni_frame_t>(bad.data(), bad.size(), &error).has_value()) << len;
  }
}

}  // namespace
}  // namespace snapnav
