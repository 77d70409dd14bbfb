#include "bus_check.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include <unistd.h>

#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::tools {

omni_frame_t MakeProbeFrame(int64_t seq, int size_bytes) {
  if (size_bytes < 1) throw std::invalid_argument("probe size must be at least 1 byte");
  omni_frame_t f;
  f.utime = kProbeBaseUtime + seq * kProbePeriodUtime;
  f.sensor_name = "bus-check";
  f.kind = omni_frame_t::RAW_OMNI;
  f.width = size_bytes;
  f.height = 1;
  f.row_stride = size_bytes;
  f.encoding = omni_frame_t::GRAY8;
  f.mirror_center_x_px = f.mirror_center_y_px = 0;
  f.mirror_inner_radius_px = f.mirror_outer_radius_px = 0;
  f.mirror_elevation_inner_rad = f.mirror_elevation_outer_rad = 0;
  f.bearing_col0_rad = f.elevation_top_rad = f.elevation_bottom_rad = 0;
  f.data_size = size_bytes;
  f.data.resize(size_bytes);
  uint32_t state = static_cast<uint32_t>(seq) * 2654435761u + 1u;  // xorshift, seeded by seq
  for (int i = 0; i < size_bytes; ++i) {
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    f.data[i] = static_cast<uint8_t>(state);
  }
  return f;
}

int64_t ProbeSeq(int64_t utime) {
  const int64_t d = utime - kProbeBaseUtime;
  if (d < 0 || d % kProbePeriodUtime != 0) return -1;
  return d / kProbePeriodUtime;
}

int64_t PayloadUtime(const void* data, size_t size) {
  if (size < 16) return -1;
  const auto* b = static_cast<const uint8_t*>(data) + 8;  // after the fingerprint
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  return static_cast<int64_t>(v);
}

ProbeVerifier::ProbeVerifier(glue::Bus& bus, const std::string& channel, std::vector<int> sizes_bytes,
                             int expected_count)
    : bus_(bus), sizes_bytes_(std::move(sizes_bytes)), expected_count_(expected_count), seen_(expected_count, false) {
  if (sizes_bytes_.empty()) throw std::invalid_argument("verifier needs at least one probe size");
  if (expected_count < 1) throw std::invalid_argument("verifier needs a positive expected count");
  bus_.SubscribeRaw(channel, [this](const void* data, size_t size) { OnProbe(data, size); });
}

void ProbeVerifier::OnProbe(const void* data, size_t size) {
  std::string error;
  const auto frame = glue::Decode<omni_frame_t>(data, size, &error);
  if (!frame) {
    bus_.CountDecodeError(error);
    return;
  }
  const int64_t seq = ProbeSeq(frame->utime);
  if (seq < 0 || seq >= expected_count_) {
    ++corrupt_;
    throw std::runtime_error("probe utime " + std::to_string(frame->utime) + " is not one of the expected probes");
  }
  const std::string expected =
      glue::Encode(MakeProbeFrame(seq, sizes_bytes_[static_cast<size_t>(seq) % sizes_bytes_.size()]));
  if (expected.size() != size || std::memcmp(expected.data(), data, size) != 0) {
    ++corrupt_;
    throw std::runtime_error("probe " + std::to_string(seq) + " differs from what was sent");
  }
  if (seen_[seq]) {
    ++duplicates_;
    return;
  }
  if (seq <= last_seq_) ++out_of_order_;
  last_seq_ = std::max(last_seq_, seq);
  seen_[seq] = true;
  ++received_;
  bytes_ += static_cast<int64_t>(size);
}

bool ProbeVerifier::ok() const {
  return complete() && corrupt_ == 0 && out_of_order_ == 0 && duplicates_ == 0 && bus_.total_errors() == 0;
}

std::string ProbeVerifier::Report() const {
  std::ostringstream out;
  out << received_ << "/" << expected_count_ << " probes byte-identical (" << bytes_ << " bytes), " << corrupt_
      << " corrupt, " << out_of_order_ << " out of order, " << duplicates_ << " duplicates";
  if (!complete()) {
    out << "; missing:";
    int shown = 0;
    for (int k = 0; k < expected_count_ && shown < 10; ++k) {
      if (!seen_[k]) {
        out << " " << k;
        ++shown;
      }
    }
    if (expected_count_ - received_ > shown) out << " ...";
  }
  return out.str();
}

