// CARMEN importer: inline logs written by the tests (no files from outside the project).

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <sstream>

#include "importer_test_util.hpp"
#include "importers.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::importers {
namespace {

using testing::Errors;
using testing::HasError;
using testing::TempDir;
using testing::VectorSink;

constexpr char kLaser[] = "LASER_SCAN";
constexpr char kOdometry[] = "ODOMETRY";
constexpr char kPose[] = "POSE_CARMEN";

ImportReport Import(const std::string& text, VectorSink& sink, const CarmenOptions& options = {}) {
  std::istringstream in(text);
  return ImportCarmen(in, "test.log", sink, options);
}

// Three FLASER lines. The second moves the robot 0.3 m forward along its heading 0.5 rad and
// turns it by 0.1 rad in 0.2 s; its laser pose ("corrected", x y theta) differs from odometry.
const char kThreeScans[] =
    "# CARMEN test log\n"
    "PARAM robot_frontlaser_offset 0.0 99.0 testhost 0.0\n"
    "FLASER 5 1.00 2.00 81.91 0.50 90.00 10.0 20.0 0.5 10.0 20.0 0.5 100.000000 testhost 0.100\n"
    "SYNC 100.1 testhost 0.2\n"
    "FLASER 5 1.10 2.10 81.95 0.60 3.00 5.0 6.0 -1.0 10.263275 20.143828 0.6 100.200000 testhost 0.300\n"
    "FLASER 4 1.0 1.0 1.0 1.0 11.0 21.0 0.7 11.0 21.0 0.7 100.400000 testhost 0.500\n";

TEST(CarmenImport, FlaserCountsUnitsAndOdometryIncrements) {
  VectorSink sink;
  const auto report = Import(kThreeScans, sink);
  EXPECT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), 3);
  EXPECT_EQ(report.Count(kOdometry), 3);
  EXPECT_EQ(report.Count(kPose), 3);
  EXPECT_EQ(report.comment_lines, 1);
  EXPECT_EQ(report.skipped.at("PARAM"), 1);
  EXPECT_EQ(report.skipped.at("SYNC"), 1);
  EXPECT_EQ(report.synthesized_utimes, 0);

  const auto scans = sink.Decoded<laser_scan_t>(kLaser);
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(scans[0].utime, 100000000);
  EXPECT_EQ(scans[1].utime, 100200000);
  ASSERT_EQ(scans[0].nranges, 5);
  ASSERT_EQ(scans[0].ranges_m.size(), 5u);
  // Metres as logged; 81.91 (SICK's no return) and anything >= 81.9 become range_max_m.
  EXPECT_FLOAT_EQ(scans[0].range_max_m, 81.91f);
  EXPECT_FLOAT_EQ(scans[0].range_min_m, 0.0f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[0], 1.0f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[1], 2.0f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[2], 81.91f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[3], 0.5f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[4], 81.91f);
  EXPECT_FLOAT_EQ(scans[1].ranges_m[2], 81.91f);
  EXPECT_FLOAT_EQ(scans[1].ranges_m[4], 3.0f);
  // 180 degrees in radians, centred ahead: 5 beams -> 45 degrees apart, both ends included.
  EXPECT_NEAR(scans[0].angle_min_rad, -M_PI / 2, 1e-6);
  EXPECT_NEAR(scans[0].angle_increment_rad, M_PI / 4, 1e-6);
  EXPECT_NEAR(scans[0].angle_min_rad + 4 * scans[0].angle_increment_rad, M_PI / 2, 1e-6);
  // An even count (4) starts at the right end and stops one step short of the left one.
  ASSERT_EQ(scans[2].nranges, 4);
  EXPECT_NEAR(scans[2].angle_increment_rad, M_PI / 4, 1e-6);
  EXPECT_EQ(scans[2].nintensities, 0);
  EXPECT_FLOAT_EQ(scans[0].sensor_x_m, 0.0f);

  const auto odo = sink.Decoded<odometry_t>(kOdometry);
  ASSERT_EQ(odo.size(), 3u);
  EXPECT_DOUBLE_EQ(odo[0].x_m, 10.0);
  EXPECT_DOUBLE_EQ(odo[0].y_m, 20.0);
  EXPECT_DOUBLE_EQ(odo[0].theta_rad, 0.5);
  EXPECT_DOUBLE_EQ(odo[0].delta_x_m, 0.0);
  EXPECT_DOUBLE_EQ(odo[0].delta_t_s, 0.0);
  // The increment is in the previous robot frame: 0.3 m straight ahead, 0.1 rad left.
  EXPECT_NEAR(odo[1].delta_x_m, 0.3, 1e-5);
  EXPECT_NEAR(odo[1].delta_y_m, 0.0, 1e-5);
  EXPECT_NEAR(odo[1].delta_theta_rad, 0.1, 1e-9);
  EXPECT_NEAR(odo[1].delta_t_s, 0.2, 1e-9);
  EXPECT_NEAR(odo[1].linear_velocity_mps, 1.5, 1e-4);
  EXPECT_NEAR(odo[1].angular_velocity_radps, 0.5, 1e-6);
  EXPECT_DOUBLE_EQ(odo[1].x_m, 10.263275);

  // POSE_CARMEN carries the line's x y theta, not its odometry.
  const auto poses = sink.Decoded<pose_t>(kPose);
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_DOUBLE_EQ(poses[1].x_m, 5.0);
  EXPECT_DOUBLE_EQ(poses[1].y_m, 6.0);
  EXPECT_DOUBLE_EQ(poses[1].theta_rad, -1.0);
  EXPECT_EQ(poses[1].estimator, "carmen_log");
  EXPECT_EQ(poses[1].utime, scans[1].utime);

  // The report's figures agree.
  const auto& laser = report.channels.at(kLaser);
  EXPECT_EQ(laser.min_beams, 4);
  EXPECT_EQ(laser.max_beams, 5);
  EXPECT_EQ(laser.no_returns, 3);
  EXPECT_FLOAT_EQ(laser.max_return_m, 3.0f);
  EXPECT_EQ(laser.first_utime, 100000000);
  EXPECT_EQ(laser.last_utime, 100400000);
}

