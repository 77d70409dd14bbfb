#pragma once
// homing: snapshot homing (thesis chapters 3 and 4). Omni frames (raw catadioptric images,
// unwrapped here, or panoramas) are compared with a home snapshot by HOG homing; or landmark
// sets (from the landmarks process: vertical lines, SIFT, SURF) are matched with a home set and
// homed by the landmark ALV. Each input yields one homing_vector_t once a home is set.

#include <cmath>
#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/frame_panoramas.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/nav/homing/hog_homing.hpp"
#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/homing/unwrap.hpp"
#include "snapnav/nav/landmarks/view_fusion.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::processes {

enum class HomingInput { kRaw, kPanorama, kLandmarks };  // which channel the input comes from
enum class HomeSource { kMessage, kImage, kFirst };  // how the home snapshot is set at first

// Several frames of one view fused into one ([view_fusion]; snapnav's improvement for people
// walking through the views). A frame is taken when at least the interval has passed since the
// last one taken; the last N taken are fused, and a gap of more than N intervals starts afresh.
// The home from home_frames frames / sets (home = first: the first ones, no vectors until it is
// complete; home = message: the last ones on the home channel); each current view from the last
// current_frames (a robot that pauses to look).
struct ViewFusionConfig {
  int home_frames = 1;
  double home_interval_s = 1.0;
  int current_frames = 1;
  double current_interval_s = 0.5;
  // Landmark sets are fused by persistence; frames (HOG) by their median panorama. `median`
  // for landmark methods (landmarks of the median panorama) needs the frames: eval-homing only.
  nav::ViewFusion mode = nav::ViewFusion::kPersistent;
  nav::PersistenceOptions persistence;
};

struct HomingConfig {
  std::string omni_channel;           // omni_frame_t in (input = raw)
  std::string panorama_channel;       // omni_frame_t in (input = panorama)
  std::string home_snapshot_channel;  // omni_frame_t in: replaces the home
  std::string homing_vector_channel;  // homing_vector_t out
  std::string landmarks_channel;      // landmark_set_t in (input = landmarks)
  std::string home_landmarks_channel; // landmark_set_t in: replaces the home set
  HomingInput input = HomingInput::kRaw;
  HomeSource home = HomeSource::kMessage;
  std::string home_image;       // home = image: the file (resolved against the config's folder)
  bool home_image_raw = true;   // home_image holds a raw catadioptric image (else a panorama)
  nav::PanoramaModel panorama;  // every frame is turned into this panorama
  nav::MirrorModel mirror;      // of home_image, and of raw frames without a calibration
  std::string mask_path;        // [mirror] mask: the robot's own parts in raw frames ("": none)
  cv::Mat mask;                 // that mask (image_mask.hpp): left out of the HOG cells
  nav::HogHomingConfig homing;
  // Landmark homing ([matching] for SIFT and SURF, [vline_matching] for vertical lines, [landmark_alv]).
  nav::LandmarkHomingConfig keypoint_homing, vline_homing;
  ViewFusionConfig fusion;
  const nav::LandmarkHomingConfig& landmark_homing(nav::LandmarkMethod m) const {
    return m == nav::LandmarkMethod::kVline ? vline_homing : keypoint_homing;
  }

  // The channel the node takes frames from.
  const std::string& input_channel() const {
    return input == HomingInput::kRaw ? omni_channel : input == HomingInput::kPanorama ? panorama_channel : landmarks_channel;
  }

  // Reads [channels], [homing], [panorama], [mirror], [hog], [compass], [alv], [preprocess],
  // [matching], [vline_matching], [landmark_alv] and [view_fusion];
  // every key is required, unknown keys and invalid values are glue::ConfigError.
  static HomingConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  // Throws glue::ConfigError (naming `origin`) when the options do not fit together.
  void Validate() const;  // throws std::invalid_argument naming the [section] and key
  // The effective configuration, as an INI file FromIni reads back (channels with their prefix).
  void Print(std::ostream& out) const;
};

