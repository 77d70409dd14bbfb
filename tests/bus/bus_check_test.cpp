// Node tests of bus-check on memq://: the verifier accepts exactly the probes
// that were sent, and the echo node returns them byte-identical.
#include <gtest/gtest.h>

#include "bus_check.hpp"
#include "snapnav/glue/codec.hpp"

namespace snapnav::tools {
namespace {

TEST(BusCheck, ProbeFramesAreDeterministicAndDistinct) {
  EXPECT_EQ(glue::Encode(MakeProbeFrame(3, 1000)), glue::Encode(MakeProbeFrame(3, 1000)));
  EXPECT_NE(glue::Encode(MakeProbeFrame(3, 1000)), glue::Encode(MakeProbeFrame(4, 1000)));
  EXPECT_EQ(ProbeSeq(MakeProbeFrame(17, 10).utime), 17);
  const std::string bytes = glue::Encode(MakeProbeFrame(5, 100));
  EXPECT_EQ(PayloadUtime(bytes.data(), bytes.size()), MakeProbeFrame(5, 100).utime);
}

TEST(BusCheck, VerifierAcceptsAllProbesInOrder) {
  glue::Bus bus("memq://");
  const std::vector<int> sizes{100, 65536, 1048576};
  ProbeVerifier verifier(bus, "TEST_PROBE_OK", sizes, 6);
  for (int k = 0; k < 6; ++k) bus.Publish("TEST_PROBE_OK", MakeProbeFrame(k, sizes[k % 3]));
  while (bus.HandleOnce(0)) {
  }
  EXPECT_TRUE(verifier.ok()) << verifier.Report();
  EXPECT_EQ(verifier.bytes(), 2 * (glue::Encode(MakeProbeFrame(0, 100)).size() +
                                   glue::Encode(MakeProbeFrame(1, 65536)).size() +
                                   glue::Encode(MakeProbeFrame(2, 1048576)).size()));
}

TEST(BusCheck, VerifierDetectsLossReorderAndCorruption) {
  glue::Bus bus("memq://");
  ProbeVerifier verifier(bus, "TEST_PROBE_BAD", {100}, 4);
  bus.Publish("TEST_PROBE_BAD", MakeProbeFrame(1, 100));
  bus.Publish("TEST_PROBE_BAD", MakeProbeFrame(0, 100));  // out of order
  auto corrupt = MakeProbeFrame(2, 100);
  corrupt.data[50] ^= 1;
  bus.Publish("TEST_PROBE_BAD", corrupt);
  while (bus.HandleOnce(0)) {
  }
  EXPECT_FALSE(verifier.ok());
  EXPECT_FALSE(verifier.complete());
  EXPECT_EQ(verifier.out_of_order(), 1);
  EXPECT_EQ(verifier.corrupt(), 1);
  EXPECT_NE(verifier.Report().find("missing: 2 3"), std::string::npos) << verifier.Report();
}

TEST(BusCheck, EchoNodeReturnsPayloadUnchanged) {
  glue::Bus bus("memq://");
  EchoNode echo(bus, "TEST_PING", "TEST_PONG");
  std::string got;
  bus.SubscribeRaw("TEST_PONG", [&](const void* d, size_t n) { got.assign(static_cast<const char*>(d), n); });
  const std::string sent = glue::Encode(MakeProbeFrame(9, 4096));
  bus.PublishRaw("TEST_PING", sent.data(), sent.size());
  while (bus.HandleOnce(0)) {
  }
  EXPECT_EQ(echo.echoed(), 1);
  EXPECT_EQ(got, sent);
}

}  // namespace
}  // namespace snapnav::tools

namespace snapnav::tools {
namespace {

TEST(BusCheckSoak, StreamsAreDeterministicAndDistinct) {
  EXPECT_EQ(glue::Encode(MakeSoakFrame(3, 4096)), glue::Encode(MakeSoakFrame(3, 4096)));
  EXPECT_NE(glue::Encode(MakeSoakFrame(3, 4096)), glue::Encode(MakeSoakFrame(4, 4096)));
  EXPECT_EQ(MakeSoakFrame(2, 1048576).data.size(), 1048576u);
  EXPECT_EQ(glue::Encode(MakeSoakScan(5, 681)), glue::Encode(MakeSoakScan(5, 681)));
  EXPECT_NE(glue::Encode(MakeSoakScan(5, 681)), glue::Encode(MakeSoakScan(6, 681)));
  EXPECT_EQ(ProbeSeq(MakeSoakScan(9, 10).utime), 9);
  EXPECT_THROW(MakeSoakFrame(0, 4), std::invalid_argument);
}

TEST(BusCheckSoak, VerifierCountsEveryStream) {
  glue::Bus bus("memq://");
  SoakVerifier verifier(bus, "T_SOAK_FRAME", "T_SOAK_SCAN", 4096, 100, 6, 2);
  for (int k = 0; k < 6; ++k) {
    bus.Publish("T_SOAK_FRAME", MakeSoakFrame(k, 4096));
    if (k % 3 == 0) bus.Publish("T_SOAK_SCAN", MakeSoakScan(k / 3, 100));
  }
  while (bus.HandleOnce(0)) {
  }
  EXPECT_TRUE(verifier.ok()) << verifier.Report();
  EXPECT_EQ(verifier.frames().received, 6);
  EXPECT_EQ(verifier.scans().received, 2);
  EXPECT_EQ(verifier.Counts("v_").at("v_frames_missing"), 0);
}

TEST(BusCheckSoak, VerifierDetectsLossDuplicatesAndCorruption) {
  glue::Bus bus("memq://");
  SoakVerifier verifier(bus, "T_SOAK_FRAME2", "T_SOAK_SCAN2", 4096, 100, 4, 2);
  bus.Publish("T_SOAK_FRAME2", MakeSoakFrame(1, 4096));
  bus.Publish("T_SOAK_FRAME2", MakeSoakFrame(1, 4096));  // duplicate
  bus.Publish("T_SOAK_FRAME2", MakeSoakFrame(0, 4096));  // out of order
  auto bad = MakeSoakScan(0, 100);
  bad.ranges_m[50] += 1;
  bus.Publish("T_SOAK_SCAN2", bad);
  bus.Publish("T_SOAK_SCAN2", MakeSoakScan(7, 100));  // never sent
  while (bus.HandleOnce(0)) {
  }
  EXPECT_FALSE(verifier.ok());
  EXPECT_EQ(verifier.frames().missing(), 2);
  EXPECT_EQ(verifier.frames().duplicates, 1);
  EXPECT_EQ(verifier.frames().out_of_order, 1);
  EXPECT_EQ(verifier.scans().corrupt, 2);
  EXPECT_EQ(verifier.scans().missing(), 2);
}

TEST(BusCheckSoak, RssOfThisProcessIsKnown) {
  EXPECT_GT(ProcessRssKb(), 0);
  EXPECT_EQ(ProcessRssKb(999999999), -1);
}

}  // namespace
}  // namespace snapnav::tools
