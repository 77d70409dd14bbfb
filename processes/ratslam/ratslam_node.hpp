#pragma once
// ratslam: libnav's RatSLAM (Milford and Wyeth 2010, as OpenRatSLAM) on the bus. OMNI_FRAME (raw
// catadioptric frames, unwrapped with the shared frame -> panorama conversion, or panoramas) and
// ODOMETRY in; POSE_RATSLAM (pose_t, estimator "ratslam") on every processed frame and/or odometry
// message with the input's utime, and the experience map (experience_map_t) on EXPERIENCE_MAP every
// experience_map_interval_s of message time.
//
// Frames: the first odometry message only fixes the start (its increment is relative to a message
// never seen): the experience map's frame is the odometry frame at the start, so POSE_RATSLAM is
// comparable with POSE_DEAD_RECKONING and, in the simulator, with the ground truth. A frame before
// any odometry starts RatSLAM at the origin instead. Messages are processed in arrival order.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/handler_problems.hpp"
#include "snapnav/glue/frame_panoramas.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/ratslam_options.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/ratslam/ratslam.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav {
struct experience_map_t;
}

namespace snapnav::processes {

// The experience map as a message (estimator "ratslam", frame "map").
experience_map_t ToExperienceMapMsg(int64_t utime, const nav::RatSlam& slam);

enum class RatSlamPoseOn { kFrame, kOdometry, kBoth };
const char* RatSlamPoseOnName(RatSlamPoseOn p);  // "frame", "odometry", "both"

struct RatSlamConfig {
  std::string omni_channel;            // omni_frame_t in (input = raw)
  std::string panorama_channel;        // omni_frame_t in (input = panorama)
  std::string odometry_channel;        // odometry_t in
  std::string pose_channel;            // pose_t out
  std::string experience_map_channel;  // experience_map_t out
  bool raw_input = true;
  RatSlamPoseOn pose_on = RatSlamPoseOn::kFrame;
  double experience_map_interval_s = 1.0;  // message time between experience maps [s]; 0: never
  double stats_interval_s = 10;            // a stats line every this much message time [s]; 0: none
  nav::PanoramaModel panorama;             // every frame becomes a panorama of this model
  nav::MirrorModel mirror;                 // of raw frames without a calibration
  std::string mask_path;                   // [mirror] mask: the robot's own parts in raw frames ("": none)
  cv::Mat mask;                            // that mask (image_mask.hpp): left out of the view templates
  nav::RatSlamOptions options;

  const std::string& input_channel() const { return raw_input ? omni_channel : panorama_channel; }
  // Reads [channels], [node], [panorama], [mirror] and [ratslam]; every key is required, unknown
  // keys and invalid values are glue::ConfigError naming the file.
  static RatSlamConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  // The effective configuration, as an INI file FromIni reads back (channels with their prefix).
  void Print(std::ostream& out) const;
};

class RatSlamNode {
 public:
  // Subscribes to the input and odometry channels. Throws std::invalid_argument for options
  // libnav refuses. Stats lines go to `log`.
  RatSlamNode(glue::Bus& bus, const RatSlamConfig& config, std::ostream& log);

  int64_t frames() const { return frames_; }        // decoded frames on the input channel
  int64_t processed() const { return processed_; }  // frames given to RatSlam::OnImage
  int64_t odometry() const { return odometry_; }    // decoded odometry messages
  int64_t poses_published() const { return poses_published_; }
  int64_t maps_published() const { return maps_published_; }
  // Malformed input (frames, odometry), by reason ("wrong size", "non-finite odometry", ...).
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  int64_t rejected(const std::string& reason) const;
  int64_t rejected_total() const;
  int64_t internal_errors() const { return problems_.internal_errors(); }
  // Mean wall time per RatSlam::OnImage and per OnOdometry [ms] (statistics only).
  double mean_image_ms() const { return processed_ > 0 ? image_ms_ / static_cast<double>(processed_) : 0.0; }
  double mean_odometry_ms() const { return steps_ > 0 ? odometry_ms_ / static_cast<double>(steps_) : 0.0; }
  // RatSLAM; nullptr before the first usable message.
  const nav::RatSlam* slam() const { return slam_ ? &*slam_ : nullptr; }
  // Publishes the experience map now (also done every experience_map_interval_s).
  void PublishExperienceMap(int64_t utime);
  void Report(std::ostream& out) const;

 private:
  void OnFrame(const omni_frame_t& frame);
  void OnOdometry(const odometry_t& msg);
  void HandleFrame(const omni_frame_t& frame);
  void HandleOdometry(const odometry_t& msg);
  void Reject(const std::string& reason, const std::string& detail);
  void PublishPose(int64_t utime);
  void AfterMessage(int64_t utime);  // experience map and stats when due
  void PrintStats(std::ostream& out, int64_t utime) const;

  glue::Bus& bus_;
  RatSlamConfig config_;
  std::ostream& log_;
  glue::FramePanoramas frames_to_panoramas_;
  std::optional<nav::RatSlam> slam_;
  bool odometry_seen_ = false;
  std::optional<int64_t> last_map_utime_, last_stats_utime_, first_utime_;
  int64_t frames_ = 0, processed_ = 0, odometry_ = 0, steps_ = 0;
  int64_t poses_published_ = 0, maps_published_ = 0;
  double image_ms_ = 0, odometry_ms_ = 0;
  std::map<std::string, int64_t> rejected_;
  glue::HandlerProblems problems_;  // internal errors (rejected messages are counted in rejected_)
  cv::Mat gray_;
};

}  // namespace snapnav::processes