TEST(CarmenImport, FrontLaserOffsetMovesTheLoggedLaserPoseBackToTheRobot) {
  VectorSink sink;
  const auto report = Import(
      "PARAM robot_frontlaser_offset 0.25 1.0 h 1.0\n"
      "FLASER 3 1 1 1 1.25 2.0 0.0 1.0 2.0 0.0 2.0 h 2.0\n",
      sink);
  ASSERT_TRUE(report.ok()) << Errors(report);
  const auto scans = sink.Decoded<laser_scan_t>(kLaser);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_FLOAT_EQ(scans[0].sensor_x_m, 0.25f);
  const auto poses = sink.Decoded<pose_t>(kPose);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_NEAR(poses[0].x_m, 1.0, 1e-12);
  EXPECT_NEAR(poses[0].y_m, 2.0, 1e-12);
}

TEST(CarmenImport, MaxRangeOptionAndPrefix) {
  VectorSink sink;
  CarmenOptions options;
  options.flaser_max_range_m = 50.0;
  options.channels = ChannelNames::WithPrefix("RUN1_");
  const auto report = Import("FLASER 3 49.9 50.0 81.91 0 0 0 0 0 0 1.0 h 1.0\n", sink, options);
  ASSERT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.Count("LASER_SCAN"), 0);
  const auto scans = sink.Decoded<laser_scan_t>("RUN1_LASER_SCAN");
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_FLOAT_EQ(scans[0].range_max_m, 50.0f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[0], 49.9f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[1], 50.0f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[2], 50.0f);
  EXPECT_EQ(sink.Decoded<odometry_t>("RUN1_ODOMETRY").size(), 1u);
  EXPECT_EQ(sink.Decoded<pose_t>("RUN1_POSE_CARMEN").size(), 1u);
}

TEST(CarmenImport, TruncatedLastLineImportsTheValidLinesAndNamesTheLine) {
  std::string text = kThreeScans;
  // Cut the last line in the middle of its third reading ("1.0" -> "1.").
  const auto last = text.rfind("FLASER 4");
  text = text.substr(0, last) + "FLASER 4 1.0 1.0 1.";
  VectorSink sink;
  const auto report = Import(text, sink);
  EXPECT_FALSE(report.ok());
  EXPECT_EQ(report.error_count, 1);
  EXPECT_TRUE(HasError(report, "test.log:6:")) << Errors(report);
  EXPECT_TRUE(HasError(report, "truncated")) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), 2);
  EXPECT_EQ(report.Count(kOdometry), 2);
  EXPECT_EQ(sink.Decoded<laser_scan_t>(kLaser).size(), 2u);
}

