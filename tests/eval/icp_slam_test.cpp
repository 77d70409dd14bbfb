// MRPT's icp-slam beside our laser SLAM (tools/eval/slam/icp_slam.hpp): the generated config, the
// parsing of icp-slam's output files (fixtures written here), pairing by time, the errors when
// the program is missing or fails, and, where Debian's mrpt-apps / mrpt-common are installed,
// the rawlog stepping on the Malaga loop and the re-stamping of carmen2rawlog's output.
#include "icp_slam.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/snapnav_icp_slam_XXXXXX";
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string File(const std::string& name, const std::string& text) const {
    const std::string p = path_ + "/" + name;
    std::ofstream(p) << text;
    return p;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string ThrowMessage(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

bool OnPath(const std::string& name) {
  std::istringstream dirs(std::getenv("PATH") ? std::getenv("PATH") : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (::access((dir + "/" + name).c_str(), X_OK) == 0) return true;
  }
  return false;
}

TEST(IcpSlamOutput, ParsesThePathFile) {
  TempDir dir;
  const auto path = dir.File("log_estimated_path.txt",
                             "0 0.000000 0.000000 0.000000\n1 0.250000 -0.100000 0.050000\n"
                             "2 1.500000 2.000000 -3.100000\n");
  const auto poses = ParseIcpSlamPath(path);
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_DOUBLE_EQ(poses[1].x_m, 0.25);
  EXPECT_DOUBLE_EQ(poses[1].y_m, -0.1);
  EXPECT_DOUBLE_EQ(poses[1].theta_rad, 0.05);
  EXPECT_DOUBLE_EQ(poses[2].theta_rad, -3.1);
}

TEST(IcpSlamOutput, MalformedPathFilesNameFileAndLine) {
  TempDir dir;
  const auto bad = dir.File("bad.txt", "0 0 0 0\n1 0.5 nan?\n");
  EXPECT_NE(ThrowMessage([&] { ParseIcpSlamPath(bad); }).find(bad + ":2: expected 'step x y yaw'"), std::string::npos);
  const auto gap = dir.File("gap.txt", "0 0 0 0\n2 1 1 0\n");
  EXPECT_NE(ThrowMessage([&] { ParseIcpSlamPath(gap); }).find(gap + ":2: step 2, expected 1"), std::string::npos);
  const auto extra = dir.File("extra.txt", "0 0 0 0 7\n");
  EXPECT_NE(ThrowMessage([&] { ParseIcpSlamPath(extra); }).find(":1:"), std::string::npos);
  EXPECT_NE(ThrowMessage([&] { ParseIcpSlamPath(dir.path() + "/missing.txt"); }).find("missing.txt"),
            std::string::npos);
}

TEST(IcpSlamOutput, ParsesTheTimesFile) {
  TempDir dir;
  const auto ms = ParseIcpSlamTimes(dir.File("log_times.txt", "0.116849 1\n0.007243 1\n4.770000 57\n"));
  ASSERT_EQ(ms.size(), 3u);
  EXPECT_DOUBLE_EQ(ms[2], 4.77);
  const auto bad = dir.File("bad_times.txt", "0.1 1\n-2 1\n");
  EXPECT_NE(ThrowMessage([&] { ParseIcpSlamTimes(bad); }).find(bad + ":2:"), std::string::npos);
}

TEST(IcpSlamConfig, SetsItsKeysAndKeepsTheRest) {
  const std::string base =
      "[ICP]\nmaxIterations = 80 // iterations\nLOG_FREQUENCY = 7\n"
      "[MappingApplication]\nrawlog_file=../x.rawlog\nlogOutput_dir=LOG_ICP\nLOG_FREQUENCY=50  // every 50\n"
      "SAVE_3D_SCENE=1\nlocalizationLinDistance = 0.2\n[Other]\nSAVE_3D_SCENE=1\n";
  const std::string cfg = MakeIcpSlamConfig(base, "/data/in put.rawlog", "/work/out", "base.ini");
  EXPECT_NE(cfg.find("from base.ini"), std::string::npos);
  EXPECT_NE(cfg.find("\nrawlog_file = /data/in put.rawlog\n"), std::string::npos);
  EXPECT_NE(cfg.find("\n# snapnav: was rawlog_file = ../x.rawlog\n"), std::string::npos);
  EXPECT_NE(cfg.find("\nlogOutput_dir = /work/out\n"), std::string::npos);
  EXPECT_NE(cfg.find("\n# snapnav: was LOG_FREQUENCY = 50\nLOG_FREQUENCY = 0\n"), std::string::npos);
  // Keys missing from the section are added to it.
  const auto section = cfg.find("[MappingApplication]");
  const auto other = cfg.find("[Other]");
  for (const std::string key :
       {"verbosity = LVL_WARN", "SAVE_POSE_LOG = 0", "SHOW_PROGRESS_3D_REAL_TIME = 0", "rawlog_offset = 0"}) {
    const auto at = cfg.find("\n" + key + "\n");
    ASSERT_NE(at, std::string::npos) << key;
    EXPECT_GT(at, section);
    EXPECT_LT(at, other);
  }
  // Other sections and keys are untouched.
  EXPECT_NE(cfg.find("\nLOG_FREQUENCY = 7\n"), std::string::npos);
  EXPECT_NE(cfg.find("[Other]\nSAVE_3D_SCENE=1\n"), std::string::npos);
  EXPECT_NE(cfg.find("\nlocalizationLinDistance = 0.2\n"), std::string::npos);
  // MRPT's reader would take a '#' after a value as part of it.
  std::istringstream lines(cfg);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line[0] != '#') {
      EXPECT_EQ(line.find('#'), std::string::npos) << line;
    }
  }
  EXPECT_THROW(MakeIcpSlamConfig("[ICP]\nx=1\n", "a", "b"), std::invalid_argument);
}

