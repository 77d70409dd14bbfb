// bus-check: end-to-end checks and the round-trip benchmark of the LCM bus.
//   bus-check publish  send --count probe frames of known content at --rate-hz
//   bus-check verify   receive them; exit 0 only if every one arrived byte-identical and in order
//   bus-check echo     republish BUS_PING on BUS_PONG
//   bus-check ping     time round trips through an echo process, per message size
//   bus-check soak-publish  1 MB frames at 30 Hz and scans at 10 Hz for --duration-s (the soak test)
//   bus-check soak-verify   receive both soak streams; exit 0 only if every message arrived intact

#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <thread>

#include "bus_check.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::tools {
namespace {

std::vector<int> ParseSizes(const std::string& text) {
  std::vector<int> sizes;
  for (const auto& part : glue::SplitList(text)) {
    char* end = nullptr;
    const long v = std::strtol(part.c_str(), &end, 10);
    if (part.empty() || *end != '\0' || v < 1 || v > 64 * 1024 * 1024) {
      throw glue::FlagError("--sizes expects a list of byte counts in 1..67108864, got '" + part + "'");
    }
    sizes.push_back(static_cast<int>(v));
  }
  if (sizes.empty()) throw glue::FlagError("--sizes is empty");
  return sizes;
}


struct SoakSettings {
  std::string frame_channel, scan_channel;
  int frame_bytes, beams;
  double frame_rate_hz, scan_rate_hz;
  int64_t frames, scans;  // how many the publisher sends
  double progress_s, timeout_s;
  std::string out_json;
  std::string log_path;  // soak-verify: read this log (a file or a FIFO) instead of the bus
};

void WriteJson(const std::string& path, const results::Json& j) {
  if (!path.empty()) results::WriteJsonFile(path, j);
}

// Sends the frames and scans of `s` in time order, paced by the steady clock.
int RunSoakPublisher(glue::Bus& bus, const SoakSettings& s, const std::string& prefix) {
  const int64_t rss_start = ProcessRssKb();
  const double frame_period_us = 1e6 / s.frame_rate_hz, scan_period_us = 1e6 / s.scan_rate_hz;
  int64_t frames = 0, scans = 0, late = 0, errors = 0;
  double max_late_ms = 0;
  const int64_t start = glue::MonotonicUtime();
  int64_t next_progress = start + static_cast<int64_t>(s.progress_s * 1e6);
  std::cerr << "bus-check soak-publish: " << s.frames << " frames of " << s.frame_bytes << " B at " << s.frame_rate_hz
            << " Hz on " << s.frame_channel << ", " << s.scans << " scans of " << s.beams << " beams at "
            << s.scan_rate_hz << " Hz on " << s.scan_channel << "\n";
  while ((frames < s.frames || scans < s.scans) && !glue::ShutdownRequested()) {
    const int64_t frame_due = frames < s.frames ? start + static_cast<int64_t>(frames * frame_period_us) : INT64_MAX;
    const int64_t scan_due = scans < s.scans ? start + static_cast<int64_t>(scans * scan_period_us) : INT64_MAX;
    const bool frame_next = frame_due <= scan_due;
    const int64_t due = frame_next ? frame_due : scan_due;
    const int64_t wait_us = due - glue::MonotonicUtime();
    if (wait_us > 0) std::this_thread::sleep_for(std::chrono::microseconds(wait_us));
    const double late_ms = (glue::MonotonicUtime() - due) / 1000.0;
    max_late_ms = std::max(max_late_ms, late_ms);
    if (late_ms > 1000.0 / s.frame_rate_hz) ++late;
    try {
      if (frame_next) {
        bus.Publish(s.frame_channel, MakeSoakFrame(frames, s.frame_bytes));
      } else {
        bus.Publish(s.scan_channel, MakeSoakScan(scans, s.beams));
      }
    } catch (const std::exception& e) {
      if (++errors <= 5) std::cerr << "bus-check soak-publish: " << e.what() << "\n";
    }
    (frame_next ? frames : scans) += 1;
    if (s.progress_s > 0 && glue::MonotonicUtime() >= next_progress) {
      std::cerr << "bus-check soak-publish: " << std::fixed << std::setprecision(0)
                << (glue::MonotonicUtime() - start) * 1e-6 << " s: sent " << frames << " frames, " << scans
                << " scans, RSS " << ProcessRssKb() / 1024 << " MB\n";
      next_progress += static_cast<int64_t>(s.progress_s * 1e6);
    }
  }
  const double elapsed_s = (glue::MonotonicUtime() - start) * 1e-6;
  const int64_t rss_end = ProcessRssKb();
  std::cerr << "bus-check soak-publish: sent " << frames << " frames and " << scans << " scans in " << std::fixed
            << std::setprecision(1) << elapsed_s << " s (" << late << " more than a frame period late, max "
            << max_late_ms << " ms; " << errors << " publish errors); RSS " << rss_start << " -> " << rss_end
            << " kB\n";
  results::Json j;
  j[prefix + "frames_sent"] = frames;
  j[prefix + "scans_sent"] = scans;
  j[prefix + "frame_bytes"] = s.frame_bytes;
  j[prefix + "beams"] = s.beams;
  j[prefix + "frame_rate_hz"] = results::Rounded(s.frame_rate_hz, 3);
  j[prefix + "scan_rate_hz"] = results::Rounded(s.scan_rate_hz, 3);
  j[prefix + "elapsed_s"] = results::Rounded(elapsed_s, 3);
  j[prefix + "late_publishes"] = late;
  j[prefix + "max_late_ms"] = results::Rounded(max_late_ms, 3);
  j[prefix + "publish_errors"] = errors;
  j[prefix + "rss_start_kb"] = rss_start;
  j[prefix + "rss_end_kb"] = rss_end;
  WriteJson(s.out_json, j);
  return errors == 0 && frames == s.frames && scans == s.scans ? 0 : 1;
}

// Checks the soak streams in a log as lcm-logger writes it: a file, or a FIFO the logger writes
// into (so a long soak needs no disk space). Reads until the end of the file (the writer closed).
int RunSoakLogVerifier(const SoakSettings& s, const std::string& prefix) {
  SoakVerifier verifier(s.frame_channel, s.scan_channel, s.frame_bytes, s.beams, s.frames, s.scans);
  const int64_t rss_start = ProcessRssKb();
  std::cerr << "bus-check soak-verify: reading " << s.log_path << "\n";
  LogStreamReader log(s.log_path);
  const int64_t start = glue::MonotonicUtime();
  int64_t next_progress = start + static_cast<int64_t>(s.progress_s * 1e6), events = 0, timestamp = 0;
  std::string channel, data, log_error;
  auto next = [&] {
    try {
      return log.Next(&channel, &data, &timestamp);
    } catch (const std::runtime_error& e) {
      log_error = e.what();  // keep what was valid before it
      std::cerr << "bus-check soak-verify: " << log_error << "\n";
      return false;
    }
  };
  while (next()) {
    verifier.Feed(channel, data.data(), data.size());
    ++events;
    if (s.progress_s > 0 && glue::MonotonicUtime() >= next_progress) {
      std::cerr << "bus-check soak-verify (log): " << std::fixed << std::setprecision(0)
                << (glue::MonotonicUtime() - start) * 1e-6 << " s: " << verifier.Report() << "\n";
      next_progress += static_cast<int64_t>(s.progress_s * 1e6);
    }
  }
  const int64_t rss_end = ProcessRssKb();
  std::cout << "bus-check soak-verify (log " << s.log_path << "): " << events << " events, " << verifier.Report()
            << ", " << verifier.ignored() << " of other channels\n";
  results::Json j = verifier.Counts(prefix);
  j[prefix + "events"] = events;
  j[prefix + "other_channel_events"] = verifier.ignored();
  j[prefix + "reader_rss_start_kb"] = rss_start;
  j[prefix + "reader_rss_end_kb"] = rss_end;
  j[prefix + "log_intact"] = log_error.empty();
  WriteJson(s.out_json, j);
  return verifier.ok() && log_error.empty() ? 0 : 1;
}

// Receives both streams until all arrived, the log ends, a signal, or timeout_s without a message.
int RunSoakVerifier(glue::Bus& bus, const SoakSettings& s, const std::string& prefix,
                    const std::function<void()>& signal_ready) {
  SoakVerifier verifier(bus, s.frame_channel, s.scan_channel, s.frame_bytes, s.beams, s.frames, s.scans);
  const int64_t rss_start = ProcessRssKb();
  signal_ready();
  int64_t last_message = glue::MonotonicUtime(), last_count = 0;
  int64_t next_progress = last_message + static_cast<int64_t>(s.progress_s * 1e6);
  const int64_t start = last_message;
  bool timed_out = false;
  while (!verifier.complete() && !glue::ShutdownRequested() && !bus.end_of_log()) {
    bus.HandleOnce(100);
    const int64_t now = glue::MonotonicUtime();
    if (verifier.received_total() != last_count) {
      last_count = verifier.received_total();
      last_message = now;
    } else if (last_count > 0 && now - last_message > s.timeout_s * 1e6) {
      timed_out = true;
      break;
    }
    if (s.progress_s > 0 && now >= next_progress) {
      std::cerr << "bus-check soak-verify: " << std::fixed << std::setprecision(0) << (now - start) * 1e-6 << " s: "
                << verifier.Report() << ", RSS " << ProcessRssKb() / 1024 << " MB\n";
      next_progress += static_cast<int64_t>(s.progress_s * 1e6);
    }
  }
  const int64_t rss_end = ProcessRssKb();
  if (timed_out) std::cerr << "bus-check soak-verify: nothing for " << s.timeout_s << " s, stopping\n";
  std::cout << "bus-check soak-verify: " << verifier.Report() << "; RSS " << rss_start << " -> " << rss_end << " kB\n";
  bus.ReportStats(std::cerr);
  results::Json j = verifier.Counts(prefix);
  j[prefix + "rss_start_kb"] = rss_start;
  j[prefix + "rss_end_kb"] = rss_end;
  WriteJson(s.out_json, j);
  return verifier.ok() ? 0 : 1;
}

int Main(int argc, char** argv) {
  glue::CommonFlags common;
  int count = 60;
  double rate_hz = 30;
  double duration_s = 10;
  double timeout_s = 10;
  std::string sizes_text = "100,65536,1048576";
  std::string ready_file, out_json;
  std::string probe = channels::kBusCheck, ping = channels::kBusPing, pong = channels::kBusPong;
  std::string soak_frame = channels::kSoakFrame, soak_scan = channels::kSoakScan;
  int frame_bytes = 1048576, beams = 681;
  double frame_rate_hz = 30, scan_rate_hz = 10, progress_s = 30;
  std::string json_prefix, soak_log;
  glue::Flags flags("bus-check MODE",
                    "Checks the LCM bus end to end. MODE is one of:\n"
                    "  publish  send --count probe frames (sizes cycling through --sizes) at --rate-hz\n"
                    "  verify   receive --count probes; exit 0 only if all arrived byte-identical and in order\n"
                    "  echo     republish every " + ping + " message on " + pong + "\n"
                    "  ping     round-trip latency and loss through an echo process, per size\n"
                    "  soak-publish  --frame-bytes frames at --frame-rate-hz and --beams scans at --scan-rate-hz\n"
                    "           for --duration-s (defaults: 1 MB at 30 Hz, 681 beams at 10 Hz)\n"
                    "  soak-verify   receive both soak streams (same flags); exit 0 only if every message arrived\n"
                    "           byte-identical and in order. Both write counts and RSS to --out (JSON)");
  flags.AddCommon(&common);
  flags.AddInt("count", &count, "probes to publish or expect");
  flags.AddDouble("rate-hz", &rate_hz, "publish rate [Hz]");
  flags.AddString("sizes", &sizes_text, "probe payload sizes, cycled [bytes]");
  flags.AddDouble("timeout-s", &timeout_s, "verify: give up after this long without a probe [s]");
  flags.AddDouble("duration-s", &duration_s, "ping: duration per size [s]");
  flags.AddString("ready-file", &ready_file, "verify/echo: create this file once subscribed");
  flags.AddString("out", &out_json, "ping, soak-*: write the figures to this JSON file");
  flags.AddInt("frame-bytes", &frame_bytes, "soak: image bytes per frame");
  flags.AddDouble("frame-rate-hz", &frame_rate_hz, "soak: frame rate [Hz]");
  flags.AddInt("beams", &beams, "soak: ranges per scan");
  flags.AddDouble("scan-rate-hz", &scan_rate_hz, "soak: scan rate [Hz]");
  flags.AddDouble("progress-s", &progress_s, "soak: a progress line every this many seconds [s]");
  flags.AddString("log", &soak_log, "soak-verify: check this LCM log (a file, or a FIFO lcm-logger writes) instead of the bus");
  flags.AddString("json-prefix", &json_prefix, "soak: prefix of every key in --out (default: the mode's role)");
  flags.AllowPositional("MODE", "publish | verify | echo | ping");
  if (!flags.Parse(argc, argv)) return 0;
  if (flags.positional().size() != 1) throw glue::FlagError("expected exactly one MODE (see --help)");
  const std::string mode = flags.positional()[0];
  const std::vector<int> sizes = ParseSizes(sizes_text);

  if (!common.config.empty()) {
    const auto ini = glue::IniFile::Load(common.config);
    probe = ini.GetString("channels", "probe");
    ping = ini.GetString("channels", "ping");
    pong = ini.GetString("channels", "pong");
    soak_frame = ini.GetString("channels", "soak_frame");
    soak_scan = ini.GetString("channels", "soak_scan");
    ini.CheckAllUsed();
  }
  probe = channels::Prefixed(common.channel_prefix, probe);
  ping = channels::Prefixed(common.channel_prefix, ping);
  pong = channels::Prefixed(common.channel_prefix, pong);
  soak_frame = channels::Prefixed(common.channel_prefix, soak_frame);
  soak_scan = channels::Prefixed(common.channel_prefix, soak_scan);

  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  std::cerr << "bus-check " << mode << ": url=" << bus.url() << " sizes=" << sizes_text << " count=" << count
            << " rate_hz=" << rate_hz << " channels=" << probe << "," << ping << "," << pong << "\n";
  auto signal_ready = [&] {
    if (!ready_file.empty()) std::ofstream(ready_file) << "ready\n";
  };

  if (mode == "publish") {
    const int64_t period_us = static_cast<int64_t>(1e6 / rate_hz);
    const int64_t start = glue::MonotonicUtime();
    for (int k = 0; k < count && !glue::ShutdownRequested(); ++k) {
      const int64_t due = start + k * period_us;
      const int64_t wait_us = due - glue::MonotonicUtime();
      if (wait_us > 0) std::this_thread::sleep_for(std::chrono::microseconds(wait_us));
      bus.Publish(probe, MakeProbeFrame(k, sizes[k % sizes.size()]));
    }
    std::cerr << "bus-check publish: sent " << count << " probes on " << probe << "\n";
    return 0;
  }
  if (mode == "verify") {
    ProbeVerifier verifier(bus, probe, sizes, count);
    signal_ready();
    int64_t last_progress = glue::MonotonicUtime();
    int last_received = 0;
    while (!verifier.complete() && !glue::ShutdownRequested() && !bus.end_of_log()) {
      bus.HandleOnce(100);
      if (verifier.received() != last_received) {
        last_received = verifier.received();
        last_progress = glue::MonotonicUtime();
      } else if (glue::MonotonicUtime() - last_progress > timeout_s * 1e6) {
        std::cerr << "bus-check verify: no probe for " << timeout_s << " s, giving up\n";
        break;
      }
    }
    std::cout << "bus-check verify: " << verifier.Report() << "\n";
    bus.ReportStats(std::cerr);
    return verifier.ok() ? 0 : 1;
  }
  if (mode == "echo") {
    EchoNode echo(bus, ping, pong);
    signal_ready();
    bus.Run();
    std::cerr << "bus-check echo: echoed " << echo.echoed() << " messages\n";
    return 0;
  }
  if (mode == "ping") {
    const auto pings = RunPing(bus, ping, pong, sizes, rate_hz, duration_s, true);
    std::cout << std::left << std::setw(10) << "size_B" << std::setw(8) << "sent" << std::setw(8) << "lost"
              << std::setw(14) << "rtt_median_ms" << std::setw(12) << "rtt_p99_ms" << "rtt_max_ms\n";
    results::Json json;
    json["rate_hz"] = results::Significant(rate_hz);
    json["duration_s"] = results::Significant(duration_s);
    for (const auto& r : pings) {
      std::cout << std::left << std::setw(10) << r.size_bytes << std::setw(8) << r.sent << std::setw(8)
                << (r.sent - r.received) << std::setw(14) << std::fixed << std::setprecision(3) << r.median_ms
                << std::setw(12) << r.p99_ms << r.max_ms << "\n";
      const std::string s = std::to_string(r.size_bytes) + "B";
      json["sent_" + s] = r.sent;
      json["lost_" + s] = r.sent - r.received;
      json["rtt_median_ms_" + s] = results::Significant(r.median_ms);
      json["rtt_p99_ms_" + s] = results::Significant(r.p99_ms);
      json["rtt_max_ms_" + s] = results::Significant(r.max_ms);
    }
    WriteJson(out_json, json);
    return 0;
  }
  if (mode == "soak-publish" || mode == "soak-verify") {
    if (frame_bytes < 8 || beams < 1 || !(frame_rate_hz > 0) || !(scan_rate_hz > 0) || !(duration_s > 0)) {
      throw glue::FlagError("soak needs --frame-bytes >= 8, --beams >= 1 and positive rates and duration");
    }
    const int64_t n_frames = std::llround(frame_rate_hz * duration_s), n_scans = std::llround(scan_rate_hz * duration_s);
    SoakSettings settings{soak_frame, soak_scan, frame_bytes, beams, frame_rate_hz, scan_rate_hz, n_frames, n_scans,
                          progress_s, timeout_s, out_json, soak_log};
    if (mode == "soak-publish") return RunSoakPublisher(bus, settings, json_prefix.empty() ? "publisher_" : json_prefix);
    if (!soak_log.empty()) return RunSoakLogVerifier(settings, json_prefix.empty() ? "logger_" : json_prefix);
    return RunSoakVerifier(bus, settings, json_prefix.empty() ? "verifier_" : json_prefix, signal_ready);
  }
  throw glue::FlagError("unknown MODE '" + mode + "' (publish, verify, echo, ping, soak-publish or soak-verify)");
}

}  // namespace
}  // namespace snapnav::tools

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, snapnav::tools::Main); }
