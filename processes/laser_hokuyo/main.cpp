// laser-hokuyo: publishes the scans of a Hokuyo URG laser scanner (MRPT driver).
#include <iostream>
#include <memory>

#include "laser_hokuyo_node.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace {

int Main(int argc, char** argv) {
  using namespace snapnav;
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/laser_hokuyo.ini";
  int max_scans = 0;
  glue::Flags flags("laser-hokuyo",
                    "Reads a Hokuyo URG laser scanner (SCIP 2.0, e.g. URG-04LX) on a USB serial port through MRPT's\n"
                    "CHokuyoURG driver and publishes laser_scan_t. utime is the driver's scan timestamp.");
  flags.AddCommon(&common);
  flags.AddInt("max-scans", &max_scans, "stop after publishing this many scans (0: no limit)");
  if (!flags.Parse(argc, argv)) return 0;
  if (max_scans < 0) throw glue::FlagError("--max-scans must be >= 0");

  const auto config = processes::LaserHokuyoConfig::FromIni(glue::IniFile::Load(common.config), common.channel_prefix);
  std::cerr << "laser-hokuyo: config " << common.config << "\n";
  config.Print(std::cerr);
  glue::InstallShutdownHandlers();
  // The sensor first: without it there is nothing to publish.
  auto source = std::make_unique<processes::HokuyoUrgSource>(config.hokuyo, config.config_path);
  glue::Bus bus(common.lcm_url);
  processes::LaserHokuyoNode node(bus, config, std::move(source), &std::cerr);
  std::cerr << "laser-hokuyo: publishing on " << config.scan_channel << " (" << bus.url() << ")\n";
  node.Run(max_scans);
  std::cerr << "laser-hokuyo: ";
  node.Report(std::cerr);
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, Main); }