TEST(IcpSlamConfig, SetsOtherKeysInTheirSections) {
  const std::string base =
      "[ICP]\ncorresponding_points_decimation = 5 // every 5th\n"
      "[MappingApplication]\nlocalizationLinDistance\t= 0.2\t// metres\ncorresponding_points_decimation = 9\n";
  const std::string cfg = MakeIcpSlamConfig(base, "/r.rawlog", "/o", "",
                                            {{"ICP", "corresponding_points_decimation", "1"},
                                             {"MappingApplication", "localizationLinDistance", "0"}});
  EXPECT_NE(cfg.find("[ICP]\n# snapnav: was corresponding_points_decimation = 5\ncorresponding_points_decimation = 1\n"),
            std::string::npos)
      << cfg;
  EXPECT_NE(cfg.find("\n# snapnav: was localizationLinDistance = 0.2\nlocalizationLinDistance = 0\n"), std::string::npos);
  EXPECT_NE(cfg.find("\ncorresponding_points_decimation = 9\n"), std::string::npos);  // another section's: kept
  // A key to set that the base does not have (in that section) is a mistake, not an addition.
  const std::string message = ThrowMessage([&] {
    MakeIcpSlamConfig(base, "/r.rawlog", "/o", "", {{"MappingApplication", "localizationAngDistance", "0"}});
  });
  EXPECT_NE(message.find("localizationAngDistance in [MappingApplication]"), std::string::npos) << message;
  EXPECT_THROW(MakeIcpSlamConfig(base, "/r.rawlog", "/o", "", {{"ICP", "localizationLinDistance", "0"}}),
               std::invalid_argument);
}

TEST(IcpSlamConfig, TheShippedClassicConfig) {
  std::ifstream in(kIcpSlamClassicConfig);
  if (!in) {
    GTEST_SKIP() << kIcpSlamClassicConfig << " not installed (Debian's mrpt-apps)";
  }
  std::stringstream text;
  text << in.rdbuf();
  const std::string cfg = MakeIcpSlamConfig(text.str(), "/r.rawlog", "/o");
  EXPECT_NE(cfg.find("\nICP_algorithm = icpClassic"), std::string::npos);  // point-map to point-map ICP
  for (const std::string key : {"logOutput_dir", "SAVE_3D_SCENE", "SHOW_PROGRESS_3D_REAL_TIME", "LOG_FREQUENCY"}) {
    size_t n = 0;
    for (const std::string& form : {"\n" + key + " =", "\n" + key + "="}) {
      for (size_t at = cfg.find(form); at != std::string::npos; at = cfg.find(form, at + 1)) ++n;
    }
    EXPECT_EQ(n, 1u) << key;
  }
}

