// MRPT rawlog importer: the Malaga loop shipped by Debian's mrpt-common, rawlogs written by
// the tests with MRPT, truncated and corrupt copies, and files that are not rawlogs.

#include <gtest/gtest.h>
#include <mrpt/core/Clock.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>
#include <zlib.h>

#include <chrono>
#include <cmath>

#include "importer_test_util.hpp"
#include "importers.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"

namespace snapnav::importers {
namespace {

using testing::Errors;
using testing::HasError;
using testing::TempDir;
using testing::VectorSink;

constexpr char kLaser[] = "LASER_SCAN";
constexpr char kOdometry[] = "ODOMETRY";
const std::string kMalaga = SNAPNAV_MALAGA_RAWLOG;

// The Malaga loop: 225 sensory frames with one SICK scan each (the first one before any
// action), and 224 odometry increments in between.
constexpr int kMalagaScans = 225;
constexpr int kMalagaOdometry = 224;

std::string Gunzip(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");
  EXPECT_NE(f, nullptr) << path;
  std::string out;
  char buf[65536];
  int n = 0;
  while (f != nullptr && (n = gzread(f, buf, sizeof buf)) > 0) out.append(buf, static_cast<size_t>(n));
  if (f != nullptr) gzclose(f);
  return out;
}

mrpt::Clock::time_point At(double unix_seconds) { return mrpt::Clock::fromDouble(unix_seconds); }

// The first `n` messages of `part` equal those of `full`.
void ExpectPrefix(const VectorSink& part, const VectorSink& full) {
  ASSERT_LE(part.events.size(), full.events.size());
  for (size_t i = 0; i < part.events.size(); ++i) {
    EXPECT_EQ(part.events[i].channel, full.events[i].channel) << i;
    EXPECT_EQ(part.events[i].payload, full.events[i].payload) << i;
  }
}

class MalagaRawlog : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(std::ifstream(kMalaga).good()) << kMalaga << " is missing: install Debian's mrpt-common";
  }
};

