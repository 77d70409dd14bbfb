// The log-import binary: exit status, the log it writes, and its refusal of bad flags.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <lcm/lcm-cpp.hpp>

#include "importer_test_util.hpp"

namespace snapnav::importers {
namespace {

using testing::TempDir;

// Runs log-import with `args` (already quoted); returns its exit status, output in *out.
int RunTool(const std::string& args, const TempDir& dir, std::string* out) {
  const std::string log = dir.File("tool_output.txt");
  const std::string command = std::string("'") + SNAPNAV_LOG_IMPORT_BIN + "' " + args + " > '" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  *out = testing::ReadFile(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::map<std::string, int> ChannelCounts(const std::string& path) {
  std::map<std::string, int> counts;
  lcm::LogFile log(path, "r");
  if (!log.good()) return counts;
  while (const lcm::LogEvent* e = log.readNextEvent()) ++counts[e->channel];
  return counts;
}

TEST(LogImportTool, TruncatedCarmenLogWritesTheValidMessagesAndExitsNonZero) {
  TempDir dir;
  testing::WriteFile(dir.File("in.log"),
                     "FLASER 3 1 2 3 0 0 0 0 0 0 10.0 h 0.1\n"
                     "FLASER 3 1 2 3 0 0 0 0.1 0 0 10.2 h 0.3\n"
                     "FLASER 3 1 2");
  std::string out;
  EXPECT_EQ(RunTool("carmen '" + dir.File("in.log") + "' --out '" + dir.File("out.lcmlog") + "' --channel-prefix T_",
                    dir, &out),
            1)
      << out;
  EXPECT_NE(out.find(dir.File("in.log") + ":3: FLASER declares 3 readings"), std::string::npos) << out;
  EXPECT_NE(out.find("T_LASER_SCAN"), std::string::npos) << out;
  const auto counts = ChannelCounts(dir.File("out.lcmlog"));
  EXPECT_EQ(counts.at("T_LASER_SCAN"), 2);
  EXPECT_EQ(counts.at("T_ODOMETRY"), 2);
  EXPECT_EQ(counts.at("T_POSE_CARMEN"), 2);
}

TEST(LogImportTool, GoodInputExitsZeroAndBadFlagsAreRefused) {
  TempDir dir;
  testing::WriteFile(dir.File("in.log"), "ODOM 0 0 0 0 0 0 10.0 h 0.1\nODOM 1 0 0 0 0 0 11.0 h 1.1\n");
  std::string out;
  EXPECT_EQ(RunTool("carmen '" + dir.File("in.log") + "' --out '" + dir.File("out.lcmlog") + "'", dir, &out), 0) << out;
  EXPECT_NE(out.find("time span: 10.000000 .. 11.000000 s (1.000 s)"), std::string::npos) << out;
  EXPECT_EQ(ChannelCounts(dir.File("out.lcmlog")).at("ODOMETRY"), 2);

  EXPECT_EQ(RunTool("--help", dir, &out), 0);
  EXPECT_NE(out.find("--positions"), std::string::npos) << out;
  EXPECT_EQ(RunTool("carmen '" + dir.File("in.log") + "'", dir, &out), 2) << out;  // no --out
  EXPECT_EQ(RunTool("bag x --out y", dir, &out), 2) << out;
  EXPECT_EQ(RunTool("rawlog x --out y --positions p.csv", dir, &out), 2) << out;
  EXPECT_EQ(RunTool("carmen '" + dir.File("in.log") + "' --out '" + dir.File("in.log") + "'", dir, &out), 2) << out;
  EXPECT_NE(testing::ReadFile(dir.File("in.log")).find("ODOM"), std::string::npos) << "input overwritten";
}

TEST(LogImportTool, NotARawlogExitsNonZeroWithoutALog) {
  TempDir dir;
  testing::WriteFile(dir.File("notes.txt"), "plain text\n");
  std::string out;
  EXPECT_EQ(RunTool("rawlog '" + dir.File("notes.txt") + "' --out '" + dir.File("out.lcmlog") + "'", dir, &out), 1)
      << out;
  EXPECT_NE(out.find("not an MRPT rawlog"), std::string::npos) << out;
  EXPECT_FALSE(std::ifstream(dir.File("out.lcmlog")).good());
}

// A binary file given as a CARMEN log: one error saying it is not one, naming the file and the byte
// where it stopped looking like text (it printed the first 100 of 493 per-line errors).
TEST(LogImportTool, BinaryFileIsNotACarmenLogInOneLine) {
  TempDir dir;
  std::string bytes;
  for (int i = 0; i < 20000; ++i) bytes.push_back(static_cast<char>(i % 97 == 5 ? '\n' : (i * 131 + 7) % 256));
  testing::WriteFile(dir.File("photo.jpg"), bytes);
  std::string out;
  EXPECT_EQ(RunTool("carmen '" + dir.File("photo.jpg") + "' --out '" + dir.File("out.lcmlog") + "'", dir, &out), 1)
      << out;
  EXPECT_NE(out.find(dir.File("photo.jpg") + " is not a CARMEN log: byte 0 (line 1) is binary data (0x07)"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("errors: 1\n"), std::string::npos) << out;
  EXPECT_EQ(out.find("... and "), std::string::npos) << out;
  EXPECT_FALSE(std::ifstream(dir.File("out.lcmlog")).good());
}

}  // namespace
}  // namespace snapnav::importers
