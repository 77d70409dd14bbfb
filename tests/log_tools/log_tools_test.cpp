// The tools that read LCM logs, on damaged logs: log-report and eval-slam's loader read every
// intact event before and after a corrupt stretch and a truncated tail, name the file and the
// byte offset of each damaged place, and log-report exits with 3. (replay: tests/replay; the
// reader itself: tests/glue/log_reader_test.cpp; the importers' own inputs: tests/importers.)
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "slam_log.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/log_writer.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav {
namespace {

namespace fs = std::filesystem;

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Event {
  std::string channel;
  uint64_t offset;
};

class LogTools : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snapnav_log_tools_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // A small run: ground truth on a circle, dead reckoning beside it (one pose NaN), odometry,
    // and scans of a wall (one with a NaN angle).
    const fs::path path = dir_ / "run.lcmlog";
    glue::LogWriter w(path.string());
    uint64_t offset = 0;
    auto note = [&](const std::string& ch, size_t bytes) {
      events_.push_back({ch, offset});
      offset += 28 + ch.size() + bytes;
    };
    for (int i = 0; i < 60; ++i) {
      const int64_t t = 1700000000000000 + i * 100000;
      const double a = 0.05 * i;
      const nav::Pose2 truth{std::cos(a), std::sin(a), a + M_PI / 2};
      const pose_t gt = glue::ToPoseMsg(t, "ground_truth", "map", truth, Eigen::Matrix3d::Zero());
      w.Write("POSE_GROUND_TRUTH", gt);
      note("POSE_GROUND_TRUTH", glue::Encode(gt).size());
      pose_t dr = glue::ToPoseMsg(t, "dead_reckoning", "odom", {truth.x_m + 0.01, truth.y_m, truth.theta_rad},
                                  Eigen::Matrix3d::Identity() * 0.01);
      if (i == 30) dr.x_m = NAN;
      w.Write("POSE_DEAD_RECKONING", dr);
      note("POSE_DEAD_RECKONING", glue::Encode(dr).size());
      const odometry_t o = glue::ToOdometryMsg(t, "test", truth, {0.05, 0, 0.05}, 0.1);
      w.Write("ODOMETRY", o);
      note("ODOMETRY", glue::Encode(o).size());
      if (i % 3 == 0) {
        laser_scan_t s{};
        s.utime = t;
        s.sensor_name = "test";
        s.angle_min_rad = i == 30 ? NAN : -1.5f;
        s.angle_increment_rad = 0.01f;
        s.range_min_m = 0.02f;
        s.range_max_m = 5.6f;
        s.nranges = 300;
        for (int k = 0; k < 300; ++k) s.ranges_m.push_back(2.0f + 0.001f * k);
        w.Write("LASER_SCAN", s);
        note("LASER_SCAN", glue::Encode(s).size());
      }
    }
    w.Close();
    intact_ = ReadFile(path);
    EXPECT_EQ(intact_.size(), offset);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The log with event `hit`'s sync word overwritten and the last event cut in half.
  fs::path Damaged(size_t hit) const {
    std::string b = intact_;
    for (int k = 0; k < 4; ++k) b[events_[hit].offset + k] = 'X';
    b.resize(events_.back().offset + (b.size() - events_.back().offset) / 2);
    const fs::path p = dir_ / "damaged.lcmlog";
    std::ofstream(p, std::ios::binary) << b;
    return p;
  }
  int Run(const std::string& args, const fs::path& err) const {
    const std::string cmd = std::string(SNAPNAV_BIN_DIR) + "/" + args + " >/dev/null 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  int Count(const std::string& channel, size_t lost_a, size_t lost_b) const {
    int n = 0;
    for (size_t i = 0; i < events_.size(); ++i) n += events_[i].channel == channel && i != lost_a && i != lost_b;
    return n;
  }

  fs::path dir_;
  std::string intact_;
  std::vector<Event> events_;
};

TEST_F(LogTools, LogReportOnAnIntactLogExitsZero) {
  const fs::path out = dir_ / "report";
  EXPECT_EQ(Run("log-report " + (dir_ / "run.lcmlog").string() + " --out " + out.string(), dir_ / "err.txt"), 0)
      << ReadFile(dir_ / "err.txt");
  EXPECT_EQ(ReadFile(out / "report.md").find("DAMAGED"), std::string::npos);
  const std::string json = ReadFile(out / "summary.json");
  EXPECT_NE(json.find("\"messages_POSE_DEAD_RECKONING\": 60"), std::string::npos) << json;
  EXPECT_NE(json.find("\"rejected_POSE_DEAD_RECKONING\": 1"), std::string::npos) << json;  // the NaN pose
  EXPECT_NE(json.find("pose_dead_reckoning_ate_rmse_m"), std::string::npos) << json;
  EXPECT_TRUE(fs::exists(out / "trajectories.png"));
}