TEST_F(MalagaRawlog, CountsAndPlausibleUnits) {
  VectorSink sink;
  const auto report = ImportRawlog(kMalaga, sink, {});
  ASSERT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), kMalagaScans);
  EXPECT_EQ(report.Count(kOdometry), kMalagaOdometry);
  EXPECT_EQ(report.synthesized_utimes, 0);
  EXPECT_EQ(report.out_of_order, 0);
  EXPECT_TRUE(report.skipped.empty());

  const auto scans = sink.Decoded<laser_scan_t>(kLaser);
  ASSERT_EQ(scans.size(), static_cast<size_t>(kMalagaScans));
  int64_t no_return = 0, readings = 0;
  float longest = 0;
  for (const auto& s : scans) {
    // A SICK LMS: 361 beams over 180 degrees, 80 m maximum range, 0.78 m ahead of the robot centre.
    ASSERT_EQ(s.nranges, 361);
    ASSERT_EQ(s.ranges_m.size(), 361u);
    EXPECT_NEAR(s.angle_min_rad, -M_PI / 2, 1e-6);
    EXPECT_NEAR(s.angle_increment_rad, M_PI / 360, 1e-7);
    EXPECT_FLOAT_EQ(s.range_max_m, 80.0f);
    EXPECT_NEAR(s.sensor_x_m, 0.78, 1e-6);
    EXPECT_NEAR(s.sensor_theta_rad, 0.0, 1e-6);
    for (float r : s.ranges_m) {
      ASSERT_GE(r, 0.0f);
      ASSERT_LE(r, s.range_max_m);
      ++readings;
      if (r >= s.range_max_m) {
        ++no_return;
      } else {
        longest = std::max(longest, r);
      }
    }
  }
  // Indoors: most beams hit something within tens of metres (centimetres would give thousands).
  EXPECT_LT(no_return, readings / 4);
  EXPECT_GT(longest, 10.0f);
  EXPECT_LT(longest, 80.0f);

  // Times: the recording of 2006-01-21 (the file's name), about a minute long, increasing.
  EXPECT_EQ(scans.front().utime, 1137834225713386);
  EXPECT_NEAR((scans.back().utime - scans.front().utime) * 1e-6, 59.1, 0.5);
  for (size_t i = 1; i < scans.size(); ++i) EXPECT_GT(scans[i].utime, scans[i - 1].utime);

  // Odometry: one loop through a building; the integrated increments.
  const auto odo = sink.Decoded<odometry_t>(kOdometry);
  ASSERT_EQ(odo.size(), static_cast<size_t>(kMalagaOdometry));
  double length = 0, x = 0, y = 0, theta = 0;
  double closest_return_m = 1e9;  // to the start, once far along the path
  for (size_t i = 0; i < odo.size(); ++i) {
    const auto& o = odo[i];
    const double c = std::cos(theta), s = std::sin(theta);
    x += c * o.delta_x_m - s * o.delta_y_m;
    y += s * o.delta_x_m + c * o.delta_y_m;
    theta += o.delta_theta_rad;
    EXPECT_NEAR(o.x_m, x, 1e-6) << i;
    EXPECT_NEAR(o.y_m, y, 1e-6) << i;
    EXPECT_NEAR(std::remainder(o.theta_rad - theta, 2 * M_PI), 0.0, 1e-6) << i;
    EXPECT_LT(std::hypot(o.delta_x_m, o.delta_y_m), 2.0) << "a step of metres in a quarter second: units?";
    length += std::hypot(o.delta_x_m, o.delta_y_m);
    if (length > 40.0) {
      closest_return_m = std::min(closest_return_m, std::hypot(o.x_m - odo.front().x_m, o.y_m - odo.front().y_m));
    }
    if (i > 0) {
      EXPECT_GT(o.delta_t_s, 0.0);
      EXPECT_LT(o.delta_t_s, 2.0);
      EXPECT_LT(std::fabs(o.linear_velocity_mps), 3.0) << "a robot indoors, not a car";
    }
  }
  EXPECT_GT(length, 30.0);
  EXPECT_LT(length, 200.0);
  EXPECT_NEAR(report.channels.at(kOdometry).path_length_m, length, 1e-6);
  // One loop: after 40 m the robot passes by its start again (then drives on down the first
  // corridor), odometry drift included.
  EXPECT_LT(closest_return_m, 3.0);

  // Read in this process instead of the isolated reader: the same messages.
  RawlogOptions in_process;
  in_process.isolate_reader = false;
  VectorSink same;
  const auto same_report = ImportRawlog(kMalaga, same, in_process);
  EXPECT_TRUE(same_report.ok()) << Errors(same_report);
  ASSERT_EQ(same.events.size(), sink.events.size());
  for (size_t i = 0; i < sink.events.size(); ++i) EXPECT_EQ(same.events[i].payload, sink.events[i].payload);
}

TEST_F(MalagaRawlog, TruncatedCompressedFileKeepsTheScansBeforeTheCut) {
  TempDir dir;
  VectorSink full;
  ImportRawlog(kMalaga, full, {});
  const std::string bytes = testing::ReadFile(kMalaga);
  testing::WriteFile(dir.File("cut.rawlog"), bytes.substr(0, bytes.size() / 2));
  VectorSink sink;
  const auto report = ImportRawlog(dir.File("cut.rawlog"), sink, {});
  EXPECT_FALSE(report.ok());
  EXPECT_EQ(report.error_count, 1);
  EXPECT_TRUE(HasError(report, dir.File("cut.rawlog") + ": byte offset ")) << Errors(report);
  EXPECT_TRUE(HasError(report, "truncated")) << Errors(report);
  EXPECT_GT(report.Count(kLaser), 50);
  EXPECT_LT(report.Count(kLaser), kMalagaScans);
  ExpectPrefix(sink, full);
}

