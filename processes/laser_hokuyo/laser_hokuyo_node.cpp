#include "laser_hokuyo_node.hpp"

#include <cmath>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "snapnav/glue/options.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::processes {

namespace {

// The [hokuyo] keys, declared once: read, printed and described from here.
const glue::OptionTable<LaserHokuyoConfig>& HokuyoTable() {
  using C = LaserHokuyoConfig;
  static const auto table = glue::OptionTable<C>()
                                .Text("serial_port", [](auto& c) -> auto& { return c.hokuyo.serial_port; })
                                .Flag("intensity", [](auto& c) -> auto& { return c.hokuyo.intensity; })
                                .Text("sensor_name", [](auto& c) -> auto& { return c.scan.sensor_name; })
                                .Number("sensor_x_m", "m", [](auto& c) -> auto& { return c.scan.sensor_x_m; })
                                .Number("sensor_y_m", "m", [](auto& c) -> auto& { return c.scan.sensor_y_m; })
                                .Number("sensor_theta_rad", "rad", [](auto& c) -> auto& { return c.scan.sensor_theta_rad; })
                                .Number("fov_deg", "deg", [](auto& c) -> auto& { return c.scan.fov_deg; })
                                .Number("no_scan_timeout_s", "s", &C::no_scan_timeout_s);
  return table;
}

}  // namespace

LaserHokuyoConfig LaserHokuyoConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  LaserHokuyoConfig c;
  c.config_path = ini.origin();
  c.scan_channel = channel_prefix + ini.GetString("channels", "scan");
  HokuyoTable().ReadKeys(ini, "hokuyo", &c);
  c.scan.range_min_m = kHokuyoRangeMinM;
  ini.CheckAllUsed();
  ini.Check([&c] { c.Validate(); });
  return c;
}

void LaserHokuyoConfig::Validate() const {
  if (scan_channel.empty()) throw std::invalid_argument("[channels] scan must not be empty");
  hokuyo.Validate();
  scan.Validate();
  if (!std::isfinite(no_scan_timeout_s) || no_scan_timeout_s <= 0) {
    throw std::invalid_argument("no_scan_timeout_s must be > 0, got " + std::to_string(no_scan_timeout_s));
  }
}

void LaserHokuyoConfig::Print(std::ostream& out) const {
  out << "[channels]\nscan = " << scan_channel << "\n"
      << "[hokuyo]\n";
  HokuyoTable().Print(out, *this);
  out << "; range_min_m = " << scan.range_min_m << " (fixed: the driver's validity threshold)\n";
}

LaserHokuyoNode::LaserHokuyoNode(glue::Bus& bus, const LaserHokuyoConfig& config,
                                 std::unique_ptr<RangeScanSource> source, std::ostream* log)
    : bus_(bus), config_(config), source_(std::move(source)), log_(log) {
  config_.Validate();
  if (!source_) throw std::invalid_argument("LaserHokuyoNode needs a scan source");
  last_publish_monotonic_utime_ = glue::MonotonicUtime();
}

void LaserHokuyoNode::Warn(int64_t count, const std::string& what) {
  last_error_ = what;
  if (log_ && (count <= 5 || count % 100 == 0)) *log_ << "laser-hokuyo: " << what << " (#" << count << ")\n";
}

LaserHokuyoNode::StepResult LaserHokuyoNode::Step() {
  mrpt::obs::CObservation2DRangeScan scan;
  std::string error;
  const auto polled = source_->Poll(&scan, &error);
  StepResult result = StepResult::kNoScan;
  if (polled == RangeScanSource::PollResult::kHardwareError) {
    ++hardware_errors_;
    Warn(hardware_errors_, source_->description() + ": " + error);
  } else if (polled == RangeScanSource::PollResult::kScan) {
    laser_scan_t msg;
    bool converted = true;
    try {
      msg = RangeScanToLaserScan(scan, config_.scan);
    } catch (const std::exception& e) {
      converted = false;
      ++conversion_errors_;
      Warn(conversion_errors_, std::string("scan not converted: ") + e.what());
      result = StepResult::kSkipped;
    }
    if (converted) {
      bus_.Publish(config_.scan_channel, msg);
      ++published_;
      last_publish_monotonic_utime_ = glue::MonotonicUtime();
      return StepResult::kPublished;
    }
  }
  const double silent_s = 1e-6 * static_cast<double>(glue::MonotonicUtime() - last_publish_monotonic_utime_);
  if (silent_s > config_.no_scan_timeout_s) {
    std::ostringstream what;
    what << source_->description() << ": no scan for " << config_.no_scan_timeout_s << " s ([hokuyo] no_scan_timeout_s)"
         << "; " << hardware_errors_ << " hardware errors, " << conversion_errors_ << " scans not converted";
    if (!last_error_.empty()) what << "; last: " << last_error_;
    what << ". Was the sensor unplugged?";
    throw std::runtime_error(what.str());
  }
  return result;
}

void LaserHokuyoNode::Run(int64_t max_scans) {
  while (!glue::ShutdownRequested() && (max_scans <= 0 || published_ < max_scans)) Step();
}

void LaserHokuyoNode::Report(std::ostream& out) const {
  out << "published " << published_ << " scans on " << config_.scan_channel << " from " << source_->description()
      << " (" << hardware_errors_ << " hardware errors, " << conversion_errors_ << " not converted)";
  if (!last_error_.empty()) out << "; last problem: " << last_error_;
  out << "\n";
}

}  // namespace snapnav::processes
