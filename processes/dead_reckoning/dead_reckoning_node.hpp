#pragma once
// dead-reckoning: integrates ODOMETRY alone and publishes the pose with its
// growing covariance, as the baseline for every other estimator.

#include <iosfwd>
#include <optional>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"
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

 private:
  void OnOdometry(const odometry_t& msg);

  glue::Bus& bus_;
  DeadReckoningConfig config_;
  std::optional<nav::DeadReckoning> estimator_;
  int64_t last_utime_ = 0;
  int64_t published_ = 0;
};

}  // namespace snapnav::processes
