#include "latency_probe.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "bus_check.hpp"  // PayloadUtime
#include "snapnav/glue/flags.hpp"

namespace snapnav::tools {

std::vector<LatencyOutput> ParseLatencyOutputs(const std::string& text) {
  std::vector<LatencyOutput> outputs;
  for (const auto& part : glue::SplitList(text)) {
    LatencyOutput o;
    const auto at = part.find('@');
    o.channel = part.substr(0, at);
    if (at != std::string::npos) o.after = part.substr(at + 1);
    if (o.channel.empty() || (at != std::string::npos && o.after.empty())) {
      throw std::invalid_argument("output '" + part + "': expected CHANNEL or CHANNEL@AFTER_CHANNEL");
    }
    if (!o.after.empty() && std::none_of(outputs.begin(), outputs.end(),
                                         [&](const LatencyOutput& p) { return p.channel == o.after; })) {
      throw std::invalid_argument("output '" + part + "': " + o.after + " must be listed before it");
    }
    outputs.push_back(o);
  }
  if (outputs.empty()) throw std::invalid_argument("no output channels");
  return outputs;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  if (q < 0 || q > 1) throw std::invalid_argument("Quantile: q must be in [0, 1]");
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  return v[i];
}

LatencyProbe::LatencyProbe(glue::Bus& bus, const std::string& input, const std::vector<LatencyOutput>& outputs,
                           double window_s)
    : bus_(bus), outputs_(outputs), window_us_(static_cast<int64_t>(window_s * 1e6)) {
  if (!(window_s > 0)) throw std::invalid_argument("latency probe: window_s must be positive");
  bus_.SubscribeRaw(input, [this](const void* d, size_t n) { OnFrame(d, n); });
  for (const auto& o : outputs_) {
    counts_[o.channel];
    samples_[o.channel];
    bus_.SubscribeRaw(o.channel, [this, o](const void* d, size_t n) { OnOutput(o, d, n); });
  }
}

void LatencyProbe::OnFrame(const void* data, size_t size) {
  const int64_t utime = PayloadUtime(data, size);
  if (utime < 0) throw std::runtime_error("frame too short for a utime (" + std::to_string(size) + " bytes)");
  ++frames_;
  frames_by_utime_[utime].recv_utime = bus_.current().recv_utime;
  if (frame_log_) *frame_log_ << utime << "," << bus_.current().recv_utime << "\n";
  newest_utime_ = std::max(newest_utime_, utime);
  while (!frames_by_utime_.empty() && frames_by_utime_.begin()->first < newest_utime_ - window_us_) {
    frames_by_utime_.erase(frames_by_utime_.begin());
  }
}

void LatencyProbe::OnOutput(const LatencyOutput& out, const void* data, size_t size) {
  const int64_t recv = bus_.current().recv_utime;
  LatencyStats& c = counts_[out.channel];
  ++c.outputs;
  const auto it = frames_by_utime_.find(PayloadUtime(data, size));
  if (it == frames_by_utime_.end() || (!out.after.empty() && !it->second.results.count(out.after))) {
    ++c.unmatched;
    return;
  }
  if (!it->second.results.emplace(out.channel, recv).second) {
    ++c.repeats;
    return;
  }
  ++c.matched;
  samples_[out.channel].push_back((recv - it->second.recv_utime) / 1000.0);
}

LatencyStats LatencyProbe::Stats(const std::string& channel) const {
  const auto it = counts_.find(channel);
  if (it == counts_.end()) return {};
  LatencyStats s = it->second;
  const auto& v = samples_.at(channel);
  if (!v.empty()) {
    s.median_ms = Quantile(v, 0.5);
    s.p95_ms = Quantile(v, 0.95);
    s.max_ms = *std::max_element(v.begin(), v.end());
    s.min_ms = *std::min_element(v.begin(), v.end());
    s.mean_ms = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  }
  return s;
}

const std::vector<double>& LatencyProbe::samples_ms(const std::string& channel) const {
  static const std::vector<double> kNone;
  const auto it = samples_.find(channel);
  return it == samples_.end() ? kNone : it->second;
}

int64_t LatencyProbe::frames_without(const std::string& channel) const {
  const auto it = counts_.find(channel);
  return frames_ - (it == counts_.end() ? 0 : it->second.matched);
}

}  // namespace snapnav::tools