EchoNode::EchoNode(glue::Bus& bus, const std::string& in_channel, std::string out_channel)
    : bus_(bus), out_channel_(std::move(out_channel)) {
  bus_.SubscribeRaw(in_channel, [this](const void* data, size_t size) {
    bus_.PublishRaw(out_channel_, data, size);
    ++echoed_;
  });
}

namespace {

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  return v[i];
}

}  // namespace

std::vector<PingResult> RunPing(glue::Bus& bus, const std::string& ping_channel, const std::string& pong_channel,
                                const std::vector<int>& sizes_bytes, double rate_hz, double duration_s,
                                bool progress) {
  if (rate_hz <= 0 || duration_s <= 0) throw std::invalid_argument("ping needs a positive rate and duration");
  std::map<int64_t, int64_t> sent_at;  // probe utime -> steady send time [us]
  std::vector<double> rtts_ms;
  bus.SubscribeRaw(pong_channel, [&](const void* data, size_t size) {
    const int64_t now = glue::MonotonicUtime();
    const auto it = sent_at.find(PayloadUtime(data, size));
    if (it == sent_at.end()) return;  // a pong of an earlier size or another pinger
    rtts_ms.push_back((now - it->second) / 1000.0);
    sent_at.erase(it);
  });

  std::vector<PingResult> results;
  int64_t seq = 0;
  for (const int size : sizes_bytes) {
    PingResult r;
    r.size_bytes = size;
    rtts_ms.clear();
    sent_at.clear();
    std::string payload = glue::Encode(MakeProbeFrame(0, size));
    const int count = static_cast<int>(rate_hz * duration_s + 0.5);
    const int64_t period_us = static_cast<int64_t>(1e6 / rate_hz);
    const int64_t start = glue::MonotonicUtime();
    for (int i = 0; i < count && !glue::ShutdownRequested(); ++i) {
      const int64_t due = start + i * period_us;
      for (int64_t now = glue::MonotonicUtime(); now < due; now = glue::MonotonicUtime()) {
        bus.HandleOnce(static_cast<int>(std::max<int64_t>(1, (due - now) / 1000)));
      }
      const int64_t utime = kProbeBaseUtime + (seq++) * kProbePeriodUtime;
      for (int b = 0; b < 8; ++b) payload[8 + b] = static_cast<char>((utime >> (56 - 8 * b)) & 0xff);
      sent_at[utime] = glue::MonotonicUtime();
      bus.PublishRaw(ping_channel, payload.data(), payload.size());
      ++r.sent;
      if (progress && isatty(2) && (i + 1) % std::max(1, static_cast<int>(rate_hz)) == 0) {
        std::cerr << "  " << size << " B: " << (i + 1) << "/" << count << " sent\r" << std::flush;
      }
    }
    // Collect the last echoes.
    const int64_t drain_until = glue::MonotonicUtime() + 1'000'000;
    while (!sent_at.empty() && glue::MonotonicUtime() < drain_until) bus.HandleOnce(10);
    r.received = static_cast<int>(rtts_ms.size());
    r.median_ms = Percentile(rtts_ms, 0.5);
    r.p99_ms = Percentile(rtts_ms, 0.99);
    r.max_ms = rtts_ms.empty() ? 0 : *std::max_element(rtts_ms.begin(), rtts_ms.end());
    results.push_back(r);
    if (progress) {
      std::cerr << "  " << size << " B: " << r.sent << " sent, " << r.received << " echoed" << std::string(10, ' ')
                << "\n";
    }
  }
  return results;
}


