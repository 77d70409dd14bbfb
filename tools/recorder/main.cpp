// recorder: records the bus into an LCM log, as lcm-logger does, without dropping what arrives while
// it waits for the CPU (a queue of --queue-capacity messages instead of LCM's default 30).
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "recorder.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

using namespace snapnav;

int Main(int argc, char** argv) {
  glue::CommonFlags common;
  tools::RecorderOptions options;
  bool append = false;
  glue::Flags flags("recorder",
                    "Records every message of the bus (or of --channel) into the LCM log FILE, each event stamped\n"
                    "with its receive time: the format of lcm-logger, read by lcm-logplayer, lcm-spy and every\n"
                    "snapnav tool. Unlike Debian's lcm-logger it keeps --queue-capacity messages while it waits for the\n"
                    "CPU (LCM's default is 30: a busy moment or a burst loses messages without a count). Runs until\n"
                    "SIGINT or SIGTERM, then prints the messages it recorded per channel.");
  flags.AddCommon(&common);
  flags.AddString("channel", &options.channels, "LCM channel regex to record (gets --channel-prefix)");
  flags.AddBool("append", &append, "add to the end of FILE (a restarted recorder) instead of refusing an existing one");
  flags.AddInt("queue-capacity", &options.queue_capacity, "messages LCM keeps for the recorder while it lags");
  flags.AddDouble("flush-interval-s", &options.flush_interval_s, "hand the written events to the system this often [s]");
  flags.AllowPositional("FILE", "the LCM log to write");
  if (!flags.Parse(argc, argv)) return 0;
  if (!common.config.empty()) throw glue::FlagError("recorder has no config file; use its flags");
  if (flags.positional().size() != 1) throw glue::FlagError("give exactly one FILE to record into (recorder --help)");
  const std::string path = flags.positional()[0];
  if (!append && std::filesystem::exists(path)) {
    throw glue::FlagError("'" + path + "' exists: --append adds to it (a restarted recorder); or remove it");
  }
  if (!common.channel_prefix.empty()) options.channels = common.channel_prefix + options.channels;
  try {
    options.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }
  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  glue::LogWriter log(path, append);
  tools::Recorder recorder(bus, log, options);
  std::cerr << "recorder: recording '" << options.channels << "' from " << bus.url() << " into " << path
            << (append ? " (appending)" : "") << ", queue " << options.queue_capacity << " messages\n";
  bus.Run([&] { return recorder.write_errors() == 0; });  // a write error stops the recording
  int rc = 0;
  try {
    log.Close();
  } catch (const std::exception& e) {
    std::cerr << "recorder: error: " << e.what() << "\n";
    rc = 1;
  }
  std::cerr << "recorder: " << recorder.events() << " messages, " << std::fixed << std::setprecision(1)
            << recorder.bytes() / 1048576.0 << " MB of payload recorded into " << path << "\n";
  if (recorder.write_errors() > 0) {
    std::cerr << "recorder: error: stopped: " << recorder.last_error() << "\n";
    rc = 1;
  }
  bus.ReportStats(std::cerr);
  return rc;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
