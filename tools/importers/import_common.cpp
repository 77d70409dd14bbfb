// Shared parts of the importers: channel names, the report, the LCM log sink, and the
// internal helpers (emitter, bounded line reader, number parsing, zlib input).

#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "import_util.hpp"
#include "importers.hpp"

namespace snapnav::importers {

ChannelNames ChannelNames::WithPrefix(const std::string& prefix) {
  ChannelNames names;
  for (std::string* name :
       {&names.laser_scan, &names.odometry, &names.omni_frame, &names.pose_ground_truth, &names.pose_carmen}) {
    *name = channels::Prefixed(prefix, *name);
  }
  return names;
}

int64_t ImportReport::Count(const std::string& channel) const {
  const auto it = channels.find(channel);
  return it == channels.end() ? 0 : it->second.count;
}

int64_t ImportReport::TotalMessages() const {
  int64_t total = 0;
  for (const auto& [name, stats] : channels) total += stats.count;
  return total;
}

int64_t ImportReport::TotalSkipped() const {
  int64_t total = 0;
  for (const auto& [kind, count] : skipped) total += count;
  return total;
}

void ImportReport::AddError(std::string message) {
  ++error_count;
  if (errors.size() < kMaxStoredErrors) errors.push_back(std::move(message));
}

TimeSource ParseTimeSource(const std::string& text) {
  if (text == "auto") return TimeSource::kAuto;
  if (text == "log") return TimeSource::kLog;
  if (text == "synthesize") return TimeSource::kSynthesize;
  throw std::invalid_argument("time source must be auto, log or synthesize, got '" + text + "'");
}

std::string ToString(TimeSource source) {
  switch (source) {
    case TimeSource::kAuto:
      return "auto";
    case TimeSource::kLog:
      return "log";
    case TimeSource::kSynthesize:
      return "synthesize";
  }
  return "?";
}

void PrintSummary(const ImportReport& report, std::ostream& out) {
  out << "input: " << report.input << "\n";
  bool any = false;
  int64_t first = 0, last = 0;
  size_t width = 8;
  for (const auto& [name, stats] : report.channels) width = std::max(width, name.size());
  out << "messages written: " << report.TotalMessages() << "\n";
  for (const auto& [name, stats] : report.channels) {
    out << "  " << std::left << std::setw(static_cast<int>(width)) << name << std::right << std::setw(8) << stats.count
        << "   " << internal::FormatUtime(stats.first_utime) << " .. " << internal::FormatUtime(stats.last_utime)
        << " s\n";
    std::ostringstream detail;
    detail << std::fixed << std::setprecision(2);
    if (stats.readings > 0) {
      detail << "beams per scan " << stats.min_beams;
      if (stats.max_beams != stats.min_beams) detail << ".." << stats.max_beams;
      detail << "; returns " << stats.min_return_m << ".." << stats.max_return_m << " m; no return "
             << std::setprecision(1)
             << 100.0 * static_cast<double>(stats.no_returns) / static_cast<double>(stats.readings)
             << std::setprecision(2) << "% (range_max_m " << stats.max_range_m << ")";
    } else if (stats.path_length_m > 0) {
      detail << "path length " << stats.path_length_m << " m";
    }
    if (!detail.str().empty()) out << "  " << std::string(width, ' ') << "   " << detail.str() << "\n";
    if (!any || stats.first_utime < first) first = stats.first_utime;
    if (!any || stats.last_utime > last) last = stats.last_utime;
    any = true;
  }
  if (any) {
    out << "time span: " << internal::FormatUtime(first) << " .. " << internal::FormatUtime(last) << " s ("
        << std::fixed << std::setprecision(3) << (last - first) * 1e-6 << " s)\n";
    out.unsetf(std::ios::floatfield);
  }
  if (report.synthesized_utimes > 0) {
    out << "synthesized times: " << report.synthesized_utimes << " messages\n";
  }
  if (report.out_of_order > 0) {
    out << "out of order: " << report.out_of_order << " messages have a utime before the previous message's\n";
  }
  if (report.comment_lines > 0) out << "comment lines: " << report.comment_lines << "\n";
  if (!report.skipped.empty()) {
    out << "skipped (not converted): " << report.TotalSkipped() << "\n";
    for (const auto& [kind, count] : report.skipped) out << "  " << kind << ": " << count << "\n";
  }
  for (const auto& note : report.notes) out << "note: " << note << "\n";
  if (report.error_count > 0) {
    out << "errors: " << report.error_count << "\n";
    for (const auto& e : report.errors) out << "  " << e << "\n";
    if (report.error_count > static_cast<int64_t>(report.errors.size())) {
      out << "  ... and " << (report.error_count - static_cast<int64_t>(report.errors.size())) << " more\n";
    }
  }
}

LcmLogSink::LcmLogSink(const std::string& path) : log_(path) {}

LcmLogSink::~LcmLogSink() = default;

void LcmLogSink::Write(const std::string& channel, int64_t utime, const std::string& payload) {
  log_.WriteRaw(channel, utime, payload);
}

void LcmLogSink::Close() { log_.Close(); }

namespace internal {

ChannelStats& Emitter::Write(const std::string& channel, int64_t utime, const std::string& payload) {
  sink_.Write(channel, utime, payload);
  auto& stats = report_.channels[channel];
  if (stats.count == 0) stats.first_utime = utime;
  ++stats.count;
  stats.last_utime = utime;
  if (any_ && utime < last_utime_) ++report_.out_of_order;
  any_ = true;
  last_utime_ = utime;
  return stats;
}

void Emitter::Emit(const std::string& channel, const laser_scan_t& msg) {
  ChannelStats& stats = Write(channel, msg.utime, glue::Encode(msg));
  const bool first = stats.count == 1;
  stats.min_beams = first ? msg.nranges : std::min(stats.min_beams, msg.nranges);
  stats.max_beams = first ? msg.nranges : std::max(stats.max_beams, msg.nranges);
  stats.max_range_m = first ? msg.range_max_m : std::max(stats.max_range_m, msg.range_max_m);
  for (const float r : msg.ranges_m) {
    ++stats.readings;
    if (r >= msg.range_max_m) {
      ++stats.no_returns;
      continue;
    }
    const bool first_return = stats.readings - stats.no_returns == 1;
    stats.min_return_m = first_return ? r : std::min(stats.min_return_m, r);
    stats.max_return_m = first_return ? r : std::max(stats.max_return_m, r);
  }
}

void Emitter::Emit(const std::string& channel, const odometry_t& msg) {
  AddToPath(channel, Write(channel, msg.utime, glue::Encode(msg)), msg.x_m, msg.y_m);
}

void Emitter::Emit(const std::string& channel, const pose_t& msg) {
  AddToPath(channel, Write(channel, msg.utime, glue::Encode(msg)), msg.x_m, msg.y_m);
}

void Emitter::AddToPath(const std::string& channel, ChannelStats& stats, double x_m, double y_m) {
  const auto it = last_position_.find(channel);
  if (it != last_position_.end()) {
    stats.path_length_m += std::hypot(x_m - it->second.first, y_m - it->second.second);
  }
  last_position_[channel] = {x_m, y_m};
}

LineReader::Status LineReader::Next() {
  line_.clear();
  had_newline_ = false;
  std::streambuf* buf = in_.rdbuf();
  if (buf == nullptr) return Status::kEnd;
  bool too_long = false;
  bool any = false;
  for (;;) {
    const int c = buf->sbumpc();
    if (c == std::char_traits<char>::eof()) {
      in_.setstate(std::ios::eofbit);
      break;
    }
    any = true;
    ++bytes_read_;
    if (c == '\n') {
      had_newline_ = true;
      break;
    }
    if (line_.size() >= max_line_bytes_) {
      too_long = true;  // keep consuming up to the newline, store nothing more
      continue;
    }
    line_.push_back(static_cast<char>(c));
  }
  if (!any) return Status::kEnd;
  ++line_number_;
  if (!line_.empty() && line_.back() == '\r') line_.pop_back();
  if (too_long) {
    line_.clear();
    return Status::kTooLong;
  }
  return Status::kLine;
}

void Tokenize(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i >= line.size()) break;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    tokens->push_back(line.substr(i, j - i));
    i = j;
  }
}

