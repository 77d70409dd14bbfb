#pragma once
// placecells: place-cell memory and localization (thesis 4.4, 5.1, 5.2). Omni frames (raw
// catadioptric images, unwrapped here, or panoramas) become views of places.
//   explore   a view unlike every stored cell (novelty above a threshold) becomes a new cell at
//             the pose of the explore pose channel (ground truth, dead reckoning, laser SLAM);
//             the memory file is written every N new cells and on exit.
//   localize  the memory file is loaded at start; each processed view is compared with it (the
//             distance filter uses the last fix moved by odometry) and the best cell
//             (place_cell_match_t) and the pose estimate (pose_t) are published.
// Frames are processed at most every min_interval_s of message time or min_travel_m of odometry.

#include <cstdint>
#include <deque>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/frame_panoramas.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/pose_correction_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {

enum class PlaceCellsMode { kExplore, kLocalize };
const char* PlaceCellsModeName(PlaceCellsMode mode);  // "explore", "localize"

struct PlaceCellsConfig {
  std::string omni_channel;          // omni_frame_t in (input = raw)
  std::string panorama_channel;      // omni_frame_t in (input = panorama)
  std::string odometry_channel;      // odometry_t in: motion between localizations, travel
  std::string explore_pose_channel;  // pose_t in (explore): where each new cell is
  std::string explore_correction_channel;  // pose_correction_t in (explore): corrections of those poses
  std::string match_channel;         // place_cell_match_t out
  std::string pose_channel;          // pose_t out (localize)
  bool raw_input = true;
  PlaceCellsMode mode = PlaceCellsMode::kLocalize;
  std::string memory_file;           // relative paths: to the working folder
  double novelty_threshold = 0.1;    // explore: measure units (rad for bearing and vline, fraction for count)
  int save_every_cells = 10;         // explore: write the file every N new cells; 0: on exit only
  double explore_pose_max_age_s = 0.2;  // explore: the pose nearest the frame's utime must be this close [s]
  double min_interval_s = 0.5;       // process a frame once this much message time has passed ...
  double min_travel_m = 0.1;         // ... or the odometry has travelled this far (each: 0 = off; both 0: every frame)
  double stats_interval_s = 10;      // a stats line every this much message time [s]; 0: none
  nav::PanoramaModel panorama;
  nav::MirrorModel mirror;           // of raw frames without a calibration
  std::string mask_path;             // [mirror] mask: the robot's own parts in raw frames ("": none)
  cv::Mat mask;                      // that mask (image_mask.hpp): no landmark on it
  nav::PlaceViewOptions view;        // of a new memory (a loaded memory keeps its own)
  nav::LocalizerOptions localizer;
  nav::VocabularyOptions vocabulary;

  const std::string& input_channel() const { return raw_input ? omni_channel : panorama_channel; }
  // Reads [channels], [placecells], [panorama], [mirror], [landmarks], [vline], [sift], [surf],
  // [place_view], [matching], [measure], [distance_filter], [localizer], [vocabulary]; every key
  // is required, unknown keys and invalid values are glue::ConfigError.
  static PlaceCellsConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  // Throws glue::ConfigError (naming `origin`) when the options do not fit together.
  void Validate() const;  // throws std::invalid_argument naming the [section] and key
  // The effective configuration, as an INI file FromIni reads back (channels with their prefix).
  void Print(std::ostream& out) const;
};

class PlaceCellsNode {
 public:
  // Subscribes to the input, odometry and (explore) pose channels. Localize: loads the memory
  // file (glue::PlaceMemoryError naming the file when it is missing or not a memory). Explore:
  // extends the memory file when it exists (same errors), else starts an empty memory. A loaded
  // memory whose panorama differs from the config's is refused (std::runtime_error).
  // Progress lines (loading, saving, periodic stats) go to `log`.
  PlaceCellsNode(glue::Bus& bus, const PlaceCellsConfig& config, std::ostream& log);

  // Explore: writes the memory file when cells were added since it was last written. Returns
  // whether it wrote.
  bool Save();
  // When the bus stops (glue::RunNode), also on an error: Save(), so nothing explored is lost.
  void Finish() { Save(); }

  const nav::PlaceCellMemory& memory() const { return memory_; }
  int64_t frames() const { return frames_; }        // decoded frames on the input channel
  int64_t processed() const { return processed_; }  // views made and compared
  int64_t new_cells() const { return new_cells_; }  // explore: cells added by this run
  int64_t localized() const { return localized_; }  // localize: matches with a cell
  int64_t not_localized() const { return not_localized_; }
  int64_t saves() const { return saves_; }
  // Explore: correction tables of the explore pose channel taken, and cell moves they made.
  int64_t corrections() const { return corrections_.tables(); }
  int64_t cells_moved() const { return cells_moved_; }
  // Frames not processed by choice, by reason ("rate limit", "no explore pose").
  const std::map<std::string, int64_t>& skipped() const { return skipped_; }
  // Malformed input (frames, odometry, poses) and processing errors, by reason.
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  int64_t rejected_total() const;
  // The node's counts, one line each.
  void Report(std::ostream& out) const;

 private:
  struct StampedPose {
    int64_t utime;
    nav::Pose2 pose;
  };
  void OnFrame(const omni_frame_t& frame);
  void OnOdometry(const odometry_t& msg);
  void OnExplorePose(const pose_t& msg);
  void OnExploreCorrection(const pose_correction_t& msg);
  void Reject(const std::string& reason, const std::string& detail);
  bool RateAllows(int64_t utime) const;
  std::optional<StampedPose> ExplorePoseAt(int64_t utime) const;
  std::optional<nav::Pose2> Prediction() const;
  void Explore(const cv::Mat& panorama, int64_t utime, const StampedPose& pose);
  void Localize(const cv::Mat& panorama, int64_t utime);
  void MaybePrintStats(int64_t utime);
  void PrintStats(std::ostream& out, int64_t utime) const;

  glue::Bus& bus_;
  PlaceCellsConfig config_;
  std::ostream& log_;
  nav::PlaceCellMemory memory_;
  glue::FramePanoramas frames_to_panoramas_;
  // Odometry: the last cumulative pose, the distance travelled since the last processed frame.
  std::optional<nav::Pose2> odometry_;
  double travel_since_processed_m_ = 0;
  std::optional<int64_t> last_processed_utime_;
  // Localize: the last fix and the odometry pose at that time.
  std::optional<nav::Pose2> fix_;
  std::optional<nav::Pose2> odometry_at_fix_;
  std::deque<StampedPose> explore_poses_;  // explore: recent poses as received, oldest first
  // Explore: the cells this run added, each with its pose as received (the corrections apply to it).
  struct ExploredCell {
    int index;
    StampedPose received;
  };
  std::vector<ExploredCell> explored_;
  glue::PoseCorrections corrections_;      // the newest table of the explore pose channel
  int64_t cells_moved_ = 0;
  bool moved_since_save_ = false;
  std::optional<int64_t> stats_utime_;     // message time of the last stats line
  int64_t frames_ = 0, processed_ = 0, new_cells_ = 0, localized_ = 0, not_localized_ = 0, saves_ = 0;
  int64_t unsaved_cells_ = 0;
  double seconds_ = 0;  // processing time (view + compare), for the report
  std::map<std::string, int64_t> skipped_, rejected_;
};

}  // namespace snapnav::processes
