#pragma once
// Where laser-hokuyo's scans come from: an interface the node polls, and its
// implementation on MRPT's Hokuyo URG driver (SCIP 2.0 over a USB serial port).

#include <exception>
#include <memory>
#include <string>

#include <mrpt/obs/CObservation2DRangeScan.h>

namespace mrpt::hwdrivers {
class CHokuyoURG;
}

namespace snapnav::processes {

class RangeScanSource {
 public:
  enum class PollResult { kScan, kNoScan, kHardwareError };
  virtual ~RangeScanSource() = default;
  // Waits briefly (the driver's timeout) for the next scan. kHardwareError sets *error.
  virtual PollResult Poll(mrpt::obs::CObservation2DRangeScan* scan, std::string* error) = 0;
  // E.g. "Hokuyo URG on /dev/ttyACM0".
  virtual std::string description() const = 0;
};

struct HokuyoOptions {
  std::string serial_port = "/dev/ttyACM0";
  bool intensity = false;  // ask for intensities (SCIP ME command; not every model has it)

  void Validate() const;  // throws std::invalid_argument
};

// Empty when `port` exists, is a character device and this user may read and write
// it; otherwise why not: "no such device", "not a character device ...", "permission
// denied ...".
std::string CheckSerialPort(const std::string& port);

// The message of an exception without MRPT's location and call-stack lines.
std::string BriefMrptError(const std::exception& e);

class HokuyoUrgSource : public RangeScanSource {
 public:
  // Checks the port, opens it and starts the scanner. Throws std::runtime_error
  // "cannot open Hokuyo URG on PORT: REASON. HINT" (HINT names `config_path`); MRPT
  // exceptions never escape with their stack trace.
  HokuyoUrgSource(const HokuyoOptions& options, const std::string& config_path);
  ~HokuyoUrgSource() override;  // turns the laser off

  PollResult Poll(mrpt::obs::CObservation2DRangeScan* scan, std::string* error) override;
  std::string description() const override { return "Hokuyo URG on " + options_.serial_port; }

 private:
  HokuyoOptions options_;
  std::unique_ptr<mrpt::hwdrivers::CHokuyoURG> driver_;
};

}  // namespace snapnav::processes