TEST(CarmenImport, MalformedLinesAreReportedWithTheirLineAndTheRestImported) {
  const std::string text =
      "FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.0 h 0.1\n"        // 1 valid
      "FLASER 5 1 2 x 4 5 0 0 0 0 0 0 1.1 h 0.2\n"        // 2 not a number
      "FLASER 6 1 2 3 4 5 0 0 0 0 0 0 1.2 h 0.3\n"        // 3 count does not match
      "FLASER\n"                                          // 4 no count
      "FLASER 99999999999999 1 2 3\n"                     // 5 absurd count
      "FLASER -3 1 2 3\n"                                 // 6 negative count
      "ODOM 1 2 3 0 0 0 1.3 h\n"                          // 7 too few fields
      "flaser 1 2\n"                                      // 8 not a message kind
      "FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.4 h 0.4\n"        // 9 valid
      "FLASER 5 1 2 3 4 nan 0 0 0 0 0 0 1.5 h 0.5\n"      // 10 nan
      "FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.6 h 0.6 extra\n"  // 11 too many fields
      "FLASER 5 1 2 3 4 5 0 0 0 0 0 0 1.7e h 0.7\n";      // 12 bad timestamp
  VectorSink sink;
  const auto report = Import(text, sink);
  EXPECT_EQ(report.Count(kLaser), 2);
  EXPECT_EQ(report.error_count, 10) << Errors(report);
  for (int line : {2, 3, 4, 5, 6, 7, 8, 10, 11, 12}) {
    EXPECT_TRUE(HasError(report, "test.log:" + std::to_string(line) + ": ")) << line << "\n" << Errors(report);
  }
  EXPECT_TRUE(HasError(report, "test.log:2: FLASER reading 3 (field 5) is not a number: 'x'")) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log:3: FLASER declares 6 readings")) << Errors(report);
  EXPECT_TRUE(HasError(report, "outside 0..100000")) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log:12: FLASER timestamp")) << Errors(report);
  const auto scans = sink.Decoded<laser_scan_t>(kLaser);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[1].utime, 1400000);
}

TEST(CarmenImport, OdomLinesAreTheOdometryAndUntimedOdomLinesAreSkipped) {
  // As GMapping writes a corrected log: raw ODOM lines, and after each scan the corrected
  // pose as an ODOM line with timestamp 0.
  const std::string text =
      "ODOM 0 0 0 0.5 0.1 0 1.0 h 1.0\n"
      "FLASER 3 1 1 1 5 5 0 0 0 0 1.05 h 1.05\n"
      "ODOM 5 5 0 0 0 0 0 h 0\n"
      "NEFF 27.1 0 h 0\n"
      "ODOM 0.1 0 0 0.5 0.1 0 1.2 h 1.2\n";
  VectorSink sink;
  const auto report = Import(text, sink);
  ASSERT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.skipped.at("ODOM with timestamp 0"), 1);
  EXPECT_EQ(report.skipped.at("NEFF"), 1);
  const auto odo = sink.Decoded<odometry_t>(kOdometry);
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_EQ(odo[0].utime, 1000000);
  EXPECT_DOUBLE_EQ(odo[0].linear_velocity_mps, 0.5);
  EXPECT_DOUBLE_EQ(odo[0].angular_velocity_radps, 0.1);
  EXPECT_NEAR(odo[1].delta_x_m, 0.1, 1e-12);
  EXPECT_NEAR(odo[1].delta_t_s, 0.2, 1e-9);
  EXPECT_EQ(report.Count(kLaser), 1);
  const auto poses = sink.Decoded<pose_t>(kPose);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_DOUBLE_EQ(poses[0].x_m, 5.0);
  EXPECT_EQ(poses[0].utime, 1050000);
}

