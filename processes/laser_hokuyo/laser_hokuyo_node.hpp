#pragma once
// laser-hokuyo: reads a Hokuyo URG laser scanner (e.g. URG-04LX: 682 beams over
// about 240 degrees, 0.02..5.6 m) through MRPT's CHokuyoURG driver and publishes
// laser_scan_t. utime is the observation's timestamp as the driver sets it (the PC
// clock when the scan arrived, re-based on the sensor's own clock after its first
// few scans).

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>

#include "hokuyo_source.hpp"
#include "laser_scan_conversion.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav::processes {

// CHokuyoURG marks readings under 20 mm invalid; that is the published range_min_m.
inline constexpr double kHokuyoRangeMinM = 0.02;

struct LaserHokuyoConfig {
  std::string scan_channel;
  std::string config_path;  // named in error messages
  HokuyoOptions hokuyo;
  LaserScanOptions scan;
  double no_scan_timeout_s = 2.0;  // no scan for this long is an error

  // Reads [channels] and [hokuyo]; every key is required, unknown keys and invalid
  // values are glue::ConfigError naming the file.
  static LaserHokuyoConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Validate() const;  // throws std::invalid_argument
  void Print(std::ostream& out) const;
};

class LaserHokuyoNode {
 public:
  enum class StepResult { kPublished, kNoScan, kSkipped };

  LaserHokuyoNode(glue::Bus& bus, const LaserHokuyoConfig& config, std::unique_ptr<RangeScanSource> source,
                  std::ostream* log = nullptr);

  // Polls the source once and publishes a scan if one came. Hardware errors and scans
  // that do not convert are counted; no published scan for no_scan_timeout_s throws
  // std::runtime_error.
  StepResult Step();
  // Steps until `max_scans` are published (0: no limit) or glue::ShutdownRequested().
  void Run(int64_t max_scans);

  int64_t published() const { return published_; }
  int64_t hardware_errors() const { return hardware_errors_; }
  int64_t conversion_errors() const { return conversion_errors_; }
  void Report(std::ostream& out) const;

 private:
  void Warn(int64_t count, const std::string& what);

  glue::Bus& bus_;
  LaserHokuyoConfig config_;
  std::unique_ptr<RangeScanSource> source_;
  std::ostream* log_;
  int64_t last_publish_monotonic_utime_ = 0;
  int64_t published_ = 0;
  int64_t hardware_errors_ = 0;
  int64_t conversion_errors_ = 0;
  std::string last_error_;
};

}  // namespace snapnav::processes
