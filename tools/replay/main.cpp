// replay: a recorded LCM log through the processing processes in lockstep, outputs into a new log.
#include <iostream>

#include "replay.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  replay::ReplayOptions options;
  options.config_dir = SNAPNAV_CONFIG_DIR;
  std::string only;
  bool quiet = false;
  bool print_config = false;
  std::string names;
  for (const auto& e : replay::ReplayRegistry()) names += (names.empty() ? "" : ", ") + e.name;
  glue::Flags flags(
      "replay",
      "Feeds a recorded LCM log through the processing processes in lockstep, as fast as possible,\n"
      "and records what they publish. The nodes are the ones the process binaries run, with the same\n"
      "config files, on one in-process bus: each log event is published in order and every message it\n"
      "causes (landmarks -> homing, placecells -> navigator) is handled before the next, so the same\n"
      "log gives a byte-identical output log. Output events carry the event time of the input event\n"
      "that caused them. Log messages on a channel a replayed process publishes are not fed (the\n"
      "process makes them anew). Processes: " +
          names +
          ".\n"
          "Each process's effective configuration is printed with --print-config (about 500 lines).\n"
          "Exit status 0; 3 when the input log is damaged (the intact events were replayed, the damage is\n"
          "reported with its byte offsets); 1 on an error (a file that is not an LCM log, a config error, an\n"
          "override of a key the config does not have); 2 on a flag error.");
  flags.AllowPositional("LOG", "the recorded LCM log");
  flags.AddString("out", &options.output, "output LCM log (required)");
  flags.AddString("only", &only, "comma-separated processes to run (default: every one that starts with its config)");
  flags.AddString("config-dir", &options.config_dir, "folder of the processes' INI files");
  flags.AddStringList("set", &options.sets, "config override PROCESS:SECTION.KEY=VALUE, e.g. homing:homing.home=first");
  flags.AddString("channel-prefix", &options.channel_prefix, "prefix prepended to every channel of every process");
  flags.AddBool("with-inputs", &options.with_inputs, "also write the input events that were fed to the output log");
  flags.AddBool("print-config", &print_config, "print each process's effective configuration (INI) before the replay");
  flags.AddBool("quiet", &quiet, "print no configuration (the default without --print-config; kept for old scripts)");
  flags.AddDouble("progress-s", &options.progress_interval_s, "seconds between progress lines (0: none)");
  if (!flags.Parse(argc, argv)) return 0;
  if (flags.positional().size() != 1) throw glue::FlagError("expected one LOG (see --help)");
  if (options.output.empty()) throw glue::FlagError("--out OUT.lcmlog is required");
  options.input = flags.positional()[0];
  options.only = glue::SplitList(only);
  options.print_config = print_config && !quiet;
  const auto result = replay::RunReplay(options, std::cerr);
  if (result.damage_count > 0) {
    std::cerr << "replay: warning: " << options.input << " is damaged (" << result.damage_count << " place(s), "
              << result.damaged_bytes << " bytes skipped, see above): replayed the intact events\n";
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
