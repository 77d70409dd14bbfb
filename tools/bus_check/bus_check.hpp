#pragma once
// bus-check: probe frames of known content, a verifier that checks every one
// arrived byte-identical and in order, an echo node and a round-trip pinger.

#include <cstdint>
#include <string>
#include <vector>

#include "snapnav/glue/bus.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::tools {

inline constexpr int64_t kProbeBaseUtime = 1'000'000'000;  // utime of probe 0 [us]
inline constexpr int64_t kProbePeriodUtime = 1'000;        // utime step per probe [us]

// Probe number `seq`: a one-row GRAY8 omni frame of `size_bytes` pixels whose
// content is a function of seq. utime encodes seq.
omni_frame_t MakeProbeFrame(int64_t seq, int size_bytes);
// Inverse of the utime encoding of MakeProbeFrame (-1 if not a probe utime).
int64_t ProbeSeq(int64_t utime);
// The utime field of an encoded omni_frame_t payload, without decoding it all.
int64_t PayloadUtime(const void* data, size_t size);

// Checks the probes on `channel`: probe k must be byte-identical to
// MakeProbeFrame(k, sizes[k % sizes.size()]) and arrive after probe k-1.
class ProbeVerifier {
 public:
  ProbeVerifier(glue::Bus& bus, const std::string& channel, std::vector<int> sizes_bytes, int expected_count);
  bool complete() const { return received_ == expected_count_; }
  bool ok() const;
  int received() const { return received_; }
  int corrupt() const { return corrupt_; }
  int out_of_order() const { return out_of_order_; }
  int duplicates() const { return duplicates_; }
  int64_t bytes() const { return bytes_; }
  std::string Report() const;

 private:
  void OnProbe(const void* data, size_t size);

  glue::Bus& bus_;
  std::vector<int> sizes_bytes_;
  int expected_count_;
  std::vector<bool> seen_;
  int64_t last_seq_ = -1;
  int received_ = 0, corrupt_ = 0, out_of_order_ = 0, duplicates_ = 0;
  int64_t bytes_ = 0;
};

// Republishes every payload of `in_channel` on `out_channel`, unchanged.
class EchoNode {
 public:
  EchoNode(glue::Bus& bus, const std::string& in_channel, std::string out_channel);
  int64_t echoed() const { return echoed_; }

 private:
  glue::Bus& bus_;
  std::string out_channel_;
  int64_t echoed_ = 0;
};

struct PingResult {
  int size_bytes = 0;
  int sent = 0;
  int received = 0;
  double median_ms = 0, p99_ms = 0, max_ms = 0;
};

// Sends probes of each size at rate_hz for duration_s to ping_channel and
// times their echoes on pong_channel (steady clock).
std::vector<PingResult> RunPing(glue::Bus& bus, const std::string& ping_channel, const std::string& pong_channel,
                                const std::vector<int>& sizes_bytes, double rate_hz, double duration_s,
                                bool progress);

}  // namespace snapnav::tools
