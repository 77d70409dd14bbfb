#pragma once
// The recorder: every message of the bus into an LCM log, as lcm-logger records it (each event
// stamped with its receive time; the format lcm-logplayer, lcm-spy and every snapnav tool read),
// with a deep queue. LCM keeps at most a subscription's queue capacity of received messages while
// the handler has not taken them, and drops the rest for that subscriber without a count; Debian's
// lcm-logger (1.3.1) subscribes with LCM's default, 30 messages, which a moment without the CPU or a
// publisher catching up in a burst overruns (docs/deployment.md: 828 of 1,022,490 lost in an hour).

#include <cstdint>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/log_writer.hpp"

namespace snapnav::tools {

struct RecorderOptions {
  std::string channels = ".*";    // LCM channel regex
  int queue_capacity = 20000;     // messages LCM keeps for the recorder while it lags (30 s at 650 per s)
  double flush_interval_s = 0.1;  // hands the buffered events to the operating system this often [s, wall clock]
  void Validate() const;          // throws std::invalid_argument
};

class Recorder {
 public:
  // Subscribes to options.channels on `bus`; writes into `log` (which outlives the recorder).
  Recorder(glue::Bus& bus, glue::LogWriter& log, const RecorderOptions& options);

  int64_t events() const { return events_; }
  int64_t bytes() const { return bytes_; }
  // Events that could not be written (the disk full, the file gone): after the first, nothing more is
  // written and the caller stops (recorder's main: the handle loop ends).
  int64_t write_errors() const { return write_errors_; }
  const std::string& last_error() const { return last_error_; }
  // Flushes what is buffered; throws std::runtime_error when it cannot.
  void Flush() { log_.Flush(); }

 private:
  void OnMessage(const void* data, size_t size);

  glue::Bus& bus_;
  glue::LogWriter& log_;
  RecorderOptions options_;
  int64_t events_ = 0;
  int64_t bytes_ = 0;
  int64_t write_errors_ = 0;
  std::string last_error_;
  int64_t last_flush_utime_ = 0;
};

}  // namespace snapnav::tools
