// bus-check: end-to-end checks and the round-trip benchmark of the LCM bus.
//   bus-check publish  send --count probe frames of known content at --rate-hz
//   bus-check verify   receive them; exit 0 only if every one arrived byte-identical and in order
//   bus-check echo     republish BUS_PING on BUS_PONG
//   bus-check ping     time round trips through an echo process, per message size

#include <fstream>
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

int Main(int argc, char** argv) {
  glue::CommonFlags common;
  int count = 60;
  double rate_hz = 30;
  double duration_s = 10;
  double timeout_s = 10;
  std::string sizes_text = "100,65536,1048576";
  std::string ready_file, out_json;
  std::string probe = channels::kBusCheck, ping = channels::kBusPing, pong = channels::kBusPong;
  glue::Flags flags("bus-check MODE",
                    "Checks the LCM bus end to end. MODE is one of:\n"
                    "  publish  send --count probe frames (sizes cycling through --sizes) at --rate-hz\n"
                    "  verify   receive --count probes; exit 0 only if all arrived byte-identical and in order\n"
                    "  echo     republish every " + ping + " message on " + pong + "\n"
                    "  ping     round-trip latency and loss through an echo process, per size");
  flags.AddCommon(&common);
  flags.AddInt("count", &count, "probes to publish or expect");
  flags.AddDouble("rate-hz", &rate_hz, "publish rate [Hz]");
  flags.AddString("sizes", &sizes_text, "probe payload sizes, cycled [bytes]");
  flags.AddDouble("timeout-s", &timeout_s, "verify: give up after this long without a probe [s]");
  flags.AddDouble("duration-s", &duration_s, "ping: duration per size [s]");
  flags.AddString("ready-file", &ready_file, "verify/echo: create this file once subscribed");
  flags.AddString("out", &out_json, "ping: write the figures to this JSON file");
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
    ini.CheckAllUsed();
  }
  probe = channels::Prefixed(common.channel_prefix, probe);
  ping = channels::Prefixed(common.channel_prefix, ping);
  pong = channels::Prefixed(common.channel_prefix, pong);

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
    const auto results = RunPing(bus, ping, pong, sizes, rate_hz, duration_s, true);
    std::cout << std::left << std::setw(10) << "size_B" << std::setw(8) << "sent" << std::setw(8) << "lost"
              << std::setw(14) << "rtt_median_ms" << std::setw(12) << "rtt_p99_ms" << "rtt_max_ms\n";
    std::ofstream json;
    if (!out_json.empty()) json.open(out_json);
    if (json) json << "{\n  \"rate_hz\": " << rate_hz << ",\n  \"duration_s\": " << duration_s;
    for (const auto& r : results) {
      std::cout << std::left << std::setw(10) << r.size_bytes << std::setw(8) << r.sent << std::setw(8)
                << (r.sent - r.received) << std::setw(14) << std::fixed << std::setprecision(3) << r.median_ms
                << std::setw(12) << r.p99_ms << r.max_ms << "\n";
      if (json) {
        const std::string s = std::to_string(r.size_bytes) + "B";
        json << ",\n  \"sent_" << s << "\": " << r.sent << ",\n  \"lost_" << s << "\": " << (r.sent - r.received)
             << ",\n  \"rtt_median_ms_" << s << "\": " << r.median_ms << ",\n  \"rtt_p99_ms_" << s
             << "\": " << r.p99_ms << ",\n  \"rtt_max_ms_" << s << "\": " << r.max_ms;
      }
    }
    if (json) json << "\n}\n";
    return 0;
  }
  throw glue::FlagError("unknown MODE '" + mode + "' (publish, verify, echo or ping)");
}

}  // namespace
}  // namespace snapnav::tools

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, snapnav::tools::Main); }
