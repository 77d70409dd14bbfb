#include "dead_reckoning_node.hpp"

#include <iostream>
#include <ostream>
#include <stdexcept>

#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/options.hpp"

namespace snapnav::processes {
namespace {

// The [dead_reckoning] keys, declared once: read, printed and described from here.
const glue::OptionTable<nav::DeadReckoningOptions>& DeadReckoningTable() {
  using O = nav::DeadReckoningOptions;
  static const auto table = glue::OptionTable<O>()
                                .Number("translation_noise_m_per_m", "m/m", &O::translation_noise_m_per_m)
                                .Number("rotation_noise_rad_per_rad", "rad/rad", &O::rotation_noise_rad_per_rad)
                                .Number("rotation_noise_rad_per_m", "rad/m", &O::rotation_noise_rad_per_m);
  return table;
}

}  // namespace

DeadReckoningConfig DeadReckoningConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  DeadReckoningConfig c;
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");
  DeadReckoningTable().ReadKeys(ini, "dead_reckoning", &c.options);
  ini.CheckAllUsed();
  ini.Check([&c] { c.options.Validate(); });
  return c;
}

void DeadReckoningConfig::Print(std::ostream& out) const {
  out << "[channels]\nodometry = " << odometry_channel << "\npose = " << pose_channel << "\n"
      << "[dead_reckoning]\n";
  DeadReckoningTable().Print(out, options);
}

DeadReckoningNode::DeadReckoningNode(glue::Bus& bus, const DeadReckoningConfig& config)
    : bus_(bus), config_(config) {
  bus_.Subscribe(config_.odometry_channel, &DeadReckoningNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
}

void DeadReckoningNode::Reject(const std::string& reason, const std::string& detail) {
  ++rejected_[reason];
  bus_.CountDecodeError(reason + ": " + detail);  // per channel; printed to stderr, rate-limited
}

void DeadReckoningNode::OnOdometry(const odometry_t& msg) {
  // The first message's cumulative pose is the start; after it only increments are used.
  if (const std::string problem = glue::OdometryProblem(msg, !estimator_); !problem.empty()) {
    Reject("bad odometry", problem);
    return;
  }
  switch (clock_.Check(msg.utime)) {
    case glue::MessageClock::Verdict::kImplausible:
      Reject("implausible utime", std::to_string(msg.utime));
      return;
    case glue::MessageClock::Verdict::kBackInTime:
      Reject("odometry back in time", "utime " + std::to_string(msg.utime) + " after " + std::to_string(*clock_.last()));
      return;
    case glue::MessageClock::Verdict::kRestarted:
      std::cerr << "dead-reckoning: odometry time restarted at utime " << msg.utime << "\n";
      break;
    case glue::MessageClock::Verdict::kAccepted:
      break;
  }
  if (!estimator_) {
    // The first message fixes the start: the odometry frame's origin is the robot's first pose.
    estimator_.emplace(config_.options, glue::OdometryPose(msg));
  } else {
    estimator_->AddOdometry(glue::OdometryDelta(msg));
  }
  bus_.Publish(config_.pose_channel, glue::ToPoseMsg(msg.utime, "dead_reckoning", "odom", estimator_->pose(),
                                                     estimator_->covariance()));
  ++published_;
}

void DeadReckoningNode::Report(std::ostream& out) const {
  out << "dead-reckoning: published " << published_ << " poses\n";
  for (const auto& [reason, n] : rejected_) out << "dead-reckoning:   rejected (" << reason << "): " << n << "\n";
}

}  // namespace snapnav::processes
