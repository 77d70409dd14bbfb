#include "dead_reckoning_node.hpp"

#include <ostream>
#include <stdexcept>

#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/conversions.hpp"

namespace snapnav::processes {

DeadReckoningConfig DeadReckoningConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  DeadReckoningConfig c;
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");
  c.options.translation_noise_m_per_m = ini.GetDouble("dead_reckoning", "translation_noise_m_per_m");
  c.options.rotation_noise_rad_per_rad = ini.GetDouble("dead_reckoning", "rotation_noise_rad_per_rad");
  c.options.rotation_noise_rad_per_m = ini.GetDouble("dead_reckoning", "rotation_noise_rad_per_m");
  ini.CheckAllUsed();
  c.options.Validate();
  return c;
}

void DeadReckoningConfig::Print(std::ostream& out) const {
  out << "[channels]\nodometry = " << odometry_channel << "\npose = " << pose_channel << "\n"
      << "[dead_reckoning]\ntranslation_noise_m_per_m = " << options.translation_noise_m_per_m
      << "\nrotation_noise_rad_per_rad = " << options.rotation_noise_rad_per_rad
      << "\nrotation_noise_rad_per_m = " << options.rotation_noise_rad_per_m << "\n";
}

DeadReckoningNode::DeadReckoningNode(glue::Bus& bus, const DeadReckoningConfig& config)
    : bus_(bus), config_(config) {
  bus_.Subscribe(config_.odometry_channel, &DeadReckoningNode::OnOdometry, this);
}

void DeadReckoningNode::OnOdometry(const odometry_t& msg) {
  if (!estimator_) {
    // The first message fixes the start: the odometry frame's origin is the robot's first pose.
    estimator_.emplace(config_.options, glue::OdometryPose(msg));
  } else {
    if (msg.utime < last_utime_) {
      throw std::invalid_argument("odometry utime " + std::to_string(msg.utime) + " goes back in time");
    }
    estimator_->AddOdometry(glue::OdometryDelta(msg));
  }
  last_utime_ = msg.utime;
  bus_.Publish(config_.pose_channel, glue::ToPoseMsg(msg.utime, "dead_reckoning", "odom", estimator_->pose(),
                                                     estimator_->covariance()));
  ++published_;
}

}  // namespace snapnav::processes