TEST(IcpSlamPairing, PosesOfScanEntriesAtTheirTimes) {
  const std::vector<RawlogStep> steps = {{100, false}, {100, true}, {200, false}, {200, true}};
  const std::vector<nav::Pose2> poses = {{0, 0, 0}, {1, 0, 0}, {1.5, 0, 0}, {2, 0, 0}};
  const auto at = PosesAtScans(steps, poses);
  ASSERT_EQ(at.size(), 2u);
  EXPECT_EQ(at[0].utime, 100);
  EXPECT_DOUBLE_EQ(at[0].pose.x_m, 1);
  EXPECT_EQ(at[1].utime, 200);
  EXPECT_DOUBLE_EQ(at[1].pose.x_m, 2);
  EXPECT_THROW(PosesAtScans(steps, {poses[0]}), std::runtime_error);
}

TEST(IcpSlamPairing, SameTrajectoryInAnotherFrameDiffersByNothing) {
  std::vector<int64_t> utimes;
  std::vector<nav::Pose2> ours;
  std::vector<nav::StampedPose> icp;
  const nav::Pose2 frame{3, -2, 0.7};
  for (int i = 0; i < 50; ++i) {
    const nav::Pose2 p{0.1 * i, std::sin(0.2 * i), 0.05 * i};
    utimes.push_back(1'000'000 + 100'000 * i);
    ours.push_back(p);
    if (i != 0) icp.push_back({utimes.back() + (i % 3) * 100, frame.Compose(p)});  // icp-slam skips the first
  }
  const auto cmp = CompareWithIcpSlam(utimes, ours, icp, 1000);
  EXPECT_EQ(cmp.paired, 49);
  EXPECT_FALSE(cmp.icp_at_scans[0].has_value());
  EXPECT_LT(cmp.difference.rmse_m, 1e-9);
  EXPECT_NEAR(cmp.slam_to_icp.theta_rad, 0.7, 1e-9);
  // Off by one scan: the difference shows.
  std::vector<nav::StampedPose> shifted;
  for (size_t i = 1; i < icp.size(); ++i) shifted.push_back({icp[i - 1].utime, icp[i].pose});
  EXPECT_GT(CompareWithIcpSlam(utimes, ours, shifted, 1000).difference.rmse_m, 0.05);
  // Nothing within the tolerance: an error that says why.
  for (auto& p : icp) p.utime += 5000;
  EXPECT_NE(ThrowMessage([&] { CompareWithIcpSlam(utimes, ours, icp, 1000); }).find("only 0 of the log's 50 scans"),
            std::string::npos);
}

TEST(IcpSlamRunner, MissingProgramIsNamed) {
  TempDir dir;
  IcpSlamOptions options;
  options.icp_slam = "snapnav-no-such-icp-slam";
  options.base_config = dir.File("base.ini", "[MappingApplication]\n");
  options.progress = false;
  const auto input = dir.File("x.rawlog", "");
  const std::string msg = ThrowMessage([&] { RunIcpSlam(input, dir.path() + "/work", options); });
  EXPECT_NE(msg.find("snapnav-no-such-icp-slam not found on PATH"), std::string::npos) << msg;
  EXPECT_NE(msg.find("mrpt-apps"), std::string::npos) << msg;
  EXPECT_NE(ThrowMessage([&] {
              RunIcpSlam(dir.path() + "/nothing.rawlog", dir.path() + "/work", options);
            }).find("nothing.rawlog: no such file"),
            std::string::npos);
}

TEST(IcpSlamRunner, FailureGivesCommandExitCodeAndLastLines) {
  TempDir dir;
  const std::string fake =
      dir.File("fake-icp-slam", "#!/bin/sh\necho starting\necho 'Message: it broke' >&2\nexit 3\n");
  ::chmod(fake.c_str(), 0755);
  IcpSlamOptions options;
  options.icp_slam = fake;
  options.base_config = dir.File("base.ini", "[MappingApplication]\n");
  options.progress = false;
  const auto input = dir.File("x.rawlog", "");
  const std::string msg = ThrowMessage([&] { RunIcpSlam(input, dir.path() + "/work", options); });
  EXPECT_NE(msg.find("`" + fake + " " + dir.path() + "/work/icp-slam.ini " + input + "` exited with code 3"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("starting"), std::string::npos) << msg;
  EXPECT_NE(msg.find("it broke"), std::string::npos) << msg;
  EXPECT_NE(msg.find(dir.path() + "/work/icp-slam.log"), std::string::npos) << msg;
  // A program that exits 0 but writes no path is an error too.
  const std::string quiet = dir.File("quiet-icp-slam", "#!/bin/sh\necho nothing to see\n");
  ::chmod(quiet.c_str(), 0755);
  options.icp_slam = quiet;
  const std::string msg2 = ThrowMessage([&] { RunIcpSlam(input, dir.path() + "/work", options); });
  EXPECT_NE(msg2.find("wrote no"), std::string::npos) << msg2;
  EXPECT_NE(msg2.find("nothing to see"), std::string::npos) << msg2;
  // The generated config is left in the work folder.
  EXPECT_TRUE(fs::exists(dir.path() + "/work/icp-slam.ini"));
}

TEST(IcpSlamRawlog, MalagaLoopStepsAsIcpSlamDoes) {
  if (!fs::exists(kMalagaLoopRawlog)) {
    GTEST_SKIP() << kMalagaLoopRawlog << " not installed (Debian's mrpt-common)";
  }
  const auto steps = ReadRawlogSteps(kMalagaLoopRawlog);
  // 225 sensory frames, 224 actions: the first frame has no action before it and is skipped.
  ASSERT_EQ(steps.size(), 224u);
  for (const auto& s : steps) EXPECT_TRUE(s.scan);
  EXPECT_EQ(steps.front().utime, 1137834225973760);  // the second scan, as log-import stamps it
  EXPECT_EQ(steps.back().utime, 1137834284788331);   // the last scan
  TempDir dir;
  const std::string garbage = dir.File("garbage.rawlog", "this is not a rawlog at all\n");
  EXPECT_NE(ThrowMessage([&] { ReadRawlogSteps(garbage); }).find(garbage + ": rawlog entry"), std::string::npos);
}

TEST(IcpSlamRawlog, CarmenConversionIsRestampedWithLogImportTimes) {
  if (!OnPath("carmen2rawlog")) {
    GTEST_SKIP() << "carmen2rawlog not installed (Debian's mrpt-apps)";
  }
  TempDir dir;
  std::string text = "# a tiny CARMEN log\n";
  for (int i = 0; i < 3; ++i) {
    std::ostringstream line;
    line << "FLASER 5";
    for (int b = 0; b < 5; ++b) line << " " << 1.0 + 0.1 * b + 0.01 * i;
    line << " " << 0.1 * i << " 0 0 " << 0.1 * i << " 0 0 "
         << "1134864629." << 100000 * (i + 1) << " host 0." << i << "\n";
    text += line.str();
  }
  const std::string clf = dir.File("tiny.clf", text);
  const std::string converted = dir.path() + "/converted.rawlog", restamped = dir.path() + "/restamped.rawlog";
  ASSERT_EQ(
      std::system(("carmen2rawlog -q -w -z 0 -i " + clf + " -o " + converted + " >/dev/null 2>&1 </dev/null").c_str()),
      0);
  EXPECT_EQ(RestampCarmenRawlog(converted, clf, restamped), 3);
  const auto steps = ReadRawlogSteps(restamped);
  ASSERT_EQ(steps.size(), 6u);  // odometry, scan per line
  std::vector<int64_t> scan_times;
  for (size_t i = 0; i < steps.size(); ++i) {
    if (steps[i].scan) scan_times.push_back(steps[i].utime);
    if (!steps[i].scan) {
      EXPECT_EQ(steps[i].utime, steps[i + 1].utime) << "odometry at its line's scan time";
    }
  }
  EXPECT_EQ(scan_times, (std::vector<int64_t>{1134864629100000, 1134864629200000, 1134864629300000}));
  // A CARMEN log that does not match the rawlog is refused.
  const std::string other = dir.File("other.clf", text.substr(0, text.rfind("FLASER")));
  EXPECT_NE(ThrowMessage([&] { RestampCarmenRawlog(converted, other, restamped); }).find("holds 3 scans"),
            std::string::npos);
}

}  // namespace
}  // namespace snapnav::eval
