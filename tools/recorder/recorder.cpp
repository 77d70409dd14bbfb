#include "recorder.hpp"

#include <cmath>
#include <stdexcept>

#include "snapnav/glue/time.hpp"

namespace snapnav::tools {

void RecorderOptions::Validate() const {
  if (channels.empty()) throw std::invalid_argument("the channel regex must not be empty");
  if (queue_capacity < 1) throw std::invalid_argument("the queue capacity must be at least 1 message");
  if (!(flush_interval_s >= 0) || !std::isfinite(flush_interval_s)) {
    throw std::invalid_argument("the flush interval must be >= 0 s");
  }
}

Recorder::Recorder(glue::Bus& bus, glue::LogWriter& log, const RecorderOptions& options)
    : bus_(bus), log_(log), options_(options) {
  options_.Validate();
  last_flush_utime_ = glue::MonotonicUtime();
  bus_.SubscribeRaw(
      options_.channels, [this](const void* data, size_t size) { OnMessage(data, size); }, options_.queue_capacity);
}

void Recorder::OnMessage(const void* data, size_t size) {
  if (write_errors_ > 0) return;  // stopping: nothing more goes into a file that failed
  const glue::MessageInfo& m = bus_.current();
  try {
    log_.WriteRaw(m.channel, m.recv_utime, std::string(static_cast<const char*>(data), size));
    ++events_;
    bytes_ += static_cast<int64_t>(size);
    const int64_t now = glue::MonotonicUtime();
    if (now - last_flush_utime_ >= static_cast<int64_t>(options_.flush_interval_s * 1e6)) {
      log_.Flush();
      last_flush_utime_ = now;
    }
  } catch (const std::exception& e) {
    ++write_errors_;
    last_error_ = e.what();
    throw;  // the bus counts it on the channel and reports it; the recorder's loop stops on write_errors()
  }
}

}  // namespace snapnav::tools
