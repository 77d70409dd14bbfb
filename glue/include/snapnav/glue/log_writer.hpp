#pragma once
// Writes LCM log files directly (lcm::LogFile), stamping each event with the
// message's utime so that the same input gives a byte-identical log.

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "snapnav/glue/codec.hpp"

namespace snapnav::glue {

class LogWriter {
 public:
  // Creates (truncates) `path`, or with `append` adds to its end (creating it when missing); throws
  // std::runtime_error if it cannot.
  explicit LogWriter(const std::string& path, bool append = false)
      : path_(path), log_(std::make_unique<lcm::LogFile>(path, append ? "a" : "w")) {
    if (!log_->good()) {
      throw std::runtime_error(std::string("cannot ") + (append ? "open" : "create") + " LCM log '" + path +
                               "': " + std::strerror(errno));
    }
  }
  void WriteRaw(const std::string& channel, int64_t timestamp_us, const std::string& bytes) {
    if (!log_) throw std::logic_error("LCM log '" + path_ + "' is closed");
    lcm::LogEvent ev;
    ev.eventnum = events_;
    ev.timestamp = timestamp_us;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(bytes.size());
    ev.data = const_cast<char*>(bytes.data());
    if (log_->writeEvent(&ev) != 0 || std::ferror(log_->getFilePtr())) {
      throw std::runtime_error("cannot write to LCM log '" + path_ + "': " + std::strerror(errno));
    }
    ++events_;
  }
  template <class Msg>
  void Write(const std::string& channel, const Msg& msg) {
    WriteRaw(channel, msg.utime, Encode(msg));
  }
  // Flushes and closes; throws std::runtime_error if the data did not reach the file.
  void Close() {
    if (!log_) return;
    const bool flushed = std::fflush(log_->getFilePtr()) == 0 && !std::ferror(log_->getFilePtr());
    log_.reset();
    if (!flushed) throw std::runtime_error("cannot write to LCM log '" + path_ + "': " + std::strerror(errno));
  }
  // Hands what is buffered to the operating system (a crash of the process then loses nothing written).
  void Flush() {
    if (log_ && std::fflush(log_->getFilePtr()) != 0) {
      throw std::runtime_error("cannot write to LCM log '" + path_ + "': " + std::strerror(errno));
    }
  }
  int64_t events() const { return events_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t events_ = 0;
};

}  // namespace snapnav::glue
