#pragma once
// latency-probe: end-to-end latency through the processes. It subscribes to an input channel
// (omni frames) and to output channels (homing vectors, poses ...) and stamps each message with
// its own receive time (LCM's, one clock). An output whose utime equals a frame's utime is that
// frame's result: latency = receive time of the output - receive time of the frame. Every snapnav
// type starts with int64_t utime, so the probe decodes no more than that.

#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "snapnav/glue/bus.hpp"

namespace snapnav::tools {

// One output to time. With `after` set, the output counts only once the `after` output of the
// same frame has arrived (e.g. the fused pose produced from that frame's place-cell fix, when
// scans share the frame's utime).
struct LatencyOutput {
  std::string channel;
  std::string after;  // empty: the first message with the frame's utime
};

// "HOMING_VECTOR,POSE_EKF@POSE_PLACE_CELLS" -> outputs; throws std::invalid_argument on an empty
// name or an `after` that is not listed before.
std::vector<LatencyOutput> ParseLatencyOutputs(const std::string& text);

struct LatencyStats {
  int64_t outputs = 0;    // messages received on the channel
  int64_t matched = 0;    // of them, the first result of a frame received by the probe
  int64_t unmatched = 0;  // utime of no frame seen (or too old), or before its `after` output
  int64_t repeats = 0;    // a second message for a frame already matched
  double median_ms = 0, p95_ms = 0, max_ms = 0, min_ms = 0, mean_ms = 0;
};

// The q-quantile of `v` (0 <= q <= 1; nearest rank on the sorted values); 0 for an empty vector.
double Quantile(std::vector<double> v, double q);

class LatencyProbe {
 public:
  // Subscribes to `input` and every output channel (names already prefixed). Frames older than
  // `window_s` of message time than the newest one are forgotten.
  LatencyProbe(glue::Bus& bus, const std::string& input, const std::vector<LatencyOutput>& outputs,
               double window_s = 30);

  // Every frame's utime and receive time from now on, as CSV lines "utime,recv_utime" (null: none).
  void LogFrames(std::ostream* out) { frame_log_ = out; }

  int64_t frames() const { return frames_; }
  // Figures of one output channel (all zero when nothing came).
  LatencyStats Stats(const std::string& channel) const;
  const std::vector<double>& samples_ms(const std::string& channel) const;
  const std::vector<LatencyOutput>& outputs() const { return outputs_; }
  // Frames that got no result on `channel`.
  int64_t frames_without(const std::string& channel) const;

 private:
  struct Frame {
    int64_t recv_utime = 0;
    std::map<std::string, int64_t> results;  // output channel -> its receive time
  };
  void OnFrame(const void* data, size_t size);
  void OnOutput(const LatencyOutput& out, const void* data, size_t size);

  glue::Bus& bus_;
  std::ostream* frame_log_ = nullptr;
  std::vector<LatencyOutput> outputs_;
  int64_t window_us_;
  std::map<int64_t, Frame> frames_by_utime_;
  int64_t frames_ = 0, newest_utime_ = 0;
  std::map<std::string, LatencyStats> counts_;
  std::map<std::string, std::vector<double>> samples_;
  std::map<std::string, int64_t> matched_frames_;
};

}  // namespace snapnav::tools
