// The glue bus on the real LCM with memq://: typed round trips, and bad
// payloads or throwing handlers counted instead of crashing.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/handler_problems.hpp"
#include "snapnav/glue/lcm_url.hpp"
#include "snapnav/pose_t.hpp"
#include "snapnav/laser_scan_t.hpp"

namespace snapnav::glue {
namespace {

pose_t SamplePose(int64_t utime) {
  pose_t p{};
  p.utime = utime;
  p.estimator = "test";
  p.frame = "map";
  p.x_m = 1.0 * utime;
  return p;
}

void HandleAll(Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

TEST(Bus, TypedPublishSubscribeRoundTrip) {
  Bus bus("memq://");
  std::vector<pose_t> got;
  bus.Subscribe<pose_t>("TEST_BUS_ROUNDTRIP", [&](const pose_t& p) { got.push_back(p); });
  bus.Publish("TEST_BUS_ROUNDTRIP", SamplePose(1));
  bus.Publish("TEST_BUS_ROUNDTRIP", SamplePose(2));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].utime, 2);
  EXPECT_DOUBLE_EQ(got[1].x_m, 2.0);
  EXPECT_EQ(bus.stats().at("TEST_BUS_ROUNDTRIP").received, 2u);
  EXPECT_EQ(bus.total_errors(), 0u);
}

TEST(Bus, WrongTypeIsCountedAndTheProcessGoesOn) {
  Bus bus("memq://");
  int handled = 0;
  bus.Subscribe<laser_scan_t>("TEST_BUS_WRONG_TYPE", [&](const laser_scan_t&) { ++handled; });
  bus.Publish("TEST_BUS_WRONG_TYPE", SamplePose(1));
  const char junk[3] = {1, 2, 3};
  bus.PublishRaw("TEST_BUS_WRONG_TYPE", junk, sizeof junk);
  HandleAll(bus);
  EXPECT_EQ(handled, 0);
  const auto& s = bus.stats().at("TEST_BUS_WRONG_TYPE");
  EXPECT_EQ(s.decode_errors, 2u);
  EXPECT_NE(s.last_error.find("shorter than a type fingerprint"), std::string::npos) << s.last_error;
}

TEST(Bus, HandlerExceptionIsCountedNotPropagated) {
  Bus bus("memq://");
  int calls = 0;
  bus.Subscribe<pose_t>("TEST_BUS_THROW", [&](const pose_t& p) {
    ++calls;
    if (p.utime == 1) throw std::invalid_argument("bad pose");
  });
  bus.Publish("TEST_BUS_THROW", SamplePose(1));
  bus.Publish("TEST_BUS_THROW", SamplePose(2));
  EXPECT_NO_THROW(HandleAll(bus));
  EXPECT_EQ(calls, 2);
  const auto& s = bus.stats().at("TEST_BUS_THROW");
  EXPECT_EQ(s.handler_errors, 1u);
  EXPECT_EQ(s.last_error, "bad pose");
  std::ostringstream report;
  bus.ReportStats(report);
  EXPECT_NE(report.str().find("TEST_BUS_THROW"), std::string::npos);
  EXPECT_NE(report.str().find("handler errors 1"), std::string::npos) << report.str();
}

TEST(Bus, CurrentMessageInfoInsideHandler) {
  Bus bus("memq://");
  std::string channel;
  size_t size = 0;
  bus.Subscribe<pose_t>("TEST_BUS_INFO", [&](const pose_t&) {
    channel = bus.current().channel;
    size = bus.current().size_bytes;
  });
  const auto p = SamplePose(3);
  bus.Publish("TEST_BUS_INFO", p);
  HandleAll(bus);
  EXPECT_EQ(channel, "TEST_BUS_INFO");
  EXPECT_EQ(size, static_cast<size_t>(p.getEncodedSize()));
}

// LCM keeps a subscription's messages only up to its queue capacity while the handlers lag: the
// default (LCM's 30) drops the rest of a burst, the odometry capacity keeps 20 s of 50 Hz. UDP
// multicast only (memq:// has no queue limit), so it runs in the private network namespace of the
// ctest bus_queue_capacity_private_bus (SNAPNAV_PRIVATE_BUS set), and skips elsewhere.
TEST(BusPrivate, QueueCapacityBoundsWhatALaggingSubscriberKeeps) {
  if (!std::getenv("SNAPNAV_PRIVATE_BUS")) GTEST_SKIP() << "needs the private bus: ctest -R bus_queue_capacity";
  Bus bus("udpm://239.255.76.67:7691?ttl=0&recv_buf_size=4194304");
  int small = 0, large = 0;
  bus.Subscribe<pose_t>("TEST_BUS_QUEUE", [&](const pose_t&) { ++small; });
  bus.Subscribe<pose_t>("TEST_BUS_QUEUE", [&](const pose_t&) { ++large; }, Bus::kOdometryQueueCapacity);
  for (int i = 0; i < 500; ++i) bus.Publish("TEST_BUS_QUEUE", SamplePose(i));
  // The subscriber lags: nothing is handled until every message has been received.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  while (bus.HandleOnce(200)) {
  }
  // The default keeps its capacity (and the one message LCM's receive thread holds besides).
  EXPECT_GE(small, Bus::kDefaultQueueCapacity);
  EXPECT_LE(small, Bus::kDefaultQueueCapacity + 1);
  EXPECT_EQ(large, 500);
}

