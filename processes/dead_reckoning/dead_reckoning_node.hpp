#pragma once
// dead-reckoning: integrates ODOMETRY alone and publishes the pose with its
// growing covariance, as the baseline for every other estimator.

#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/message_clock.hpp"
#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/odometry_t.hpp"

namespace snapnav::processes {

struct DeadReckoningConfig {
  std::string odometry_channel;
  std::string pose_channel;
  nav::DeadReckoningOptions options;

  // Reads [channels] and [dead_reckoning]; every key is required, unknown keys are errors.
  static DeadReckoningConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Print(std::ostream& out) const;
};

class DeadReckoningNode {
 public:
  DeadReckoningNode(glue::Bus& bus, const DeadReckoningConfig& config);
  int64_t published() const { return published_; }
  // Odometry messages skipped, by reason ("bad odometry", "odometry back in time", ...); each is
  // also counted as rejected on its channel by the bus.
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  // The counts: "dead-reckoning: published N poses" and a line per reason of rejection.
  void Report(std::ostream& out) const;

 private:
  void OnOdometry(const odometry_t& msg);
  void Reject(const std::string& reason, const std::string& detail);

  glue::Bus& bus_;
  DeadReckoningConfig config_;
  std::optional<nav::DeadReckoning> estimator_;
  glue::MessageClock clock_;
  int64_t published_ = 0;
  std::map<std::string, int64_t> rejected_;
};

}  // namespace snapnav::processes
