// glue::RunNode: the skeleton every process's main runs (config printed, bus, node, report).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "snapnav/glue/log_writer.hpp"
#include "snapnav/glue/run_node.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::glue {
namespace {

namespace fs = std::filesystem;

struct TestConfig {
  std::string channel = "POSE";
  void Print(std::ostream& out) const { out << "  [test] channel = " << channel << "\n"; }
};

// What happened, in order, across the node's life.
std::vector<std::string>* g_events = nullptr;

class CountingNode {
 public:
  CountingNode(Bus& bus, const TestConfig& config, int tag) : tag_(tag) {
    bus.Subscribe<pose_t>(config.channel, [this](const pose_t&) { ++poses_; });
  }
  int poses() const { return poses_; }
  void Report(std::ostream& out) const {
    g_events->push_back("report " + std::to_string(poses_));
    out << "counting: poses " << poses_ << " tag " << tag_ << "\n";
  }

 protected:
  int poses_ = 0;
  int tag_;
};

class SavingNode : public CountingNode {
 public:
  SavingNode(Bus& bus, const TestConfig& config) : CountingNode(bus, config, 0) {}
  void Finish() { g_events->push_back("finish " + std::to_string(poses_)); }
};

class RunNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    g_events = &events_;
    dir_ = fs::temp_directory_path() / ("snapnav_run_node_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    log_ = (dir_ / "in.lcmlog").string();
    LogWriter w(log_);
    for (int i = 0; i < 5; ++i) {
      pose_t p{};
      p.utime = 1000 + i;
      p.estimator = "test";
      p.frame = "map";
      w.Write("POSE", p);
    }
    w.Write("OTHER", pose_t{});
    w.Close();
    old_ = std::cerr.rdbuf(err_.rdbuf());
  }
  void TearDown() override {
    std::cerr.rdbuf(old_);
    g_events = nullptr;
    fs::remove_all(dir_);
  }
  std::string url() const { return "file://" + log_ + "?speed=0"; }

  std::vector<std::string> events_;
  fs::path dir_;
  std::string log_;
  std::ostringstream err_;
  std::streambuf* old_ = nullptr;
};

TEST_F(RunNodeTest, PrintsTheConfigRunsTheBusToTheEndAndReports) {
  const TestConfig config;
  const int rc = RunNode<CountingNode>(
      "counting", "/etc/test.ini", config, url(),
      [](const CountingNode& node, const Bus& bus) {
        return "poses from POSE (" + bus.url() + "), " + std::to_string(node.poses()) + " so far";
      },
      7);
  std::cerr.rdbuf(old_);
  const std::string err = err_.str();
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(events_, (std::vector<std::string>{"report 5"}));
  // In this order: the config file and its values, the node's line, its report, the bus's counts.
  const auto config_line = err.find("counting: config /etc/test.ini\n  [test] channel = POSE\n");
  const auto node_line = err.find("counting: poses from POSE (file://" + log_ + "?speed=0), 0 so far\n");
  const auto report = err.find("counting: poses 5 tag 7\n");
  ASSERT_NE(config_line, std::string::npos) << err;
  ASSERT_NE(node_line, std::string::npos) << err;
  ASSERT_NE(report, std::string::npos) << err;
  EXPECT_LT(config_line, node_line);
  EXPECT_LT(node_line, report);
  EXPECT_NE(err.find("POSE", report + 1), std::string::npos) << "the bus's counts after the report: " << err;
}

TEST_F(RunNodeTest, ANodeWithFinishHasItCalledBeforeItsReport) {
  RunNode<SavingNode>("saving", "x.ini", TestConfig{}, url(),
                      [](const SavingNode&, const Bus&) { return std::string(); });
  EXPECT_EQ(events_, (std::vector<std::string>{"finish 5", "report 5"}));
  EXPECT_EQ(err_.str().find("saving: \n"), std::string::npos) << "an empty line is not said";
}

TEST_F(RunNodeTest, AMissingLogIsAnErrorBeforeAnyNodeIsBuilt) {
  EXPECT_THROW(RunNode<SavingNode>("saving", "x.ini", TestConfig{}, "file://" + (dir_ / "none.lcmlog").string(),
                                   [](const SavingNode&, const Bus&) { return std::string(); }),
               BusError);
  EXPECT_TRUE(events_.empty());
}

}  // namespace
}  // namespace snapnav::glue
