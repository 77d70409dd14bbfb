#include "ratslam_node.hpp"

#include <chrono>
#include <cmath>
#include <iostream>
#include <ostream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "snapnav/experience_map_t.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/message_clock.hpp"

namespace snapnav::processes {
namespace {

bool Finite(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }

double Ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

experience_map_t ToExperienceMapMsg(int64_t utime, const nav::RatSlam& slam) {
  const nav::ExperienceMap& map = slam.experience_map();
  experience_map_t m{};
  m.utime = utime;
  m.estimator = "ratslam";
  m.frame = "map";
  m.templates = slam.templates();
  m.loop_closures = slam.loop_closures();
  m.current_experience = map.current();
  const nav::Pose2 robot = slam.pose();
  m.robot_x_m = robot.x_m;
  m.robot_y_m = robot.y_m;
  m.robot_theta_rad = robot.theta_rad;
  const auto& experiences = map.experiences();
  m.nexperiences = static_cast<int32_t>(experiences.size());
  m.x_m.reserve(experiences.size());
  m.y_m.reserve(experiences.size());
  m.theta_rad.reserve(experiences.size());
  m.view_template.reserve(experiences.size());
  for (const nav::Experience& e : experiences) {
    m.x_m.push_back(e.pose.x_m);
    m.y_m.push_back(e.pose.y_m);
    m.theta_rad.push_back(e.pose.theta_rad);
    m.view_template.push_back(e.view_template);
  }
  const auto& links = map.links();
  m.nlinks = static_cast<int32_t>(links.size());
  for (const nav::ExperienceLink& l : links) {
    m.link_from.push_back(l.from);
    m.link_to.push_back(l.to);
    m.link_loop_closure.push_back(l.loop_closure ? 1 : 0);
  }
  return m;
}

const char* RatSlamPoseOnName(RatSlamPoseOn p) {
  switch (p) {
    case RatSlamPoseOn::kFrame:
      return "frame";
    case RatSlamPoseOn::kOdometry:
      return "odometry";
    case RatSlamPoseOn::kBoth:
      return "both";
  }
  return "?";
}

RatSlamConfig RatSlamConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  RatSlamConfig c;
  c.omni_channel = channel_prefix + ini.GetString("channels", "omni");
  c.panorama_channel = channel_prefix + ini.GetString("channels", "panorama");
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");
  c.experience_map_channel = channel_prefix + ini.GetString("channels", "experience_map");
  c.raw_input = glue::ReadChoice<bool>(ini, "node", "input", {{"raw", true}, {"panorama", false}});
  c.pose_on = glue::ReadChoice<RatSlamPoseOn>(
      ini, "node", "pose_on",
      {{"frame", RatSlamPoseOn::kFrame}, {"odometry", RatSlamPoseOn::kOdometry}, {"both", RatSlamPoseOn::kBoth}});
  c.experience_map_interval_s = ini.GetDouble("node", "experience_map_interval_s");
  c.stats_interval_s = ini.GetDouble("node", "stats_interval_s");
  c.panorama = glue::ReadPanoramaConfig(ini);
  c.mirror = glue::ReadMirrorConfig(ini);
  const glue::MirrorMask mask = glue::ReadMirrorMask(ini);  // the mask, loaded: [mirror] mask
  c.mask_path = mask.path;
  c.mask = mask.mask;
  c.options = glue::ReadRatSlamOptions(ini);
  ini.CheckAllUsed();
  if (!(c.experience_map_interval_s >= 0) || !std::isfinite(c.experience_map_interval_s)) {
    ini.FailKey("node", "experience_map_interval_s", "must be >= 0 (0: never publish)");
  }
  if (!(c.stats_interval_s >= 0) || !std::isfinite(c.stats_interval_s)) {
    ini.FailKey("node", "stats_interval_s", "must be >= 0 (0: no stats lines)");
  }
  try {
    c.panorama.Validate();
    c.mirror.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  return c;
}

void RatSlamConfig::Print(std::ostream& out) const {
  out << "[channels]\nomni = " << omni_channel << "\npanorama = " << panorama_channel
      << "\nodometry = " << odometry_channel << "\npose = " << pose_channel
      << "\nexperience_map = " << experience_map_channel << "\n[node]\ninput = " << (raw_input ? "raw" : "panorama")
      << "\npose_on = " << RatSlamPoseOnName(pose_on) << "\nexperience_map_interval_s = " << experience_map_interval_s
      << "\nstats_interval_s = " << stats_interval_s << "\n";
  glue::PrintPanoramaConfig(out, panorama);
  glue::PrintMirrorConfig(out, mirror, mask_path, "mirror");
  glue::PrintRatSlamOptions(out, options);
}

RatSlamNode::RatSlamNode(glue::Bus& bus, const RatSlamConfig& config, std::ostream& log)
    : bus_(bus),
      config_(config),
      log_(log),
      frames_to_panoramas_(config.panorama, config.mirror),
      problems_(bus, "ratslam") {
  config_.options.Validate();  // throws std::invalid_argument before anything is subscribed
  frames_to_panoramas_.SetMask(config_.mask);
  bus_.Subscribe(config_.input_channel(), &RatSlamNode::OnFrame, this);
  bus_.Subscribe(config_.odometry_channel, &RatSlamNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
}

int64_t RatSlamNode::rejected(const std::string& reason) const {
  const auto it = rejected_.find(reason);
  return it == rejected_.end() ? 0 : it->second;
}

int64_t RatSlamNode::rejected_total() const {
  int64_t n = 0;
  for (const auto& [_, k] : rejected_) n += k;
  return n;
}

void RatSlamNode::Reject(const std::string& reason, const std::string& detail) {
  ++rejected_[reason];
  bus_.CountDecodeError(reason + (detail.empty() ? "" : ": " + detail));  // per channel; printed, rate-limited
}

// Nothing leaves a handler: inputs are checked before libnav sees them, and anything else (a failed
// publish) is counted as an internal error and reported at exit.
void RatSlamNode::OnFrame(const omni_frame_t& frame) {
  problems_.Guard("frame", [&] { HandleFrame(frame); });
}

void RatSlamNode::OnOdometry(const odometry_t& msg) {
  problems_.Guard("odometry", [&] { HandleOdometry(msg); });
}

void RatSlamNode::HandleOdometry(const odometry_t& msg) {
  ++odometry_;
  if (!glue::PlausibleUtime(msg.utime)) {  // the map and stats intervals take time differences
    Reject("implausible utime", "odometry at utime " + std::to_string(msg.utime));
    return;
  }
  if (!odometry_seen_) {
    // The first message fixes the start; its increment is relative to a message never seen.
    if (const std::string problem = glue::OdometryStartProblem(msg); !problem.empty()) {
      Reject(Finite(msg.x_m, msg.y_m, msg.theta_rad) ? "absurd odometry" : "non-finite odometry", problem);
      return;
    }
    odometry_seen_ = true;
    if (!slam_) slam_.emplace(config_.options, glue::OdometryPose(msg));
    AfterMessage(msg.utime);
    return;
  }
  if (!Finite(msg.delta_x_m, msg.delta_y_m, msg.delta_theta_rad)) {
    Reject("non-finite odometry", "increment is not finite");
    return;
  }
  if (const std::string problem = glue::OdometryProblem(msg, false); !problem.empty()) {
    Reject("absurd odometry", problem);  // as the other nodes: no experience a kilometre away
    return;
  }
  if (!std::isfinite(msg.delta_t_s) || msg.delta_t_s < 0) {
    Reject("bad odometry time", "delta_t_s " + std::to_string(msg.delta_t_s) + " (finite, >= 0)");
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  slam_->OnOdometry(glue::OdometryDelta(msg), msg.delta_t_s);
  odometry_ms_ += Ms(t0);
  ++steps_;
  if (config_.pose_on != RatSlamPoseOn::kFrame) PublishPose(msg.utime);
  AfterMessage(msg.utime);
}

void RatSlamNode::HandleFrame(const omni_frame_t& frame) {
  ++frames_;
  if (!glue::PlausibleUtime(frame.utime)) {
    Reject("implausible utime", "frame at utime " + std::to_string(frame.utime));
    return;
  }
  const std::optional<cv::Mat> panorama = frames_to_panoramas_.Convert(frame);
  if (!panorama) {
    Reject(frames_to_panoramas_.reason(), frames_to_panoramas_.detail());
    return;
  }
  if (panorama->channels() == 1) {
    gray_ = *panorama;
  } else {
    cv::cvtColor(*panorama, gray_, cv::COLOR_BGR2GRAY);
  }
  if (!slam_) slam_.emplace(config_.options, nav::Pose2{});  // no odometry yet: start at the origin
  const auto t0 = std::chrono::steady_clock::now();
  slam_->OnImage(gray_, frames_to_panoramas_.mask());
  image_ms_ += Ms(t0);
  ++processed_;
  if (config_.pose_on != RatSlamPoseOn::kOdometry) PublishPose(frame.utime);
  AfterMessage(frame.utime);
}

void RatSlamNode::PublishPose(int64_t utime) {
  bus_.Publish(config_.pose_channel, glue::ToPoseMsg(utime, "ratslam", "map", slam_->pose(), Eigen::Matrix3d::Zero()));
  ++poses_published_;
}

void RatSlamNode::PublishExperienceMap(int64_t utime) {
  if (!slam_) return;
  bus_.Publish(config_.experience_map_channel, ToExperienceMapMsg(utime, *slam_));
  ++maps_published_;
}

void RatSlamNode::AfterMessage(int64_t utime) {
  if (!first_utime_) first_utime_ = utime;
  const double map_us = config_.experience_map_interval_s * 1e6;
  if (map_us > 0 && slam_ && (!last_map_utime_ || utime - *last_map_utime_ >= map_us || utime < *last_map_utime_)) {
    last_map_utime_ = utime;
    PublishExperienceMap(utime);
  }
  const double stats_us = config_.stats_interval_s * 1e6;
  if (stats_us > 0 && slam_ && (!last_stats_utime_ || utime - *last_stats_utime_ >= stats_us || utime < *last_stats_utime_)) {
    if (last_stats_utime_) PrintStats(log_, utime);
    last_stats_utime_ = utime;
  }
}

void RatSlamNode::PrintStats(std::ostream& out, int64_t utime) const {
  const nav::Pose2 p = slam_->pose();
  out << "ratslam: t+" << (utime - first_utime_.value_or(utime)) * 1e-6 << " s: " << processed_ << " frames, " << slam_->templates() << " templates, "
      << slam_->experience_map().experiences().size() << " experiences, " << slam_->loop_closures()
      << " loop closures, pose (" << p.x_m << ", " << p.y_m << ") m; " << mean_image_ms() << " ms per frame, "
      << mean_odometry_ms() << " ms per odometry\n";
}

void RatSlamNode::Report(std::ostream& out) const {
  out << "ratslam: frames " << frames_ << ", processed " << processed_ << ", odometry " << odometry_
      << ", poses published " << poses_published_ << ", experience maps published " << maps_published_
      << ", rejected " << rejected_total() << ", internal errors " << problems_.internal_errors() << "\n";
  if (slam_) {
    out << "ratslam: " << slam_->templates() << " templates, " << slam_->experience_map().experiences().size()
        << " experiences, " << slam_->experience_map().links().size() << " links, " << slam_->loop_closures()
        << " loop closures; mean " << mean_image_ms() << " ms per frame, " << mean_odometry_ms()
        << " ms per odometry message\n";
  }
  for (const auto& [reason, n] : rejected_) out << "ratslam:   rejected (" << reason << "): " << n << "\n";
  problems_.Report(out);
}

}  // namespace snapnav::processes
