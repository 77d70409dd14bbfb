#pragma once
// Reads LCM log files (the format lcm-logger writes) and says where they are damaged.
//
// An event is a 4-byte sync word 0xEDA1DA01, the event number (int64), the timestamp [us]
// (int64), the channel length (int32), the data length (int32), the channel and the data, all
// big-endian. LCM's own reader (lcm::LogFile) skips anything that is not a sync word and stops
// at the first event it cannot read, silently. LogReader instead checks each event's header (a
// channel of 1..999 bytes without control characters, data that fits in the file and holds
// no other intact event) and, on damage, records the byte offset and what
// was wrong, then resynchronises at the next plausible event, so every intact event before and
// after the damage is read. Memory is bounded by the file: nothing is allocated for a length the
// file cannot hold.

#include <cstdint>
#include <cstdio>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace snapnav::glue {

// The file cannot be opened or read (the message names it).
class LogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LogEvent {
  int64_t eventnum = 0;
  int64_t timestamp_us = 0;  // the event time lcm-logger stamped (receive time) [microseconds]
  std::string channel;
  std::string data;          // the message payload
  uint64_t offset = 0;       // byte offset of the event's sync word in the file
};

// One damaged stretch of a log.
struct LogDamage {
  enum class Kind { kCorrupt, kTruncated };
  Kind kind = Kind::kCorrupt;
  uint64_t offset = 0;      // where the damage starts [bytes from the start of the file]
  uint64_t resumed_at = 0;  // where reading resumed (the file size when nothing valid followed)
  std::string what;         // what is wrong there
  uint64_t skipped_bytes() const { return resumed_at - offset; }
};

// "PATH: byte N: WHAT; skipped K bytes, resumed at byte M" (or "...; the rest of the file (K
// bytes) is lost").
std::string DescribeLogDamage(const std::string& path, const LogDamage& damage, uint64_t file_size);

// Channel names longer than this are taken as damage (LCM itself allows 63 on UDP).
inline constexpr int32_t kMaxLogChannelLength = 999;

class LogReader {
 public:
  // Opens `path`; throws LogError naming it when it cannot be opened, or when it is not an LCM
  // log at all: it does not start with an event (nor with the start of one, cut off) and holds
  // no intact event anywhere ("PATH is not an LCM log: byte 0: ..."). A log whose first event is
  // damaged but which holds intact events is a damaged log, read as such.
  explicit LogReader(const std::string& path);
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;
  ~LogReader();

  // Reads the next intact event; false at the end of the file. Damage on the way is recorded in
  // damage() (and skipped). Throws LogError when the file cannot be read (an I/O error).
  bool Next(LogEvent* event);

  const std::string& path() const { return path_; }
  uint64_t file_size() const { return size_; }
  uint64_t position() const { return pos_; }   // byte offset of the next event to read
  int64_t events() const { return events_; }   // intact events read so far
  const std::vector<LogDamage>& damage() const { return damage_; }
  bool damaged() const { return !damage_.empty(); }
  uint64_t damaged_bytes() const;
  // One line per damaged stretch, each starting with `program: ` (nothing when intact).
  void ReportDamage(std::ostream& out, const std::string& program) const;

 private:
  struct Header {
    int64_t eventnum = 0, timestamp_us = 0;
    int32_t channel_length = 0, data_length = 0;
    std::string channel;
    uint64_t end = 0;  // offset just past the event
  };
  // Reads the header at `at`; returns "" when it is plausible, else what is wrong with it.
  std::string CheckHeader(uint64_t at, Header* header);
  bool SyncWordAt(uint64_t at);
  // Offset of the first plausible event header at or after `from` and before `limit` (the file
  // size when none).
  uint64_t FindNextEvent(uint64_t from, uint64_t limit);
  // Offset of the first plausible event header inside `data` (read from `data_start`), else the
  // file size.
  uint64_t FindEventInData(const std::string& data, uint64_t data_start);
  void ReadAt(uint64_t at, void* buffer, size_t size);
  void AddDamage(LogDamage::Kind kind, uint64_t offset, uint64_t resumed_at, const std::string& what);
  // At opening: throws LogError when the file is not an LCM log; a damaged start is recorded.
  void CheckIsLog();

  std::string path_;
  std::FILE* file_ = nullptr;
  uint64_t size_ = 0;
  uint64_t pos_ = 0;
  int64_t events_ = 0;
  std::vector<LogDamage> damage_;
};

}  // namespace snapnav::glue
