// latency-probe: end-to-end latency from an omni frame to the outputs it produced (homing vector,
// place-cell pose, fused pose), timed by this process's receive times.
#include <cctype>
#include <fstream>
#include <iomanip>
#include <iostream>

#include "latency_probe.hpp"
#include "results.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"

namespace {

using namespace snapnav;

std::string Key(const std::string& channel) {
  std::string k = channel;
  for (auto& c : k) c = std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
  return k;
}

int Main(int argc, char** argv) {
  glue::CommonFlags common;
  std::string input = channels::kOmniFrame;
  std::string outputs_text = std::string(channels::kHomingVector) + "," + channels::kPosePlaceCells + "," +
                             channels::kPoseFusedSlam + "@" + channels::kPosePlaceCells;
  std::string out_json, csv, ready_file, frames_csv;
  double duration_s = 0, window_s = 30;
  glue::Flags flags("latency-probe",
                    "End-to-end latency: receives the frames of --input and the messages of every --outputs channel,\n"
                    "and pairs an output with the frame of the same utime (every snapnav type starts with utime).\n"
                    "Latency = this process's receive time of the output - its receive time of the frame. CHANNEL@AFTER\n"
                    "counts an output only after AFTER's output of the same frame (the fused pose of a place-cell fix,\n"
                    "when scans share the frames' utimes). Runs until --duration-s, SIGINT or the end of a log; prints\n"
                    "and writes median / p95 / max per output. The channels get --channel-prefix.");
  flags.AddCommon(&common);
  flags.AddString("input", &input, "frame channel");
  flags.AddString("outputs", &outputs_text, "output channels, comma-separated, each CHANNEL or CHANNEL@AFTER");
  flags.AddDouble("duration-s", &duration_s, "stop after this long [s, wall clock]; 0: until SIGINT");
  flags.AddDouble("window-s", &window_s, "frames are paired for this much message time [s]");
  flags.AddString("out", &out_json, "write the figures to this JSON file (flat keys, ms)");
  flags.AddString("csv", &csv, "write every latency sample to this CSV file (output,latency_ms)");
  flags.AddString("ready-file", &ready_file, "create this file once subscribed");
  flags.AddString("frames-csv", &frames_csv,
                  "write every --input frame's utime and this process's receive time (LCM's, the wall clock) to this\n"
                  "CSV file (utime,recv_utime): two probes on two hosts of one clock give each frame's time across the link");
  if (!flags.Parse(argc, argv)) return 0;
  if (!common.config.empty()) throw glue::FlagError("latency-probe has no config file; use --input and --outputs");
  std::vector<tools::LatencyOutput> outputs;
  try {
    outputs = tools::ParseLatencyOutputs(outputs_text);
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(std::string("--outputs: ") + e.what());
  }
  for (auto& o : outputs) {
    o.channel = common.channel_prefix + o.channel;
    if (!o.after.empty()) o.after = common.channel_prefix + o.after;
  }
  input = common.channel_prefix + input;

  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  tools::LatencyProbe probe(bus, input, outputs, window_s);
  std::ofstream frame_times;
  if (!frames_csv.empty()) {
    frame_times.open(frames_csv);
    if (!frame_times) throw glue::FlagError("--frames-csv: cannot write " + frames_csv);
    frame_times << "utime,recv_utime\n";
    probe.LogFrames(&frame_times);
  }
  std::cerr << "latency-probe: frames " << input << ", outputs " << outputs_text << " (" << bus.url() << ")\n";
  if (!ready_file.empty()) std::ofstream(ready_file) << "ready\n";
  const int64_t end = duration_s > 0 ? glue::MonotonicUtime() + static_cast<int64_t>(duration_s * 1e6) : 0;
  bus.Run([&] { return end == 0 || glue::MonotonicUtime() < end; });

  results::Json json;
  json["frames"] = probe.frames();
  std::cout << "latency-probe: " << probe.frames() << " frames on " << input << "\n"
            << std::left << std::setw(24) << "output" << std::right << std::setw(9) << "matched" << std::setw(11)
            << "median_ms" << std::setw(9) << "p95_ms" << std::setw(9) << "max_ms" << std::setw(11) << "unmatched"
            << "\n";
  for (const auto& o : probe.outputs()) {
    const tools::LatencyStats s = probe.Stats(o.channel);
    std::cout << std::left << std::setw(24) << o.channel << std::right << std::setw(9) << s.matched << std::fixed
              << std::setprecision(1) << std::setw(11) << s.median_ms << std::setw(9) << s.p95_ms << std::setw(9)
              << s.max_ms << std::setw(11) << s.unmatched << "\n";
    const std::string k = Key(o.channel);
    json[k + "_messages"] = s.outputs;
    json[k + "_matched"] = s.matched;
    json[k + "_unmatched"] = s.unmatched;
    json[k + "_frames_without_output"] = probe.frames_without(o.channel);
    if (s.matched > 0) {
      json[k + "_latency_median_ms"] = results::Rounded(s.median_ms, 3);
      json[k + "_latency_p95_ms"] = results::Rounded(s.p95_ms, 3);
      json[k + "_latency_max_ms"] = results::Rounded(s.max_ms, 3);
      json[k + "_latency_min_ms"] = results::Rounded(s.min_ms, 3);
      json[k + "_latency_mean_ms"] = results::Rounded(s.mean_ms, 3);
    }
  }
  if (!out_json.empty()) results::WriteJsonFile(out_json, json);
  if (!csv.empty()) {
    std::ofstream f(csv);
    f << "output,latency_ms\n";
    for (const auto& o : probe.outputs())
      for (double v : probe.samples_ms(o.channel)) f << o.channel << "," << v << "\n";
  }
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