TEST_F(MalagaRawlog, TruncatedPlainFileReportsTheOffsetOfTheCutObject) {
  TempDir dir;
  const std::string raw = Gunzip(kMalaga);
  ASSERT_GT(raw.size(), 100000u);
  testing::WriteFile(dir.File("plain.rawlog"), raw);
  VectorSink full;
  const auto full_report = ImportRawlog(dir.File("plain.rawlog"), full, {});
  ASSERT_TRUE(full_report.ok()) << Errors(full_report);
  EXPECT_EQ(full_report.Count(kLaser), kMalagaScans);

  const size_t cut = raw.size() / 3;
  testing::WriteFile(dir.File("cut.rawlog"), raw.substr(0, cut));
  VectorSink sink;
  const auto report = ImportRawlog(dir.File("cut.rawlog"), sink, {});
  ASSERT_EQ(report.error_count, 1) << Errors(report);
  const std::string& error = report.errors[0];
  const std::string prefix = dir.File("cut.rawlog") + ": byte offset ";
  ASSERT_EQ(error.rfind(prefix, 0), 0u) << error;
  const long offset = std::stol(error.substr(prefix.size()));
  // The object that is cut starts before the cut, less than one entry (~2.2 kB) before it.
  EXPECT_LE(offset, static_cast<long>(cut));
  EXPECT_GT(offset, static_cast<long>(cut) - 3000);
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_NEAR(report.Count(kLaser), kMalagaScans / 3, 3);
  ExpectPrefix(sink, full);
}

TEST(RawlogImport, NotARawlogIsAClearErrorWithoutCrash) {
  TempDir dir;
  testing::WriteFile(dir.File("notes.txt"), "this is a text file\nnot a rawlog\n");
  VectorSink sink;
  auto report = ImportRawlog(dir.File("notes.txt"), sink, {});
  EXPECT_FALSE(report.ok());
  EXPECT_TRUE(HasError(report, dir.File("notes.txt") + ": not an MRPT rawlog")) << Errors(report);
  EXPECT_TRUE(sink.events.empty());

  std::string noise;
  for (int i = 0; i < 100000; ++i) noise.push_back(static_cast<char>((i * 2654435761u) >> 13));
  testing::WriteFile(dir.File("noise.bin"), noise);
  report = ImportRawlog(dir.File("noise.bin"), sink, {});
  EXPECT_TRUE(HasError(report, "not an MRPT rawlog")) << Errors(report);

  testing::WriteFile(dir.File("empty.rawlog"), "");
  report = ImportRawlog(dir.File("empty.rawlog"), sink, {});
  EXPECT_TRUE(HasError(report, "empty file")) << Errors(report);

  report = ImportRawlog(dir.File("missing.rawlog"), sink, {});
  EXPECT_TRUE(HasError(report, "missing.rawlog: cannot open")) << Errors(report);
  report = ImportRawlog(dir.path(), sink, {});
  EXPECT_TRUE(HasError(report, "is a directory")) << Errors(report);
  EXPECT_TRUE(sink.events.empty());
}

mrpt::obs::CObservation2DRangeScan::Ptr MakeScan(size_t n, double t) {
  auto scan = mrpt::obs::CObservation2DRangeScan::Create();
  scan->aperture = static_cast<float>(M_PI);
  scan->maxRange = 30.0f;
  scan->resizeScanAndAssign(n, 1.0f, true);
  scan->timestamp = At(t);
  return scan;
}

