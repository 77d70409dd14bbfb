#pragma once
// viewer: subscribes to what the other processes publish and keeps the picture's data (a
// ViewerScene): the point map, every pose channel (by a regular expression) with its
// covariance, the ground truth, place-cell matches, the current panorama (OMNI_PANORAMA, or
// OMNI_FRAME unwrapped), landmark sets, the homing vector and the laser scan. It only
// subscribes, so it runs unchanged on a live bus and on file://LOG?speed=0.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/frame_panoramas.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/laser_slam_status_t.hpp"
#include "snapnav/pose_correction_t.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/place_cell_match_t.hpp"
#include "snapnav/occupancy_grid_t.hpp"
#include "snapnav/point_map_t.hpp"
#include "viewer_render.hpp"

namespace snapnav::processes {

struct ViewerConfig {
  // Channels, prefixed. pose_channels and landmark_channels are regular expressions (LCM's,
  // anchored at both ends); the prefix is matched literally.
  std::string channel_prefix;  // the counts panel lists only the channels with this prefix
  std::string point_map_channel, pose_channels, truth_channel, panorama_channel, omni_channel, landmark_channels,
      homing_vector_channel, place_cell_match_channel, scan_channel, grid_channel;
  // laser_slam_status_t: a correction (`corrected`) is a jump of laser_slam_pose_channel's trail;
  // pose_correction_t: the correction of that trail's past (the trail redrawn, joined again).
  std::string laser_slam_status_channel, laser_slam_pose_channel, laser_slam_correction_channel;
  double refresh_hz = 4;              // window refresh [Hz, wall clock]
  double png_interval_s = 5;          // --png: a snapshot per this much message time [s]; 0: at exit only
  // Trajectory thinning: a pose is kept when it is this far from the last kept one, turned this
  // much, or this much later; when a channel has max_poses_per_channel, every other one is dropped.
  double trajectory_min_step_m = 0.02, trajectory_min_turn_rad = 0.05, trajectory_max_gap_s = 1.0;
  int max_poses_per_channel = 20000;
  int max_place_cell_matches = 2000;  // matched cells drawn, the newest
  viewer::RenderOptions render;
  nav::PanoramaModel panorama;  // raw frames are unwrapped into this panorama
  nav::MirrorModel mirror;      // the mirror of raw frames without a calibration
  std::string mask_path;        // [mirror] mask ("": none): masked pixels are filled in the panorama shown
  cv::Mat mask;

  // Reads [channels], [viewer], [panorama] and [mirror]; every key is required, unknown keys and
  // bad values are glue::ConfigError naming the file and line.
  static ViewerConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Validate() const;  // throws std::invalid_argument naming the [section] and key
  // The effective configuration as an INI file FromIni reads back (channels with their prefix).
  void Print(std::ostream& out) const;
};

// `text` with the characters that are special in a regular expression escaped.
std::string RegexEscape(const std::string& text);

class ViewerNode {
 public:
  ViewerNode(glue::Bus& bus, const ViewerConfig& config);

  // Place cells of a memory file, drawn as hollow circles.
  void SetMemoryCells(std::vector<cv::Point2f> cells) { scene_.memory_cells = std::move(cells); }

  // The scene, with the newest frame turned into the panorama (once per new frame) and the
  // message counts of the bus.
  const viewer::ViewerScene& Scene();
  cv::Mat Render() { return viewer::RenderScene(Scene(), config_.render); }

  int64_t first_utime() const { return scene_.first_utime; }
  int64_t latest_utime() const { return scene_.latest_utime; }
  // Messages that decoded but could not be used, by reason ("undecodable image", ...).
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  int64_t rejected_total() const;
  void Report(std::ostream& out) const;

 private:
  void SawUtime(int64_t utime);
  void OnPose(const void* data, size_t size);
  void OnPointMap(const point_map_t& msg);
  void OnGrid(const occupancy_grid_t& msg);
  void OnPanorama(const omni_frame_t& msg);
  void OnOmniFrame(const omni_frame_t& msg);
  void OnLandmarks(const void* data, size_t size);
  void OnHomingVector(const homing_vector_t& msg);
  void OnPlaceCellMatch(const place_cell_match_t& msg);
  void OnScan(const laser_scan_t& msg);
  void OnLaserSlamStatus(const laser_slam_status_t& msg);
  void OnLaserSlamCorrection(const pose_correction_t& msg);
  void Reject(const std::string& reason, const std::string& detail);
  void UpdatePanorama();

  glue::Bus& bus_;
  ViewerConfig config_;
  viewer::ViewerScene scene_;
  glue::FramePanoramas frames_to_panoramas_;
  std::optional<omni_frame_t> pending_frame_;  // newest frame not yet turned into the panorama
  bool have_panorama_channel_ = false;         // OMNI_PANORAMA seen: raw frames are not shown
  std::map<std::string, int64_t> rejected_;
  int64_t jumps_ = 0;  // laser SLAM corrections marked on its trail
  std::optional<glue::PoseCorrections> corrections_;  // the newest table of laser_slam_pose_channel
  int64_t corrected_through_utime_ = 0;  // ... and its scan: a correction announced up to it is joined
};

}  // namespace snapnav::processes
