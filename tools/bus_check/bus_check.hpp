#pragma once
// bus-check: probe frames of known content, a verifier that checks every one
// arrived byte-identical and in order, an echo node and a round-trip pinger.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "results.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/laser_scan_t.hpp"
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


// ---------------------------------------------------------------- soak
// Two streams of known content for the soak test: omni frames of `size_bytes` (a fixed
// pseudo-random image whose first 8 bytes are the sequence number, so a frame costs a copy, not
// a random generator) and laser scans of `beams` ranges that are a function of seq. utime
// encodes seq as for the probes.
omni_frame_t MakeSoakFrame(int64_t seq, int size_bytes);
laser_scan_t MakeSoakScan(int64_t seq, int beams);

// Counts of one soak stream at a subscriber.
struct SoakStream {
  int64_t expected = 0;  // messages the publisher sends
  int64_t received = 0;  // distinct, byte-identical messages
  int64_t corrupt = 0, out_of_order = 0, duplicates = 0;
  int64_t bytes = 0;
  int64_t missing() const { return expected - received; }
};

// Checks both soak streams: message k must be byte-identical to MakeSoakFrame(k, ...) /
// MakeSoakScan(k, ...) and arrive after message k-1.
class SoakVerifier {
 public:
  // Subscribes to both channels on `bus`.
  SoakVerifier(glue::Bus& bus, const std::string& frame_channel, const std::string& scan_channel, int frame_bytes,
               int beams, int64_t expected_frames, int64_t expected_scans);
  // Without a bus: messages come through Feed (e.g. the events of a log).
  SoakVerifier(const std::string& frame_channel, const std::string& scan_channel, int frame_bytes, int beams,
               int64_t expected_frames, int64_t expected_scans);
  // One message of `channel`; other channels are counted in ignored(). A bad message is counted, never thrown.
  void Feed(const std::string& channel, const void* data, size_t size);
  int64_t ignored() const { return ignored_; }
  const SoakStream& frames() const { return frames_; }
  const SoakStream& scans() const { return scans_; }
  bool complete() const { return frames_.missing() == 0 && scans_.missing() == 0; }
  bool ok() const;
  int64_t received_total() const { return frames_.received + scans_.received; }
  std::string Report() const;
  // The counts as flat JSON keys with `prefix` on every one, e.g. "verifier_frames_received": 9000.
  results::Json Counts(const std::string& prefix) const;

 private:
  struct Seen {
    std::vector<bool> seen;
    int64_t last_seq = -1;
  };
  void Check(const void* data, size_t size, const std::string& expected, int64_t seq, SoakStream* stream, Seen* seen);
  void OnFrame(const void* data, size_t size);
  void OnScan(const void* data, size_t size);
  int64_t errors() const;

  glue::Bus* bus_ = nullptr;  // null: fed by Feed
  std::string frame_channel_, scan_channel_;
  int frame_bytes_, beams_;
  int64_t ignored_ = 0, feed_errors_ = 0;
  SoakStream frames_, scans_;
  Seen frames_seen_, scans_seen_;
};

// Reads LCM log events in order from a file or a pipe (LCM's own reader loses events on pipes):
// magic 0xEDA1DA01, event number, timestamp, channel and data lengths (big-endian), channel, data.
class LogStreamReader {
 public:
  explicit LogStreamReader(const std::string& path);  // throws std::runtime_error naming the file
  ~LogStreamReader();
  LogStreamReader(const LogStreamReader&) = delete;
  LogStreamReader& operator=(const LogStreamReader&) = delete;
  // The next event; false at the end. A corrupt or truncated event throws std::runtime_error
  // naming the file and the byte offset.
  bool Next(std::string* channel, std::string* data, int64_t* timestamp_us);
  int64_t offset() const { return offset_; }

 private:
  bool Read(void* dst, size_t n);  // false at a clean end before the first byte
  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t offset_ = 0;
};

// Resident set size of process `pid` (0: this process) from /proc/PID/status [kB]; -1 when unknown.
int64_t ProcessRssKb(int pid = 0);

}  // namespace snapnav::tools