// Frames (or landmark sets) of one still view, for [view_fusion]: an item is taken when at
// least `interval_s` has passed since the last one taken (every item when n = 1); the last n
// taken are kept; a gap of more than n intervals, or time running backwards, starts afresh.
template <class T>
class FrameBuffer {
 public:
  FrameBuffer(int n, double interval_s) : n_(n), interval_us_(static_cast<int64_t>(std::llround(interval_s * 1e6))) {}
  // Whether `item` was taken.
  bool Offer(int64_t utime, T item) {
    if (!items_.empty()) {
      const int64_t dt = utime - last_utime_;
      if (dt < 0 || dt > interval_us_ * n_) {
        items_.clear();
      } else if (n_ > 1 && dt < interval_us_) {
        return false;
      }
    }
    items_.push_back(std::move(item));
    if (static_cast<int>(items_.size()) > n_) items_.erase(items_.begin());
    last_utime_ = utime;
    return true;
  }
  bool full() const { return static_cast<int>(items_.size()) >= n_; }
  const std::vector<T>& items() const { return items_; }
  void Clear() { items_.clear(); }

 private:
  int n_;
  int64_t interval_us_;
  int64_t last_utime_ = 0;
  std::vector<T> items_;
};

// The image file `path` as a panorama of config.panorama (a raw image is unwrapped with
// config.mirror). Throws std::runtime_error naming the file when it is missing, unreadable or
// does not fit.
cv::Mat LoadHomeImage(const std::string& path, bool raw, const HomingConfig& config);

class HomingNode {
 public:
  // Subscribes to the input and home-snapshot channels; with home = image loads the home image
  // (throws std::runtime_error naming the file when it cannot be used).
  HomingNode(glue::Bus& bus, const HomingConfig& config);

  bool has_home() const { return homer_.has_home() || (landmark_homer_ && landmark_homer_->has_home()); }
  int64_t frames() const { return frames_; }            // decoded frames / landmark sets on the input channel
  int64_t before_home() const { return before_home_; }  // frames that arrived before any home
  int64_t homes_set() const { return homes_set_; }
  // Landmarks of the home set (input = landmarks; 0 without one).
  int home_landmarks() const { return landmark_homer_ && landmark_homer_->has_home() ? landmark_homer_->home().size() : 0; }
  int64_t published() const { return published_valid_ + published_invalid_; }
  int64_t published_valid() const { return published_valid_; }
  int64_t published_invalid() const { return published_invalid_; }  // no estimate (valid = false)
  // Input frames not taken into the fused current view (closer than current_interval_s to the last one).
  int64_t between_fused_frames() const { return between_fused_frames_; }
  int64_t unwrapper_builds() const { return frames_to_panoramas_.unwrapper_builds(); }    // once per mirror calibration / size
  // Frames (input and home snapshots) skipped, by reason ("wrong size", "undecodable image", ...).
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  int64_t rejected_total() const;
  // The node's counts, one line each.
  void Report(std::ostream& out) const;

 private:
  void OnFrame(const omni_frame_t& frame);
  void OnHomeSnapshot(const omni_frame_t& frame);
  void OnLandmarks(const landmark_set_t& msg);
  void OnHomeLandmarks(const landmark_set_t& msg);
  // The message as a landmark set; nullopt when it is rejected (counted).
  std::optional<nav::LandmarkSet> ToLandmarks(const landmark_set_t& msg);
  void PublishVector(int64_t utime, int8_t method, const std::string& variant,
                     std::optional<nav::HomingEstimate> estimate);
  // The frame as a panorama of config_.panorama; nullopt when it is rejected (counted).
  std::optional<cv::Mat> ToPanorama(const omni_frame_t& frame);
  void Reject(const std::string& reason, const std::string& detail);
  void SetHome(const cv::Mat& panorama);
  // The fused landmark set of a buffer (persistence).
  nav::LandmarkSet Fuse(const std::vector<nav::LandmarkSet>& sets) const;
  void SetHomeLandmarks(nav::LandmarkSet set);

  glue::Bus& bus_;
  HomingConfig config_;
  nav::HogHomer homer_;
  std::optional<nav::LandmarkHomer> landmark_homer_;  // made for the home set's method
  glue::FramePanoramas frames_to_panoramas_;
  const uint8_t* mask_data_ = nullptr;  // the panorama mask the HOG homer has
  int64_t frames_ = 0, before_home_ = 0, homes_set_ = 0;
  int64_t published_valid_ = 0, published_invalid_ = 0, between_fused_frames_ = 0;
  // [view_fusion]: the frames of the home and current views (HOG: median panorama; landmark
  // sets: persistent landmarks).
  FrameBuffer<cv::Mat> home_frames_, current_frames_;
  FrameBuffer<nav::LandmarkSet> home_sets_, current_sets_;
  std::map<std::string, int64_t> rejected_;
};

}  // namespace snapnav::processes