TEST(CarmenImport, RobotLaser1) {
  const std::string text =
      // robot at (1, 2) facing +y, laser 0.2 m ahead of it; 3 readings, 3 remissions.
      "ROBOTLASER1 0 -0.5 1.0 0.5 50.0 0.01 0 3 1.5 60.0 2.5 3 100 200 300 "
      "1.0 2.2 1.5707963 1.0 2.0 1.5707963 0.3 0.1 0.5 0.2 0.0 50.000000 host 0.5\n"
      // clockwise scan (negative resolution), no remissions.
      "ROBOTLASER1 0 0.5 1.0 -0.5 50.0 0.01 0 3 1.0 2.0 3.0 0 "
      "1.0 2.2 1.5707963 1.0 2.0 1.5707963 0.3 0.1 0.5 0.2 0.0 50.100000 host 0.6\n"
      // remission count that does not fit the line.
      "ROBOTLASER1 0 0.5 1.0 -0.5 50.0 0.01 0 3 1.0 2.0 3.0 7 1 2 "
      "1.0 2.2 1.5707963 1.0 2.0 1.5707963 0.3 0.1 0.5 0.2 0.0 50.200000 host 0.7\n"
      // reading count beyond the line.
      "ROBOTLASER1 0 0.5 1.0 -0.5 50.0 0.01 0 400 1.0 2.0\n";
  VectorSink sink;
  const auto report = Import(text, sink);
  EXPECT_EQ(report.error_count, 2) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log:3: ROBOTLASER1 declares 3 readings and 7 remissions")) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log:4: ROBOTLASER1 declares 400 readings")) << Errors(report);

  const auto scans = sink.Decoded<laser_scan_t>(kLaser);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[0].utime, 50000000);
  EXPECT_FLOAT_EQ(scans[0].angle_min_rad, -0.5f);
  EXPECT_FLOAT_EQ(scans[0].angle_increment_rad, 0.5f);
  EXPECT_FLOAT_EQ(scans[0].range_max_m, 50.0f);
  ASSERT_EQ(scans[0].nranges, 3);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[0], 1.5f);
  EXPECT_FLOAT_EQ(scans[0].ranges_m[1], 50.0f);  // 60 m is beyond maximum_range: no return
  EXPECT_FLOAT_EQ(scans[0].ranges_m[2], 2.5f);
  ASSERT_EQ(scans[0].nintensities, 3);
  EXPECT_FLOAT_EQ(scans[0].intensities[2], 300.0f);
  // Mounting from laser_pose relative to robot_pose.
  EXPECT_NEAR(scans[0].sensor_x_m, 0.2, 1e-6);
  EXPECT_NEAR(scans[0].sensor_y_m, 0.0, 1e-6);
  EXPECT_NEAR(scans[0].sensor_theta_rad, 0.0, 1e-6);
  // The clockwise scan is stored counter-clockwise.
  EXPECT_FLOAT_EQ(scans[1].angle_min_rad, -0.5f);
  EXPECT_FLOAT_EQ(scans[1].angle_increment_rad, 0.5f);
  EXPECT_FLOAT_EQ(scans[1].ranges_m[0], 3.0f);
  EXPECT_FLOAT_EQ(scans[1].ranges_m[2], 1.0f);
  EXPECT_EQ(scans[1].nintensities, 0);

  const auto odo = sink.Decoded<odometry_t>(kOdometry);
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_DOUBLE_EQ(odo[0].x_m, 1.0);
  EXPECT_DOUBLE_EQ(odo[0].y_m, 2.0);
  EXPECT_DOUBLE_EQ(odo[0].theta_rad, 1.5707963);
  EXPECT_DOUBLE_EQ(odo[0].linear_velocity_mps, 0.3);
  EXPECT_DOUBLE_EQ(odo[0].angular_velocity_radps, 0.1);
  EXPECT_NEAR(odo[1].delta_t_s, 0.1, 1e-9);
  const auto poses = sink.Decoded<pose_t>(kPose);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_DOUBLE_EQ(poses[0].y_m, 2.0);
}