TEST(RawlogImport, ObservationsOnlyFormat) {
  TempDir dir;
  const std::string path = dir.File("obs.rawlog.gz");
  const double t0 = 1.5e9;
  {
    mrpt::io::CFileGZOutputStream out(path);
    auto arch = mrpt::serialization::archiveFrom(out);
    mrpt::obs::CObservationOdometry odo;
    odo.odometry = mrpt::poses::CPose2D(0, 0, 0);
    odo.timestamp = At(t0);
    arch << odo;
    // Clockwise, with an invalid reading and intensities.
    mrpt::obs::CObservation2DRangeScan scan;
    scan.sensorLabel = "LIDAR";
    scan.aperture = static_cast<float>(M_PI / 2);
    scan.rightToLeft = false;
    scan.maxRange = 10.0f;
    scan.sensorPose = mrpt::poses::CPose3D(0.1, 0.2, 0.3, 0.3, 0, 0);
    scan.resizeScan(3);
    scan.setScanHasIntensity(true);
    for (size_t i = 0; i < 3; ++i) {
      scan.setScanRange(i, static_cast<float>(i + 1));
      scan.setScanRangeValidity(i, i != 1);
      scan.setScanIntensity(i, static_cast<int>(10 * (i + 1)));
    }
    scan.timestamp = At(t0 + 0.05);
    arch << scan;
    odo.odometry = mrpt::poses::CPose2D(1, 0, 0);
    odo.timestamp = At(t0 + 0.1);
    odo.hasVelocities = true;
    odo.velocityLocal = mrpt::math::TTwist2D(0.5, 0, 0.25);
    arch << odo;
    mrpt::obs::CObservationComment comment;
    comment.text = "hello";
    comment.timestamp = At(t0 + 0.15);
    arch << comment;
    odo.odometry = mrpt::poses::CPose2D(1, 1, M_PI / 2);
    odo.hasVelocities = false;
    odo.timestamp = INVALID_TIMESTAMP;  // no time: synthesized after the previous message
    arch << odo;
  }
  VectorSink sink;
  const auto report = ImportRawlog(path, sink, {});
  ASSERT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), 1);
  EXPECT_EQ(report.Count(kOdometry), 3);
  ASSERT_EQ(report.skipped.size(), 1u);
  EXPECT_NE(report.skipped.begin()->first.find("CObservationComment"), std::string::npos);
  EXPECT_EQ(report.synthesized_utimes, 1);

  const auto scans = sink.Decoded<laser_scan_t>(kLaser);
  ASSERT_EQ(scans.size(), 1u);
  const auto& s = scans[0];
  EXPECT_EQ(s.sensor_name, "LIDAR");
  EXPECT_NEAR(s.utime, 1500000000050000, 1);
  EXPECT_NEAR(s.angle_min_rad, -M_PI / 4, 1e-6);
  EXPECT_NEAR(s.angle_increment_rad, M_PI / 4, 1e-6);
  EXPECT_NEAR(s.sensor_x_m, 0.1, 1e-6);
  EXPECT_NEAR(s.sensor_y_m, 0.2, 1e-6);
  EXPECT_NEAR(s.sensor_theta_rad, 0.3, 1e-6);
  EXPECT_FLOAT_EQ(s.range_max_m, 10.0f);
  // Stored counter-clockwise; the invalid reading is range_max_m.
  ASSERT_EQ(s.nranges, 3);
  EXPECT_FLOAT_EQ(s.ranges_m[0], 3.0f);
  EXPECT_FLOAT_EQ(s.ranges_m[1], 10.0f);
  EXPECT_FLOAT_EQ(s.ranges_m[2], 1.0f);
  ASSERT_EQ(s.nintensities, 3);
  EXPECT_FLOAT_EQ(s.intensities[0], 30.0f);
  EXPECT_FLOAT_EQ(s.intensities[2], 10.0f);

  const auto odo = sink.Decoded<odometry_t>(kOdometry);
  ASSERT_EQ(odo.size(), 3u);
  EXPECT_NEAR(odo[0].utime, 1500000000000000, 1);
  EXPECT_NEAR(odo[1].delta_x_m, 1.0, 1e-12);
  EXPECT_NEAR(odo[1].delta_t_s, 0.1, 1e-5);
  EXPECT_DOUBLE_EQ(odo[1].linear_velocity_mps, 0.5);
  EXPECT_DOUBLE_EQ(odo[1].angular_velocity_radps, 0.25);
  // From (1, 0, 0) to (1, 1, pi/2): 1 m to the left, a quarter turn.
  EXPECT_NEAR(odo[2].delta_x_m, 0.0, 1e-12);
  EXPECT_NEAR(odo[2].delta_y_m, 1.0, 1e-12);
  EXPECT_NEAR(odo[2].delta_theta_rad, M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(odo[2].x_m, 1.0);
  EXPECT_DOUBLE_EQ(odo[2].y_m, 1.0);
  // The untimed one follows the previous message (odometry at t0 + 0.1) by 1/10 s.
  EXPECT_EQ(odo[2].utime, odo[1].utime + 100000);
}