omni_frame_t MakeSoakFrame(int64_t seq, int size_bytes) {
  if (size_bytes < 8) throw std::invalid_argument("soak frames need at least 8 bytes");
  static std::vector<uint8_t> base;  // the pseudo-random image, made once per size
  if (static_cast<int>(base.size()) != size_bytes) base = MakeProbeFrame(0, size_bytes).data;
  omni_frame_t f = MakeProbeFrame(0, 1);
  f.utime = kProbeBaseUtime + seq * kProbePeriodUtime;
  f.sensor_name = "bus-check-soak";
  f.width = f.row_stride = f.data_size = size_bytes;
  f.data = base;
  for (int b = 0; b < 8; ++b) f.data[b] = static_cast<uint8_t>((static_cast<uint64_t>(seq) >> (56 - 8 * b)) & 0xff);
  return f;
}

laser_scan_t MakeSoakScan(int64_t seq, int beams) {
  if (beams < 1) throw std::invalid_argument("soak scans need at least one beam");
  laser_scan_t s;
  s.utime = kProbeBaseUtime + seq * kProbePeriodUtime;
  s.sensor_name = "bus-check-soak";
  s.sensor_x_m = 0.1f;
  s.sensor_y_m = 0;
  s.sensor_theta_rad = 0;
  s.angle_min_rad = -2.0944f;
  s.angle_increment_rad = 4.1888f / std::max(1, beams - 1);
  s.time_increment_s = 0;
  s.range_min_m = 0.02f;
  s.range_max_m = 5.6f;
  s.nranges = beams;
  s.ranges_m.resize(beams);
  for (int i = 0; i < beams; ++i) s.ranges_m[i] = 0.1f + static_cast<float>((seq * 7 + i) % 500) * 0.01f;
  s.nintensities = 0;
  return s;
}

SoakVerifier::SoakVerifier(const std::string& frame_channel, const std::string& scan_channel, int frame_bytes,
                           int beams, int64_t expected_frames, int64_t expected_scans)
    : frame_channel_(frame_channel), scan_channel_(scan_channel), frame_bytes_(frame_bytes), beams_(beams) {
  if (expected_frames < 0 || expected_scans < 0) throw std::invalid_argument("soak: negative expected counts");
  frames_.expected = expected_frames;
  scans_.expected = expected_scans;
  frames_seen_.seen.assign(expected_frames, false);
  scans_seen_.seen.assign(expected_scans, false);
}

SoakVerifier::SoakVerifier(glue::Bus& bus, const std::string& frame_channel, const std::string& scan_channel,
                           int frame_bytes, int beams, int64_t expected_frames, int64_t expected_scans)
    : SoakVerifier(frame_channel, scan_channel, frame_bytes, beams, expected_frames, expected_scans) {
  bus_ = &bus;
  bus.SubscribeRaw(frame_channel, [this](const void* data, size_t size) { OnFrame(data, size); });
  bus.SubscribeRaw(scan_channel, [this](const void* data, size_t size) { OnScan(data, size); });
}

void SoakVerifier::Feed(const std::string& channel, const void* data, size_t size) {
  try {
    if (channel == frame_channel_) {
      OnFrame(data, size);
    } else if (channel == scan_channel_) {
      OnScan(data, size);
    } else {
      ++ignored_;
    }
  } catch (const std::exception& e) {
    if (++feed_errors_ <= 5) std::cerr << "soak: " << channel << ": " << e.what() << "\n";
  }
}

void SoakVerifier::OnFrame(const void* data, size_t size) {
  const int64_t seq = ProbeSeq(PayloadUtime(data, size));
  const std::string expected =
      seq >= 0 && seq < frames_.expected ? glue::Encode(MakeSoakFrame(seq, frame_bytes_)) : std::string();
  Check(data, size, expected, seq, &frames_, &frames_seen_);
}

void SoakVerifier::OnScan(const void* data, size_t size) {
  const int64_t seq = ProbeSeq(PayloadUtime(data, size));
  const std::string expected = seq >= 0 && seq < scans_.expected ? glue::Encode(MakeSoakScan(seq, beams_)) : std::string();
  Check(data, size, expected, seq, &scans_, &scans_seen_);
}

int64_t SoakVerifier::errors() const {
  return bus_ ? static_cast<int64_t>(bus_->total_errors()) : feed_errors_;
}

