#pragma once
// Internals shared by the importers: the emitter that counts what is written, bounded line
// reading, strict number parsing, and a zlib-backed input stream (plain or gzip files).

#include <cstdint>
#include <istream>
#include <map>
#include <memory>
#include <optional>
#include <streambuf>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "importers.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::importers::internal {

// Writes messages to the sink and keeps the report's per-channel counts and time spans.
class Emitter {
 public:
  Emitter(Sink& sink, ImportReport& report) : sink_(sink), report_(report) {}

  template <class Msg>
  void Emit(const std::string& channel, const Msg& msg) {
    Write(channel, msg.utime, glue::Encode(msg));
  }
  // These also keep the beam, range and path figures of the report.
  void Emit(const std::string& channel, const laser_scan_t& msg);
  void Emit(const std::string& channel, const odometry_t& msg);
  void Emit(const std::string& channel, const pose_t& msg);

 private:
  ChannelStats& Write(const std::string& channel, int64_t utime, const std::string& payload);
  void AddToPath(const std::string& channel, ChannelStats& stats, double x_m, double y_m);

  Sink& sink_;
  ImportReport& report_;
  bool any_ = false;
  int64_t last_utime_ = 0;
  std::map<std::string, std::pair<double, double>> last_position_;  // per channel [m]
};

// Reads lines of at most max_line_bytes (a longer line is reported and skipped, so a binary
// file without newlines never grows a buffer without bound). Strips a trailing '\r'.
class LineReader {
 public:
  enum class Status { kLine, kTooLong, kEnd };

  LineReader(std::istream& in, size_t max_line_bytes) : in_(in), max_line_bytes_(max_line_bytes) {}
  Status Next();
  const std::string& line() const { return line_; }
  int64_t line_number() const { return line_number_; }
  bool had_newline() const { return had_newline_; }  // false for a last line without '\n'
  int64_t bytes_read() const { return bytes_read_; }

 private:
  std::istream& in_;
  size_t max_line_bytes_;
  std::string line_;
  int64_t line_number_ = 0;
  bool had_newline_ = false;
  int64_t bytes_read_ = 0;
};

// Splits on spaces and tabs.
void Tokenize(std::string_view line, std::vector<std::string_view>* tokens);

// Strict parsing: the whole token must be a finite number / an integer.
std::optional<double> ParseDouble(std::string_view text);
std::optional<int64_t> ParseInt64(std::string_view text);

// For messages: the token, shortened to 40 characters and with control bytes replaced.
std::string Quote(std::string_view text);

// Seconds with microseconds, e.g. "1134864629.895182".
std::string FormatUtime(int64_t utime);

// Rounds seconds to microseconds; nullopt if out of range.
std::optional<int64_t> SecondsToUtime(double seconds);

// An input file read through zlib: gzip-compressed or plain, detected by content.
class ZlibInputFile : public std::istream {
 public:
  explicit ZlibInputFile(const std::string& path);
  ~ZlibInputFile() override;

  bool is_open() const;
  bool compressed() const;            // true for gzip content
  int64_t file_bytes() const;         // size on disk [bytes]
  int64_t compressed_offset() const;  // position in the file on disk [bytes]
  // gzip: the decompressed size stored in the trailer (modulo 2^32), 0 if unknown; plain: the size.
  int64_t content_bytes_hint() const;
  // Empty, or why reading stopped early (truncated or corrupt gzip data, read error).
  const std::string& error() const;

 private:
  class Buffer;
  std::unique_ptr<Buffer> buffer_;
};

}  // namespace snapnav::importers::internal