TEST(RawlogImport, ActionSensoryFrameFormatIntegratesIncrements) {
  TempDir dir;
  const std::string path = dir.File("pairs.rawlog");
  const double t0 = 1.2e9;
  const mrpt::poses::CPose2D increments[3] = {{1, 0, 0}, {1, 0, M_PI / 2}, {1, 0, 0}};
  {
    mrpt::io::CFileOutputStream out(path);
    auto arch = mrpt::serialization::archiveFrom(out);
    for (int k = 0; k < 4; ++k) {
      if (k > 0) {
        mrpt::obs::CActionRobotMovement2D move;
        move.computeFromOdometry(increments[k - 1], mrpt::obs::CActionRobotMovement2D::TMotionModelOptions());
        // The first increment has no time of its own: it takes its sensory frame's.
        move.timestamp = k == 1 ? INVALID_TIMESTAMP : At(t0 + k - 0.5);
        mrpt::obs::CActionCollection actions;
        actions.insert(move);
        arch << actions;
      }
      mrpt::obs::CSensoryFrame frame;
      frame.insert(MakeScan(181, t0 + k));
      arch << frame;
    }
  }
  VectorSink sink;
  const auto report = ImportRawlog(path, sink, {});
  ASSERT_TRUE(report.ok()) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), 4);
  const auto odo = sink.Decoded<odometry_t>(kOdometry);
  ASSERT_EQ(odo.size(), 3u);
  EXPECT_NEAR(odo[0].utime, 1200000001000000, 1);  // the first sensory frame's time
  EXPECT_NEAR(odo[1].utime, 1200000001500000, 1);  // its own time
  EXPECT_NEAR(odo[0].x_m, 1.0, 1e-9);
  EXPECT_NEAR(odo[1].x_m, 2.0, 1e-9);
  EXPECT_NEAR(odo[1].theta_rad, M_PI / 2, 1e-9);
  EXPECT_NEAR(odo[2].x_m, 2.0, 1e-9);
  EXPECT_NEAR(odo[2].y_m, 1.0, 1e-9);
  EXPECT_NEAR(odo[2].delta_x_m, 1.0, 1e-9);
  EXPECT_NEAR(odo[2].delta_t_s, 1.0, 1e-5);
  EXPECT_NEAR(odo[2].linear_velocity_mps, 1.0, 1e-5);
  // Time order: scan 0, odometry 1, scan 1, ...
  ASSERT_EQ(sink.events.size(), 7u);
  EXPECT_EQ(sink.events[0].channel, kLaser);
  EXPECT_EQ(sink.events[1].channel, kOdometry);
  EXPECT_EQ(report.out_of_order, 0);
}

TEST(RawlogImport, CorruptCountIsAnErrorNotAHugeAllocation) {
  // Without the reader process this would allocate and zero 9 GiB (or crash).
  TempDir dir;
  // One good scan, then one whose beam count (12345) is overwritten with 2^30.
  auto write = [&](const std::string& path, int objects) {
    mrpt::io::CFileOutputStream out(path);
    auto arch = mrpt::serialization::archiveFrom(out);
    arch << *MakeScan(3, 1.0e9);
    if (objects > 1) arch << *MakeScan(12345, 1.0e9 + 1);
  };
  write(dir.File("one.rawlog"), 1);
  write(dir.File("two.rawlog"), 2);
  const size_t second = testing::ReadFile(dir.File("one.rawlog")).size();
  std::string bytes = testing::ReadFile(dir.File("two.rawlog"));
  const std::string count("\x39\x30\x00\x00", 4);  // 12345, little endian
  const size_t at = bytes.find(count, second);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 4, std::string("\x00\x00\x00\x40", 4));
  testing::WriteFile(dir.File("corrupt.rawlog"), bytes);

  VectorSink sink;
  const auto start = std::chrono::steady_clock::now();
  const auto report = ImportRawlog(dir.File("corrupt.rawlog"), sink, {});
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  ASSERT_EQ(report.error_count, 1) << Errors(report);
  EXPECT_TRUE(HasError(report, "corrupt.rawlog: byte offset " + std::to_string(second) + ": corrupt object"))
      << Errors(report);
  // MRPT sizes the scan before reading it; the reader process hits its memory limit.
  EXPECT_TRUE(HasError(report, "the MRPT reader process")) << Errors(report);
  EXPECT_EQ(report.Count(kLaser), 1);
}

}  // namespace
}  // namespace snapnav::importers
