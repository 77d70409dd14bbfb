#include "snapnav/glue/log_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cctype>
#include <cstring>
#include <ostream>

namespace snapnav::glue {
namespace {

constexpr uint32_t kSyncWord = 0xEDA1DA01u;
constexpr uint64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;
constexpr size_t kScanChunk = 1 << 16;

uint64_t BigEndian(const unsigned char* b, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | b[i];
  return v;
}

}  // namespace

std::string DescribeLogDamage(const std::string& path, const LogDamage& d, uint64_t file_size) {
  std::string s = path + ": byte " + std::to_string(d.offset) + ": " + d.what;
  if (d.kind == LogDamage::Kind::kTruncated) {
    s += " (the file is truncated: the last " + std::to_string(d.skipped_bytes()) + " bytes are an incomplete event)";
  } else if (d.resumed_at >= file_size) {
    s += "; no intact event follows: the last " + std::to_string(d.skipped_bytes()) + " bytes are lost";
  } else {
    s += "; skipped " + std::to_string(d.skipped_bytes()) + " bytes, resumed at byte " + std::to_string(d.resumed_at);
  }
  return s;
}

LogReader::LogReader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw LogError("cannot open LCM log '" + path + "': " + std::strerror(errno));
  if (fseeko(file_, 0, SEEK_END) != 0) {
    std::fclose(file_);
    throw LogError("cannot read LCM log '" + path + "': not a regular file");
  }
  size_ = static_cast<uint64_t>(ftello(file_));
  try {
    CheckIsLog();
  } catch (...) {
    std::fclose(file_);
    file_ = nullptr;
    throw;
  }
}

void LogReader::CheckIsLog() {
  if (size_ == 0) return;  // an empty log
  Header h;
  const std::string problem = CheckHeader(0, &h);
  if (problem.empty()) return;
  const uint64_t next = FindNextEvent(1, size_);
  if (next < size_) {  // a damaged start, intact events after it
    AddDamage(LogDamage::Kind::kCorrupt, 0, next, problem);
    pos_ = next;
    return;
  }
  // No intact event anywhere: an LCM log cut off in its first event starts with (a prefix of) the
  // sync word; anything else is some other file.
  unsigned char head[64];
  const size_t n = static_cast<size_t>(std::min<uint64_t>(sizeof head, size_));
  ReadAt(0, head, n);
  const unsigned char sync[4] = {0xED, 0xA1, 0xDA, 0x01};
  if (std::memcmp(head, sync, std::min<size_t>(n, 4)) == 0) return;
  std::string first_bytes;
  for (size_t i = 0; i < std::min<size_t>(n, 4); ++i) {
    static const char hex[] = "0123456789abcdef";
    first_bytes += std::string(i ? " " : "") + hex[head[i] >> 4] + hex[head[i] & 15];
  }
  std::string what = path_ + " is not an LCM log: byte 0: " + problem + " (it starts with " + first_bytes +
                     "; an LCM log starts with ed a1 da 01), and none of its " + std::to_string(size_) +
                     " bytes starts an intact event";
  size_t text = 0;
  while (text < n && (std::isprint(head[text]) || head[text] == '\t' || head[text] == '\n' || head[text] == '\r'))
    ++text;
  if (n >= 2 && head[0] == 0x1f && head[1] == 0x8b) {
    what += " (it is gzip-compressed: gunzip it first)";
  } else if (text == n) {
    std::string line(reinterpret_cast<const char*>(head), n);
    line = line.substr(0, line.find_first_of("\r\n"));
    what += " (it is text: '" + line.substr(0, 40) + (line.size() > 40 ? "...'" : "'") + ")";
  }
  throw LogError(what);
}

LogReader::~LogReader() {
  if (file_) std::fclose(file_);
}

uint64_t LogReader::damaged_bytes() const {
  uint64_t n = 0;
  for (const auto& d : damage_) n += d.skipped_bytes();
  return n;
}

void LogReader::ReportDamage(std::ostream& out, const std::string& program) const {
  for (const auto& d : damage_) out << program << ": " << DescribeLogDamage(path_, d, size_) << "\n";
}

void LogReader::ReadAt(uint64_t at, void* buffer, size_t size) {
  if (size == 0) return;
  if (fseeko(file_, static_cast<off_t>(at), SEEK_SET) != 0 || std::fread(buffer, 1, size, file_) != size) {
    throw LogError("cannot read LCM log '" + path_ + "' at byte " + std::to_string(at) + ": " +
                   (std::ferror(file_) ? std::strerror(errno) : "unexpected end of file (did it shrink?)"));
  }
}

void LogReader::AddDamage(LogDamage::Kind kind, uint64_t offset, uint64_t resumed_at, const std::string& what) {
  LogDamage d;
  d.kind = kind;
  d.offset = offset;
  d.resumed_at = resumed_at;
  d.what = what;
  damage_.push_back(std::move(d));
}

bool LogReader::SyncWordAt(uint64_t at) {
  if (size_ - at < 4) return false;
  unsigned char b[4];
  ReadAt(at, b, 4);
  return BigEndian(b, 4) == kSyncWord;
}