TEST(CarmenImport, UnusableTimestampsAreSynthesizedAndSaidSo) {
  // Timestamps truncated to 6 digits: consecutive scans share a time.
  const std::string text =
      "FLASER 3 1 1 1 0 0 0 0 0 0 1.13486e+09 h 1.13486e+09\n"
      "FLASER 3 1 1 1 0 0 0 0.1 0 0 1.13486e+09 h 1.13486e+09\n"
      "FLASER 3 1 1 1 0 0 0 0.2 0 0 1.13487e+09 h 1.13487e+09\n";
  {
    VectorSink sink;
    const auto report = Import(text, sink);
    ASSERT_TRUE(report.ok()) << Errors(report);
    const auto scans = sink.Decoded<laser_scan_t>(kLaser);
    ASSERT_EQ(scans.size(), 3u);
    EXPECT_EQ(scans[0].utime, 1134860000000000);
    EXPECT_EQ(scans[1].utime, 1134860000100000);  // 10 Hz by default
    EXPECT_EQ(scans[2].utime, 1134860000200000);
    EXPECT_EQ(report.synthesized_utimes, 9);
    bool said = false;
    for (const auto& n : report.notes)
      said |= n.find("synthesized") != std::string::npos && n.find("line 2") != std::string::npos;
    EXPECT_TRUE(said);
    const auto odo = sink.Decoded<odometry_t>(kOdometry);
    EXPECT_NEAR(odo[1].delta_t_s, 0.1, 1e-9);
    EXPECT_NEAR(odo[1].linear_velocity_mps, 1.0, 1e-9);
  }
  {
    VectorSink sink;
    CarmenOptions options;
    options.time_source = TimeSource::kLog;
    const auto report = Import(text, sink, options);
    const auto scans = sink.Decoded<laser_scan_t>(kLaser);
    ASSERT_EQ(scans.size(), 3u);
    EXPECT_EQ(scans[1].utime, 1134860000000000);
    EXPECT_EQ(report.synthesized_utimes, 0);
  }
  {
    VectorSink sink;
    CarmenOptions options;
    options.time_source = TimeSource::kSynthesize;
    options.rate_hz = 4;
    Import(kThreeScans, sink, options);
    const auto scans = sink.Decoded<laser_scan_t>(kLaser);
    ASSERT_EQ(scans.size(), 3u);
    EXPECT_EQ(scans[0].utime, 100000000);
    EXPECT_EQ(scans[2].utime, 100500000);
  }
}

TEST(CarmenImport, NotACarmenLogIsAnErrorWithoutCrash) {
  std::string garbage;
  for (int i = 0; i < 20000; ++i) garbage.push_back(static_cast<char>((i * 7919) % 256));
  VectorSink sink;
  auto report = Import(garbage, sink);
  EXPECT_FALSE(report.ok());
  EXPECT_EQ(report.error_count, 1) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log is not a CARMEN log: byte 0 (line 1) is binary data (0x00)"))
      << Errors(report);
  EXPECT_TRUE(sink.events.empty());

  // A 5 MB line without newline is refused, not buffered whole.
  report = Import(std::string(5 << 20, 'A'), sink);
  EXPECT_EQ(report.error_count, 1) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log is not a CARMEN log: line 1 is longer than")) << Errors(report);

  report = Import("", sink);
  EXPECT_TRUE(HasError(report, "empty file")) << Errors(report);
}

// Binary data or text of another kind before the first CARMEN message: one error naming the file
// and where it stopped looking like one, not one per line (a binary file of 493 "lines" gave 493).
TEST(CarmenImport, BinaryOrOtherTextIsNotACarmenLogInOneError) {
  std::string binary = "# a comment is fine\n";
  for (int line = 0; line < 493; ++line) {
    for (int i = 0; i < 40; ++i) binary.push_back(static_cast<char>(0x80 + (line * 31 + i * 7) % 100));
    binary.push_back(line == 2 ? '\0' : 'x');
    binary.push_back('\n');
  }
  // Lines 2 and 3 are high bytes only (not a CARMEN message); line 4 holds a NUL byte at byte
  // 20 + 2 * 42 + 40.
  VectorSink sink;
  auto report = Import(binary, sink);
  EXPECT_EQ(report.error_count, 1) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log is not a CARMEN log: byte " + std::to_string(20 + 2 * 42 + 40) +
                                   " (line 4) is binary data (0x00)"))
      << Errors(report);
  EXPECT_TRUE(HasError(report, "a CARMEN log is text")) << Errors(report);
  EXPECT_TRUE(sink.events.empty());

  std::string csv = "x,y,theta\n";
  for (int i = 0; i < 600; ++i) csv += std::to_string(i) + ",0.5,0.1\n";
  report = Import(csv, sink);
  EXPECT_EQ(report.error_count, 1) << Errors(report);
  EXPECT_TRUE(HasError(report,
                       "test.log is not a CARMEN log: none of its first 5 lines (besides comments) is a CARMEN "
                       "message (line 1 starts with 'x,y,theta')"))
      << Errors(report);

  // A log whose first lines are damaged is still a CARMEN log: those lines are errors, the rest is imported.
  report = Import("garbage here\n12 34\n" + std::string(kThreeScans), sink);
  EXPECT_EQ(report.error_count, 2) << Errors(report);
  EXPECT_TRUE(HasError(report, "test.log:1: not a CARMEN message")) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), 3);
}

