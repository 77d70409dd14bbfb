#include "hokuyo_source.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <mrpt/hwdrivers/CHokuyoURG.h>

namespace snapnav::processes {
namespace {

constexpr char kNoSuchDevice[] = "no such device";

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

}  // namespace

void HokuyoOptions::Validate() const {
  if (serial_port.empty()) throw std::invalid_argument("serial_port must not be empty");
}

std::string CheckSerialPort(const std::string& port) {
  struct stat st {};
  if (stat(port.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) return kNoSuchDevice;
    return std::strerror(errno);
  }
  if (S_ISDIR(st.st_mode)) return "it is a folder, not a serial device";
  if (!S_ISCHR(st.st_mode)) return "not a character device (a serial port such as /dev/ttyACM0 is expected)";
  if (access(port.c_str(), R_OK | W_OK) != 0) {
    if (errno == EACCES) {
      return "permission denied (add your user to the 'dialout' group: sudo usermod -aG dialout $USER, then log "
             "in again)";
    }
    return std::strerror(errno);
  }
  return "";
}

std::string BriefMrptError(const std::exception& e) {
  const std::string what = e.what();
  // MRPT: "==== MRPT exception ====\nMessage:  TEXT\nLocation: ...\nCall stack backtrace:\n...".
  if (const auto m = what.find("Message:"); m != std::string::npos) {
    const auto eol = what.find('\n', m);
    const std::string message = Trim(what.substr(m + 8, eol == std::string::npos ? std::string::npos : eol - m - 8));
    if (!message.empty()) return message;
  }
  size_t start = 0;
  while (start < what.size()) {
    const auto eol = what.find('\n', start);
    const std::string line = Trim(what.substr(start, eol == std::string::npos ? std::string::npos : eol - start));
    if (!line.empty() && line.rfind("====", 0) != 0) return line;
    if (eol == std::string::npos) break;
    start = eol + 1;
  }
  return "unknown error";
}

HokuyoUrgSource::HokuyoUrgSource(const HokuyoOptions& options, const std::string& config_path) : options_(options) {
  options_.Validate();
  const std::string& port = options_.serial_port;
  const std::string prefix = "cannot open Hokuyo URG on " + port + ": ";
  const std::string set_port = "set [hokuyo] serial_port in " + config_path;
  // Check the port ourselves: MRPT's answer to a missing port is an exception with a stack trace.
  const std::string problem = CheckSerialPort(port);
  if (problem == kNoSuchDevice) throw std::runtime_error(prefix + problem + ". Plug in the sensor or " + set_port);
  if (!problem.empty()) throw std::runtime_error(prefix + problem + ". Check the sensor's port or " + set_port);

  driver_ = std::make_unique<mrpt::hwdrivers::CHokuyoURG>();
  driver_->setSerialPort(port);
  driver_->setIntensityMode(options_.intensity);
  bool started = false;
  try {
    started = driver_->turnOn();
  } catch (const std::exception& e) {
    throw std::runtime_error(prefix + BriefMrptError(e) + ". Is " + port + " the sensor's serial port? Otherwise " +
                             set_port);
  }
  if (!started) {
    throw std::runtime_error(prefix +
                             "the sensor did not answer the SCIP 2.0 start-up sequence. Is it a Hokuyo URG, powered, "
                             "and not in use by another program? Otherwise " +
                             set_port);
  }
}

HokuyoUrgSource::~HokuyoUrgSource() = default;

RangeScanSource::PollResult HokuyoUrgSource::Poll(mrpt::obs::CObservation2DRangeScan* scan, std::string* error) {
  bool have_scan = false;
  bool hardware_error = false;
  try {
    driver_->doProcessSimple(have_scan, *scan, hardware_error);
  } catch (const std::exception& e) {
    *error = BriefMrptError(e);
    return PollResult::kHardwareError;
  }
  if (hardware_error) {
    *error = "the driver reported a hardware error (port closed, or the sensor sent an error status or a short scan)";
    return PollResult::kHardwareError;
  }
  return have_scan ? PollResult::kScan : PollResult::kNoScan;
}

}  // namespace snapnav::processes