std::optional<double> ParseDouble(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<int64_t> ParseInt64(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return std::nullopt;
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string Quote(std::string_view text) {
  constexpr size_t kMax = 40;
  std::string out = "'";
  for (size_t i = 0; i < text.size() && i < kMax; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    out.push_back(c < 0x20 || c >= 0x7f ? '?' : static_cast<char>(c));
  }
  if (text.size() > kMax) out += "...";
  return out + "'";
}

std::string FormatUtime(int64_t utime) {
  const bool negative = utime < 0;
  const uint64_t magnitude = negative ? -static_cast<uint64_t>(utime) : static_cast<uint64_t>(utime);
  char buf[40];
  std::snprintf(buf, sizeof buf, "%s%llu.%06llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000),
                static_cast<unsigned long long>(magnitude % 1000000));
  return buf;
}

std::optional<int64_t> SecondsToUtime(double seconds) {
  const double us = std::round(seconds * 1e6);
  if (!std::isfinite(us) || std::fabs(us) > 9.0e18) return std::nullopt;
  return static_cast<int64_t>(us);
}

// ---------------------------------------------------------------- ZlibInputFile
class ZlibInputFile::Buffer : public std::streambuf {
 public:
  explicit Buffer(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
      error_ = std::string("cannot open: ") + std::strerror(errno);
      return;
    }
    if (S_ISDIR(st.st_mode)) {
      error_ = "is a directory";
      return;
    }
    file_bytes_ = static_cast<int64_t>(st.st_size);
    file_ = gzopen(path.c_str(), "rb");
    if (file_ == nullptr) {
      error_ = std::string("cannot open: ") + std::strerror(errno);
      return;
    }
    gzbuffer(file_, 1 << 17);
    compressed_ = gzdirect(file_) == 0;
    content_hint_ = file_bytes_;
    if (compressed_) {
      content_hint_ = 0;
      std::ifstream raw(path, std::ios::binary);
      unsigned char trailer[4];
      if (file_bytes_ >= 18 && raw.seekg(-4, std::ios::end) && raw.read(reinterpret_cast<char*>(trailer), 4)) {
        content_hint_ = static_cast<int64_t>(trailer[0]) | (static_cast<int64_t>(trailer[1]) << 8) |
                        (static_cast<int64_t>(trailer[2]) << 16) | (static_cast<int64_t>(trailer[3]) << 24);
      }
    }
  }
  ~Buffer() override {
    if (file_ != nullptr) gzclose(file_);
  }

  bool is_open() const { return file_ != nullptr; }
  bool compressed() const { return compressed_; }
  int64_t file_bytes() const { return file_bytes_; }
  int64_t content_hint() const { return content_hint_; }
  int64_t compressed_offset() const { return file_ == nullptr ? 0 : static_cast<int64_t>(gzoffset(file_)); }
  const std::string& error() const { return error_; }

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    if (file_ == nullptr || done_) return traits_type::eof();
    const int n = gzread(file_, data_, sizeof data_);
    if (n <= 0 || n < static_cast<int>(sizeof data_)) {
      int errnum = Z_OK;
      const char* message = gzerror(file_, &errnum);
      if (errnum != Z_OK && error_.empty()) {
        error_ = (errnum == Z_BUF_ERROR ? std::string("gzip data truncated (") : std::string("gzip data corrupt (")) +
                 (message ? message : "?") + ")";
        done_ = true;
      }
      if (n <= 0) {
        done_ = true;
        return traits_type::eof();
      }
    }
    setg(data_, data_, data_ + n);
    return traits_type::to_int_type(*gptr());
  }

 private:
  gzFile file_ = nullptr;
  bool compressed_ = false;
  bool done_ = false;
  int64_t file_bytes_ = 0;
  int64_t content_hint_ = 0;
  std::string error_;
  char data_[1 << 16];
};

ZlibInputFile::ZlibInputFile(const std::string& path) : std::istream(nullptr), buffer_(std::make_unique<Buffer>(path)) {
  rdbuf(buffer_.get());
  if (!buffer_->is_open()) setstate(std::ios::failbit);
}

ZlibInputFile::~ZlibInputFile() = default;

bool ZlibInputFile::is_open() const { return buffer_->is_open(); }
bool ZlibInputFile::compressed() const { return buffer_->compressed(); }
int64_t ZlibInputFile::file_bytes() const { return buffer_->file_bytes(); }
int64_t ZlibInputFile::compressed_offset() const { return buffer_->compressed_offset(); }
int64_t ZlibInputFile::content_bytes_hint() const { return buffer_->content_hint(); }
const std::string& ZlibInputFile::error() const { return buffer_->error(); }

}  // namespace internal
}  // namespace snapnav::importers