TEST(CarmenImport, GzipFileImportsLikeThePlainOneAndATruncatedGzipIsNamed) {
  TempDir dir;
  std::string text = "# many lines\n";
  for (int i = 0; i < 400; ++i) {
    text += "FLASER 5 1.0 2.0 3.0 4.0 5.0 0 0 0 " + std::to_string(0.01 * i) + " 0 0 " + std::to_string(1000 + i) +
            ".5 host 1.0\n";
  }
  testing::WriteFile(dir.File("plain.log"), text);
  const std::string gz = dir.File("log.gz");
  gzFile f = gzopen(gz.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())), static_cast<int>(text.size()));
  gzclose(f);

  VectorSink plain_sink, gz_sink;
  const auto plain = ImportCarmenFile(dir.File("plain.log"), plain_sink, {});
  const auto packed = ImportCarmenFile(gz, gz_sink, {});
  ASSERT_TRUE(plain.ok()) << Errors(plain);
  ASSERT_TRUE(packed.ok()) << Errors(packed);
  EXPECT_EQ(plain.Count(kLaser), 400);
  ASSERT_EQ(plain_sink.events.size(), gz_sink.events.size());
  for (size_t i = 0; i < plain_sink.events.size(); ++i) {
    EXPECT_EQ(plain_sink.events[i].payload, gz_sink.events[i].payload);
  }

  const std::string bytes = testing::ReadFile(gz);
  testing::WriteFile(dir.File("cut.gz"), bytes.substr(0, bytes.size() / 2));
  VectorSink cut_sink;
  const auto cut = ImportCarmenFile(dir.File("cut.gz"), cut_sink, {});
  EXPECT_FALSE(cut.ok());
  EXPECT_TRUE(HasError(cut, dir.File("cut.gz") + ": gzip data truncated")) << Errors(cut);
  EXPECT_GT(cut.Count(kLaser), 0);
  EXPECT_LT(cut.Count(kLaser), 400);
  for (size_t i = 0; i < cut_sink.events.size(); ++i) {
    EXPECT_EQ(cut_sink.events[i].payload, plain_sink.events[i].payload);
  }

  VectorSink missing_sink;
  const auto missing = ImportCarmenFile(dir.File("missing.log"), missing_sink, {});
  EXPECT_TRUE(HasError(missing, "missing.log: cannot open")) << Errors(missing);
}

TEST(CarmenImport, LcmLogSinkWritesEveryMessageAsAnEvent) {
  TempDir dir;
  const std::string path = dir.File("out.lcmlog");
  VectorSink expected;
  Import(kThreeScans, expected);
  {
    LcmLogSink sink(path);
    std::istringstream in(kThreeScans);
    ImportCarmen(in, "test.log", sink, {});
    sink.Close();
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  size_t n = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ASSERT_LT(n, expected.events.size());
    EXPECT_EQ(e->channel, expected.events[n].channel);
    EXPECT_EQ(e->timestamp, expected.events[n].utime);
    EXPECT_EQ(std::string(static_cast<const char*>(e->data), e->datalen), expected.events[n].payload);
    ++n;
  }
  EXPECT_EQ(n, expected.events.size());
  EXPECT_EQ(n, 9u);
}

}  // namespace
}  // namespace snapnav::importers