void SoakVerifier::Check(const void* data, size_t size, const std::string& expected, int64_t seq, SoakStream* stream,
                         Seen* seen) {
  if (expected.empty() || expected.size() != size || std::memcmp(expected.data(), data, size) != 0) {
    ++stream->corrupt;
    throw std::runtime_error("soak message " + std::to_string(seq) + " (" + std::to_string(size) +
                             " bytes) is not one that was sent");
  }
  if (seen->seen[seq]) {
    ++stream->duplicates;
    return;
  }
  if (seq <= seen->last_seq) ++stream->out_of_order;
  seen->last_seq = std::max(seen->last_seq, seq);
  seen->seen[seq] = true;
  ++stream->received;
  stream->bytes += static_cast<int64_t>(size);
}

bool SoakVerifier::ok() const {
  for (const SoakStream* s : {&frames_, &scans_}) {
    if (s->corrupt || s->out_of_order || s->duplicates) return false;
  }
  return complete() && errors() == 0;
}

std::string SoakVerifier::Report() const {
  std::ostringstream out;
  auto stream = [&](const char* name, const SoakStream& s) {
    out << name << " " << s.received << "/" << s.expected << " (" << s.missing() << " missing, " << s.corrupt
        << " corrupt, " << s.out_of_order << " out of order, " << s.duplicates << " duplicates)";
  };
  stream("frames", frames_);
  out << ", ";
  stream("scans", scans_);
  return out.str();
}

results::Json SoakVerifier::Counts(const std::string& prefix) const {
  results::Json out;
  auto member = [&](const std::string& key, int64_t v) { out[prefix + key] = v; };
  for (const auto& [name, s] : {std::pair<const char*, const SoakStream&>{"frames", frames_}, {"scans", scans_}}) {
    const std::string n = name;
    member(n + "_expected", s.expected);
    member(n + "_received", s.received);
    member(n + "_missing", s.missing());
    member(n + "_corrupt", s.corrupt);
    member(n + "_out_of_order", s.out_of_order);
    member(n + "_duplicates", s.duplicates);
    member(n + "_bytes", s.bytes);
  }
  member("decode_or_handler_errors", errors());
  return out;
}

LogStreamReader::LogStreamReader(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "rb")) {
  if (!file_) throw std::runtime_error("cannot open LCM log '" + path + "': " + std::strerror(errno));
}

LogStreamReader::~LogStreamReader() {
  if (file_) std::fclose(file_);
}

bool LogStreamReader::Read(void* dst, size_t n) {
  const size_t got = std::fread(dst, 1, n, file_);
  offset_ += static_cast<int64_t>(got);
  return got == n;
}

bool LogStreamReader::Next(std::string* channel, std::string* data, int64_t* timestamp_us) {
  uint8_t header[28];
  const int64_t start = offset_;
  const size_t got = std::fread(header, 1, sizeof(header), file_);
  offset_ += static_cast<int64_t>(got);
  if (got == 0) return false;
  auto fail = [&](const std::string& why) {
    throw std::runtime_error(path_ + ": event at byte " + std::to_string(start) + ": " + why);
  };
  if (got < sizeof(header)) fail("truncated header");
  auto be = [&](int at, int bytes) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | header[at + i];
    return v;
  };
  if (be(0, 4) != 0xEDA1DA01u) fail("no LCM event magic");
  *timestamp_us = static_cast<int64_t>(be(12, 8));
  const uint64_t channel_len = be(20, 4), data_len = be(24, 4);
  if (channel_len == 0 || channel_len > 256 || data_len > (1u << 30)) fail("absurd channel or data length");
  channel->resize(channel_len);
  data->resize(data_len);
  if (!Read(channel->data(), channel_len) || !Read(data->data(), data_len)) fail("truncated event");
  return true;
}

int64_t ProcessRssKb(int pid) {
  std::ifstream in(pid == 0 ? std::string("/proc/self/status") : "/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::strtoll(line.c_str() + 6, nullptr, 10);
  }
  return -1;
}

}  // namespace snapnav::tools