// A pose channel corrected afterwards (laser-slam's graph back end: pose_correction_t): reported as
// published and, beside it, as the log's last table puts it; an invalid table is counted on its channel.
TEST_F(LogTools, LogReportAddsTheCorrectedTrajectoryOfACorrectedPoseChannel) {
  const fs::path path = dir_ / "corrected.lcmlog";
  glue::LogWriter w(path.string());
  const nav::Pose2 off{0.3, -0.2, 0.1};  // what the second half was published off by
  const int64_t t0 = 1700000000000000, half = t0 + 30 * 100000;
  for (int i = 0; i < 60; ++i) {
    const int64_t t = t0 + i * 100000;
    const nav::Pose2 truth{0.1 * i, 0.02 * i * i * 0.1, 0.01 * i};
    w.Write("POSE_GROUND_TRUTH", glue::ToPoseMsg(t, "ground_truth", "map", truth, Eigen::Matrix3d::Zero()));
    w.Write("POSE_LASER_SLAM", glue::ToPoseMsg(t, "laser_slam", "map", t < half ? truth : off.Compose(truth),
                                               Eigen::Matrix3d::Zero()));
  }
  pose_correction_t bad = glue::ToPoseCorrectionMsg(t0 + 6000000, "POSE_LASER_SLAM", 1, {{t0, {}}, {half, {}}});
  bad.from_utime = {half, t0};  // out of order
  w.Write("LASER_SLAM_CORRECTION", bad);
  w.Write("LASER_SLAM_CORRECTION", glue::ToPoseCorrectionMsg(t0 + 6000000, "POSE_LASER_SLAM", 2,
                                                             {{t0, {}}, {half, off.Inverse()}}));
  w.Close();
  const fs::path out = dir_ / "report";
  EXPECT_EQ(Run("log-report " + path.string() + " --out " + out.string(), dir_ / "err.txt"), 0)
      << ReadFile(dir_ / "err.txt");
  const std::string json = ReadFile(out / "summary.json");
  EXPECT_NE(json.find("\"rejected_LASER_SLAM_CORRECTION\": 1"), std::string::npos) << json;
  const auto number = [&](const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    return at == std::string::npos ? -1.0 : std::strtod(json.c_str() + at + key.size() + 4, nullptr);
  };
  EXPECT_NEAR(number("pose_laser_slam_corrected_ate_rmse_m"), 0.0, 1e-4) << json;
  EXPECT_GT(number("pose_laser_slam_ate_rmse_m"), 0.2) << json;  // as published: the second half off
  EXPECT_NE(ReadFile(out / "report.md").find("| POSE_LASER_SLAM (corrected) | 60 |"), std::string::npos);
}

TEST_F(LogTools, LogReportOnADamagedLogReportsTheOffsetsAndTheIntactEvents) {
  const size_t hit = events_.size() / 2;
  const fs::path log = Damaged(hit), out = dir_ / "report", err = dir_ / "err.txt";
  EXPECT_EQ(Run("log-report " + log.string() + " --out " + out.string(), err), 3);
  const std::string stderr_text = ReadFile(err);
  EXPECT_NE(stderr_text.find(log.string() + ": byte " + std::to_string(events_[hit].offset) + ": no event sync word"),
            std::string::npos)
      << stderr_text;
  EXPECT_NE(stderr_text.find(log.string() + ": byte " + std::to_string(events_.back().offset)), std::string::npos)
      << stderr_text;
  EXPECT_NE(stderr_text.find("truncated"), std::string::npos) << stderr_text;
  const std::string md = ReadFile(out / "report.md"), json = ReadFile(out / "summary.json");
  EXPECT_NE(md.find("DAMAGED"), std::string::npos);
  EXPECT_NE(md.find("byte " + std::to_string(events_[hit].offset)), std::string::npos) << md;
  const size_t last = events_.size() - 1;
  for (const char* ch : {"POSE_GROUND_TRUTH", "POSE_DEAD_RECKONING", "ODOMETRY", "LASER_SCAN"}) {
    const std::string want = "\"messages_" + std::string(ch) + "\": " + std::to_string(Count(ch, hit, last));
    EXPECT_NE(json.find(want), std::string::npos) << want << "\n" << json;
  }
  EXPECT_NE(json.find("\"log_damaged_places\": 2"), std::string::npos) << json;
  EXPECT_TRUE(fs::exists(out / "trajectories.png"));
}

// Random bytes are not an LCM log: log-report says so, naming the file, and exits 1 (it summarised
// zero events as a damaged log).
TEST_F(LogTools, LogReportOnRandomBytesSaysNotAnLcmLog) {
  const fs::path junk = dir_ / "random.bin", err = dir_ / "err.txt";
  std::string bytes;
  for (int i = 0; i < 50000; ++i) bytes.push_back(static_cast<char>((i * 7919 + 13) % 256));
  std::ofstream(junk, std::ios::binary) << bytes;
  EXPECT_EQ(Run("log-report " + junk.string() + " --out " + (dir_ / "report").string(), err), 1);
  const std::string text = ReadFile(err);
  EXPECT_NE(text.find("log-report: error: " + junk.string() + " is not an LCM log: byte 0"), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(dir_ / "report" / "report.md"));
}

TEST_F(LogTools, SlamLogLoaderKeepsTheIntactScansAndNamesTheDamage) {
  const size_t hit = 7;  // an early event
  const fs::path log = Damaged(hit);
  const eval::SlamLog read = eval::LoadSlamLog(log.string(), false);
  EXPECT_EQ(read.damaged_places, 2);
  ASSERT_EQ(read.damage.size(), 2u);
  EXPECT_NE(read.damage[0].find(log.string() + ": byte " + std::to_string(events_[hit].offset)), std::string::npos)
      << read.damage[0];
  EXPECT_NE(read.damage[1].find("truncated"), std::string::npos) << read.damage[1];
  const size_t last = events_.size() - 1;
  EXPECT_EQ(read.scans, Count("LASER_SCAN", hit, last) - 1);  // the scan with a NaN angle is rejected
  EXPECT_EQ(read.odometry, Count("ODOMETRY", hit, last));
  EXPECT_EQ(read.rejected, 1);
  const eval::SlamLog intact = eval::LoadSlamLog((dir_ / "run.lcmlog").string(), false);
  EXPECT_EQ(intact.damaged_places, 0);
  EXPECT_EQ(intact.scans, Count("LASER_SCAN", events_.size(), events_.size()) - 1);
}

}  // namespace
}  // namespace snapnav