std::string LogReader::CheckHeader(uint64_t at, Header* h) {
  if (size_ - at < kHeaderBytes) {
    return "incomplete event header (" + std::to_string(size_ - at) + " of " + std::to_string(kHeaderBytes) + " bytes)";
  }
  unsigned char b[kHeaderBytes];
  ReadAt(at, b, kHeaderBytes);
  if (BigEndian(b, 4) != kSyncWord) return "no event sync word";
  h->eventnum = static_cast<int64_t>(BigEndian(b + 4, 8));
  h->timestamp_us = static_cast<int64_t>(BigEndian(b + 12, 8));
  h->channel_length = static_cast<int32_t>(static_cast<uint32_t>(BigEndian(b + 20, 4)));
  h->data_length = static_cast<int32_t>(static_cast<uint32_t>(BigEndian(b + 24, 4)));
  if (h->channel_length < 1 || h->channel_length > kMaxLogChannelLength) {
    return "channel length " + std::to_string(h->channel_length) + " out of range (1.." +
           std::to_string(kMaxLogChannelLength) + ")";
  }
  if (h->data_length < 0) return "negative data length " + std::to_string(h->data_length);
  const uint64_t left = size_ - at - kHeaderBytes;
  if (static_cast<uint64_t>(h->channel_length) > left) {
    return "event needs a " + std::to_string(h->channel_length) + "-byte channel, " + std::to_string(left) +
           " bytes are left";
  }
  h->channel.resize(static_cast<size_t>(h->channel_length));
  ReadAt(at + kHeaderBytes, h->channel.data(), h->channel.size());
  for (const char c : h->channel) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) return "channel name has control characters";
  }
  const uint64_t data_left = left - static_cast<uint64_t>(h->channel_length);
  if (static_cast<uint64_t>(h->data_length) > data_left) {
    return "event on " + h->channel + " needs " + std::to_string(h->data_length) + " data bytes, " +
           std::to_string(data_left) + " are left";
  }
  h->end = at + kHeaderBytes + static_cast<uint64_t>(h->channel_length) + static_cast<uint64_t>(h->data_length);
  return "";
}

uint64_t LogReader::FindEventInData(const std::string& data, uint64_t data_start) {
  // Candidates start inside the data; the sync word of one near its end reaches past it.
  const char* const begin = data.data();
  const char* const stop = begin + data.size();
  for (const char* p = begin; p < stop; ++p) {
    p = static_cast<const char*>(std::memchr(p, 0xED, static_cast<size_t>(stop - p)));
    if (!p) break;
    if (p + 4 <= stop && BigEndian(reinterpret_cast<const unsigned char*>(p), 4) != kSyncWord) continue;
    Header h;
    const uint64_t at = data_start + static_cast<uint64_t>(p - begin);
    if (CheckHeader(at, &h).empty()) return at;
  }
  return size_;
}

uint64_t LogReader::FindNextEvent(uint64_t from, uint64_t limit) {
  // Candidates start before `limit`; their sync word may end after it.
  if (limit > size_) limit = size_;
  std::vector<unsigned char> buffer;
  for (uint64_t at = from; at < limit && size_ - at >= 4;) {
    const uint64_t starts = std::min<uint64_t>(kScanChunk, limit - at);
    const size_t n = static_cast<size_t>(std::min<uint64_t>(starts + 3, size_ - at));
    buffer.resize(n);
    ReadAt(at, buffer.data(), n);
    for (size_t i = 0; i < starts && i + 4 <= n; ++i) {
      if (BigEndian(&buffer[i], 4) != kSyncWord) continue;
      Header h;
      if (CheckHeader(at + i, &h).empty()) return at + i;
    }
    at += starts;
  }
  return size_;
}

bool LogReader::Next(LogEvent* event) {
  while (pos_ < size_) {
    Header h;
    const std::string problem = CheckHeader(pos_, &h);
    if (!problem.empty()) {
      const uint64_t next = FindNextEvent(pos_ + 1, size_);
      // A plausible start whose length runs past the end of the file, with nothing after it: a
      // log cut off while being written.
      const bool cut = next >= size_ && (SyncWordAt(pos_) || size_ - pos_ < 4);
      AddDamage(cut ? LogDamage::Kind::kTruncated : LogDamage::Kind::kCorrupt, pos_, next, problem);
      pos_ = next;
      continue;
    }
    // The data is read before it is trusted: an intact event starting inside it means this
    // event's data length is wrong (it would swallow that event), even when its claimed end
    // happens to fall on another sync word.
    const uint64_t data_start = h.end - static_cast<uint64_t>(h.data_length);
    event->data.resize(static_cast<size_t>(h.data_length));
    ReadAt(data_start, event->data.data(), event->data.size());
    if (const uint64_t inside = FindEventInData(event->data, data_start); inside < h.end) {
      AddDamage(LogDamage::Kind::kCorrupt, pos_, inside,
                "event on " + h.channel + " claims " + std::to_string(h.data_length) +
                    " data bytes, but an intact event starts at byte " + std::to_string(inside));
      pos_ = inside;
      continue;
    }
    event->eventnum = h.eventnum;
    event->timestamp_us = h.timestamp_us;
    event->channel = std::move(h.channel);
    event->offset = pos_;
    pos_ = h.end;
    ++events_;
    return true;
  }
  return false;
}

}  // namespace snapnav::glue
