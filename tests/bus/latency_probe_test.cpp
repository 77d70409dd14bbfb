// latency-probe on memq://: outputs are paired with the frame of the same utime, CHANNEL@AFTER
// waits for AFTER's output of that frame, strangers and repeats are counted apart.
#include <gtest/gtest.h>

#include <sstream>

#include "bus_check.hpp"
#include "latency_probe.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/homing_vector_t.hpp"

namespace snapnav::tools {
namespace {

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

homing_vector_t Vector(int64_t utime) {
  homing_vector_t v{};
  v.utime = utime;
  v.alv_variant = "hog";
  return v;
}

pose_t Pose(int64_t utime) { return glue::ToPoseMsg(utime, "x", "map", {}, Eigen::Matrix3d::Zero()); }

TEST(LatencyProbe, ParsesOutputs) {
  const auto o = ParseLatencyOutputs("A,B,C@B");
  ASSERT_EQ(o.size(), 3u);
  EXPECT_EQ(o[2].channel, "C");
  EXPECT_EQ(o[2].after, "B");
  EXPECT_THROW(ParseLatencyOutputs("C@B,B"), std::invalid_argument);
  EXPECT_THROW(ParseLatencyOutputs("A,,B"), std::invalid_argument);
  EXPECT_THROW(ParseLatencyOutputs(""), std::invalid_argument);
  EXPECT_THROW(ParseLatencyOutputs("A@"), std::invalid_argument);
}

TEST(LatencyProbe, Quantiles) {
  EXPECT_EQ(Quantile({}, 0.5), 0);
  EXPECT_EQ(Quantile({3, 1, 2}, 0.5), 2);
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(i);
  EXPECT_EQ(Quantile(v, 0.95), 95);
  EXPECT_EQ(Quantile(v, 1.0), 100);
  EXPECT_THROW(Quantile(v, 1.5), std::invalid_argument);
}

TEST(LatencyProbe, LogsEveryFramesUtimeAndReceiveTime) {
  glue::Bus bus("memq://");
  LatencyProbe probe(bus, "F_FRAME", ParseLatencyOutputs("F_VEC"));
  std::ostringstream log;
  probe.LogFrames(&log);
  for (int k = 0; k < 3; ++k) bus.Publish("F_FRAME", MakeProbeFrame(k, 100));
  HandleAll(bus);
  std::istringstream lines(log.str());
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    const auto comma = line.find(',');
    ASSERT_NE(comma, std::string::npos) << line;
    EXPECT_EQ(std::stoll(line.substr(0, comma)), MakeProbeFrame(n, 1).utime);
    EXPECT_GT(std::stoll(line.substr(comma + 1)), 1'600'000'000'000'000);  // LCM's receive time: the wall clock
    ++n;
  }
  EXPECT_EQ(n, 3);
}

TEST(LatencyProbe, PairsOutputsWithTheirFrames) {
  glue::Bus bus("memq://");
  LatencyProbe probe(bus, "L_FRAME", ParseLatencyOutputs("L_VEC,L_CELLS,L_EKF@L_CELLS"));
  for (int k = 0; k < 5; ++k) bus.Publish("L_FRAME", MakeProbeFrame(k, 100));
  HandleAll(bus);
  const int64_t t0 = MakeProbeFrame(0, 1).utime, t1 = MakeProbeFrame(1, 1).utime, t2 = MakeProbeFrame(2, 1).utime;
  bus.Publish("L_VEC", Vector(t0));
  bus.Publish("L_VEC", Vector(t1));
  bus.Publish("L_VEC", Vector(t1));       // a repeat
  bus.Publish("L_VEC", Vector(12345));    // no such frame
  bus.Publish("L_EKF", Pose(t2));         // before the frame's place-cell fix: a scan's pose
  bus.Publish("L_CELLS", Pose(t2));
  bus.Publish("L_EKF", Pose(t2));         // the fused pose of that fix
  HandleAll(bus);
  EXPECT_EQ(probe.frames(), 5);
  const LatencyStats vec = probe.Stats("L_VEC"), cells = probe.Stats("L_CELLS"), ekf = probe.Stats("L_EKF");
  EXPECT_EQ(vec.outputs, 4);
  EXPECT_EQ(vec.matched, 2);
  EXPECT_EQ(vec.repeats, 1);
  EXPECT_EQ(vec.unmatched, 1);
  EXPECT_EQ(cells.matched, 1);
  EXPECT_EQ(ekf.matched, 1);
  EXPECT_EQ(ekf.unmatched, 1);
  EXPECT_EQ(probe.frames_without("L_VEC"), 3);
  EXPECT_GE(vec.min_ms, 0.0);
  EXPECT_GE(vec.max_ms, vec.median_ms);
  EXPECT_EQ(probe.samples_ms("L_VEC").size(), 2u);
  EXPECT_EQ(probe.Stats("NOT_AN_OUTPUT").outputs, 0);
}

TEST(LatencyProbe, ForgetsOldFrames) {
  glue::Bus bus("memq://");
  LatencyProbe probe(bus, "L2_FRAME", ParseLatencyOutputs("L2_VEC"), 1.0);
  auto f = MakeProbeFrame(0, 10);
  bus.Publish("L2_FRAME", f);
  f.utime += 2'000'000;  // 2 s later: the first one is out of the window
  bus.Publish("L2_FRAME", f);
  HandleAll(bus);
  bus.Publish("L2_VEC", Vector(MakeProbeFrame(0, 10).utime));
  HandleAll(bus);
  EXPECT_EQ(probe.Stats("L2_VEC").unmatched, 1);
}

}  // namespace
}  // namespace snapnav::tools
