// The recorder (tools/recorder): every message into an LCM log with its receive time, as lcm-logger
// writes it; appending; a write failure stops it, counted; and on real UDP multicast it keeps a burst
// that LCM's default queue of 30 (lcm-logger's) drops.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "recorder.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/log_writer.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::tools {
namespace {

namespace fs = std::filesystem;

struct Event {
  std::string channel;
  int64_t timestamp = 0;
  std::string data;
};

std::vector<Event> ReadLog(const std::string& path) {
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  std::vector<Event> out;
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    out.push_back({e->channel, e->timestamp, std::string(static_cast<const char*>(e->data), e->datalen)});
  }
  return out;
}

std::string TempLog(const std::string& name) {
  const fs::path p = fs::path(testing::TempDir()) / ("recorder_test_" + name + ".lcmlog");
  fs::remove(p);
  return p.string();
}

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

TEST(Recorder, WritesEveryMessageWithItsReceiveTimeAndOnlyItsChannels) {
  const std::string path = TempLog("every");
  glue::Bus bus("memq://");
  glue::LogWriter log(path);
  RecorderOptions options;
  options.channels = "REC_.*";
  Recorder recorder(bus, log, options);
  const int64_t before = glue::WallUtime();
  std::vector<Event> sent;
  for (int i = 0; i < 300; ++i) {
    const std::string channel = i % 3 == 0 ? "REC_A" : (i % 3 == 1 ? "REC_B" : "OTHER");
    const std::string data = "message " + std::to_string(i) + std::string(static_cast<size_t>(i), 'x');
    bus.PublishRaw(channel, data.data(), data.size());
    if (channel != "OTHER") sent.push_back({channel, 0, data});
  }
  HandleAll(bus);
  const int64_t after = glue::WallUtime();
  EXPECT_EQ(recorder.events(), 200);
  EXPECT_EQ(recorder.write_errors(), 0);
  log.Close();
  const auto got = ReadLog(path);
  ASSERT_EQ(got.size(), sent.size());
  int64_t last = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].channel, sent[i].channel) << i;
    EXPECT_EQ(got[i].data, sent[i].data) << i;
    EXPECT_GE(got[i].timestamp, before);  // the receive time (the wall clock), as lcm-logger stamps
    EXPECT_LE(got[i].timestamp, after);
    EXPECT_GE(got[i].timestamp, last);
    last = got[i].timestamp;
  }
}

TEST(Recorder, AppendAddsToTheEndOfTheLog) {
  const std::string path = TempLog("append");
  for (int run = 0; run < 2; ++run) {
    glue::Bus bus("memq://");
    glue::LogWriter log(path, /*append=*/run > 0);
    Recorder recorder(bus, log, RecorderOptions{});
    for (int i = 0; i < 3; ++i) {
      const std::string data = std::to_string(run) + ":" + std::to_string(i);
      bus.PublishRaw("REC_APPEND", data.data(), data.size());
    }
    HandleAll(bus);
    log.Close();
  }
  const auto got = ReadLog(path);
  ASSERT_EQ(got.size(), 6u);
  EXPECT_EQ(got[0].data, "0:0");
  EXPECT_EQ(got[3].data, "1:0");
  EXPECT_EQ(got[5].data, "1:2");
}

TEST(Recorder, AWriteFailureStopsTheRecordingAndIsCounted) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  glue::Bus bus("memq://");
  glue::LogWriter log("/dev/full");  // every write fails: no space left on the device
  RecorderOptions options;
  options.flush_interval_s = 0;  // hand every event to the system at once: the failure shows on the first
  Recorder recorder(bus, log, options);
  for (int i = 0; i < 5; ++i) bus.PublishRaw("REC_FULL", "abc", 3);
  HandleAll(bus);
  EXPECT_EQ(recorder.write_errors(), 1);
  EXPECT_NE(recorder.last_error().find("/dev/full"), std::string::npos) << recorder.last_error();
  EXPECT_EQ(bus.stats().at("REC_FULL").handler_errors, 1u);  // reported on the channel, the process goes on
}

TEST(Recorder, OptionsAreValidated) {
  RecorderOptions o;
  o.queue_capacity = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = RecorderOptions{};
  o.channels = "";
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  o = RecorderOptions{};
  o.flush_interval_s = -1;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
}

// On UDP multicast, with the recorder's loop held up while a burst arrives: the recorder keeps every
// message; a subscription with LCM's default capacity (lcm-logger's) keeps 30. Runs in the private
// network namespace of ctest bus_queue_capacity_private_bus (SNAPNAV_PRIVATE_BUS set).
TEST(BusPrivate, RecorderKeepsABurstThatLcmsDefaultQueueDrops) {
  if (!std::getenv("SNAPNAV_PRIVATE_BUS")) GTEST_SKIP() << "needs the private bus: ctest -R bus_queue_capacity";
  const std::string path = TempLog("burst");
  glue::Bus bus("udpm://239.255.76.67:7692?ttl=0&recv_buf_size=4194304");
  glue::LogWriter log(path);
  Recorder recorder(bus, log, RecorderOptions{});
  int default_queue = 0;
  bus.SubscribeRaw("REC_BURST", [&](const void*, size_t) { ++default_queue; });
  glue::Bus publisher("udpm://239.255.76.67:7692?ttl=0");
  const std::string data(200, 'p');
  for (int i = 0; i < 2000; ++i) publisher.PublishRaw("REC_BURST", data.data(), data.size());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // nothing handled while the burst arrives
  while (bus.HandleOnce(200)) {
  }
  EXPECT_EQ(recorder.events(), 2000);
  EXPECT_LE(default_queue, glue::Bus::kDefaultQueueCapacity + 1);
  log.Close();
  EXPECT_EQ(ReadLog(path).size(), 2000u);
}

}  // namespace
}  // namespace snapnav::tools
