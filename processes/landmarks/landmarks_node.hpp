#pragma once
// landmarks: feature landmarks of omni frames (thesis 4.1-4.3). Each frame (raw catadioptric
// image, unwrapped here, or panorama) yields one landmark_set_t of the configured method:
// vertical lines with R-HOG windows, SIFT or SURF keypoints. Several instances may run side by
// side, one per method, each on its own output channel.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/frame_panoramas.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::processes {

struct LandmarksConfig {
  std::string omni_channel;       // omni_frame_t in (input = raw)
  std::string panorama_channel;   // omni_frame_t in (input = panorama)
  std::string landmarks_channel;  // landmark_set_t out ("%s" replaced by the method in upper case)
  bool raw_input = true;
  nav::PanoramaModel panorama;
  nav::MirrorModel mirror;        // of raw frames without a calibration
  std::string mask_path;          // [mirror] mask: the robot's own parts in raw frames ("": none)
  cv::Mat mask;                   // that mask (image_mask.hpp); no landmark on it
  nav::LandmarkExtractorConfig extractor;

  const std::string& input_channel() const { return raw_input ? omni_channel : panorama_channel; }
  // Reads [channels], [landmarks], [panorama], [mirror], [vline], [sift], [surf]; every key is
  // required, unknown keys and bad values are glue::ConfigError. `method` (if not empty)
  // replaces [landmarks] method before the output channel is named.
  static LandmarksConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix,
                                 const std::string& method = "");
  // The effective configuration, as an INI file FromIni reads back.
  void Print(std::ostream& out) const;
};

class LandmarksNode {
 public:
  LandmarksNode(glue::Bus& bus, const LandmarksConfig& config);
  int64_t frames() const { return frames_; }        // decoded frames on the input channel
  int64_t published() const { return published_; }  // landmark sets (empty ones included)
  int64_t empty_sets() const { return empty_sets_; }
  int64_t landmarks() const { return landmarks_; }  // landmarks published in all
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  int64_t rejected_total() const;
  void Report(std::ostream& out) const;

 private:
  void OnFrame(const omni_frame_t& frame);
  glue::Bus& bus_;
  LandmarksConfig config_;
  glue::FramePanoramas frames_to_panoramas_;
  int64_t frames_ = 0, published_ = 0, empty_sets_ = 0, landmarks_ = 0;
  double seconds_ = 0;  // extraction time, for the report
  std::map<std::string, int64_t> rejected_;
};

}  // namespace snapnav::processes
