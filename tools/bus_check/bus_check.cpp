#include "bus_check.hpp"

#include <algorithm>
#include <cstring>
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

}  // namespace snapnav::tools