TEST(Bus, QueueCapacityMustBePositive) {
  Bus bus("memq://");
  EXPECT_THROW(bus.Subscribe<pose_t>("TEST_BUS_QUEUE", [](const pose_t&) {}, 0), std::invalid_argument);
}

// A node's handler problems: a malformed message is skipped and rejected on its channel, a
// benign skip is only counted, an exception out of the work is an internal error, not a crash.
TEST(HandlerProblems, SkipsRejectsAndGuardsCountedByReason) {
  Bus bus("memq://");
  HandlerProblems problems(bus, "test-node");
  bus.SubscribeRaw("TEST_PROBLEMS", [&](const void*, size_t) {
    problems.Skip("no ranges", "0 ranges", true);
    problems.Skip("waiting for a fix", "", false);
    problems.Guard("scan", [] { throw std::runtime_error("publish failed"); });
    problems.Guard("scan", [] {});
  });
  bus.PublishRaw("TEST_PROBLEMS", "x", 1);
  HandleAll(bus);
  EXPECT_EQ(problems.skipped("no ranges"), 1);
  EXPECT_EQ(problems.skipped("waiting for a fix"), 1);
  EXPECT_EQ(problems.skipped("other"), 0);
  EXPECT_EQ(problems.skipped_total(), 2);
  EXPECT_EQ(problems.internal_errors(), 1);
  EXPECT_EQ(problems.last_internal_error(), "scan: publish failed");
  EXPECT_EQ(bus.stats().at("TEST_PROBLEMS").decode_errors, 1u);  // only the malformed one
  EXPECT_EQ(bus.stats().at("TEST_PROBLEMS").handler_errors, 0u);
  std::ostringstream report;
  problems.Report(report);
  EXPECT_NE(report.str().find("test-node:   skipped (no ranges): 1"), std::string::npos) << report.str();
  EXPECT_NE(report.str().find("test-node:   last internal error: scan: publish failed"), std::string::npos);
}

TEST(Bus, MissingLogFileIsExplained) {
  try {
    Bus bus("file:///nonexistent/dir/run.lcmlog?speed=0");
    FAIL() << "expected BusError";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/run.lcmlog"), std::string::npos) << e.what();
  }
}

TEST(LcmUrl, DefaultStaysOnHostWithLargeReceiveBuffer) {
  const std::string url = kDefaultLcmUrl;
  EXPECT_NE(url.find("ttl=0"), std::string::npos);
  EXPECT_NE(url.find("recv_buf_size="), std::string::npos);
}

TEST(LcmUrl, DiagnosisNamesTheFix) {
  const std::string d = DiagnoseLcmFailure("udpm://239.255.76.67:7667?ttl=0");
  EXPECT_NE(d.find("ip route add 224.0.0.0/4 dev lo"), std::string::npos) << d;
  EXPECT_NE(d.find("./snapnav bus --"), std::string::npos) << d;
}

}  // namespace
}  // namespace snapnav::glue
