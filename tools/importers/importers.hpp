#pragma once
// Importers: recorded data -> snapnav LCM messages.
//
//   ImportRawlog   MRPT rawlog (action/sensory-frame pairs or observations only, plain or gzip)
//   ImportCarmen   CARMEN text log (FLASER, ROBOTLASER1, ODOM; plain or gzip for ImportCarmenFile)
//   ImportImages   folder of PNG/JPEG images plus a positions CSV
//
// Each importer writes encoded messages into a Sink (the log-import tool's sink is an LCM log
// file, the tests' sink is a vector) and returns an ImportReport: messages per channel and
// their time span, what was skipped, and every error as "FILE:LINE: reason" (text inputs) or
// "FILE: byte offset N: reason" (rawlogs). Bad input never throws: everything valid before
// (and, for text inputs, after) a bad line is imported and the error is reported.
// Only invalid options and a sink that cannot write throw.
//
// This header has no MRPT, OpenCV or zlib includes (LCM only through glue::LogWriter).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/log_writer.hpp"

namespace lcm {
class LogFile;
}

namespace snapnav::importers {

// Corrected or logged robot poses of a CARMEN log (pose_t, estimator "carmen_log").
inline constexpr char kPoseCarmen[] = "POSE_CARMEN";
inline constexpr char kCarmenEstimator[] = "carmen_log";
inline constexpr char kGroundTruthEstimator[] = "ground_truth";

// Where synthesized time starts when an input has no usable time at all [microseconds].
inline constexpr int64_t kSynthesizedStartUtime = 1'000'000;

// The output channels of every importer.
struct ChannelNames {
  std::string laser_scan = channels::kLaserScan;               // laser_scan_t
  std::string odometry = channels::kOdometry;                  // odometry_t
  std::string omni_frame = channels::kOmniFrame;               // omni_frame_t
  std::string pose_ground_truth = channels::kPoseGroundTruth;  // pose_t of an image folder's CSV
  std::string pose_carmen = kPoseCarmen;                       // pose_t of a CARMEN log

  // The default names with `prefix` prepended to each.
  static ChannelNames WithPrefix(const std::string& prefix);
};

// Receives the imported messages in input order.
class Sink {
 public:
  virtual ~Sink() = default;
  // `payload` is an encoded LCM message; `utime` [microseconds] is its sensor time.
  virtual void Write(const std::string& channel, int64_t utime, const std::string& payload) = 0;
};

// Writes every message as one event of an LCM log file (event timestamp = utime).
class LcmLogSink : public Sink {
 public:
  // Creates (truncates) `path`. Throws std::runtime_error if it cannot.
  explicit LcmLogSink(const std::string& path);
  ~LcmLogSink() override;
  void Write(const std::string& channel, int64_t utime, const std::string& payload) override;
  // Flushes and closes the file; throws std::runtime_error if the data did not reach it.
  void Close();

 private:
  glue::LogWriter log_;
};

struct ChannelStats {
  int64_t count = 0;
  int64_t first_utime = 0;  // [microseconds]
  int64_t last_utime = 0;   // [microseconds]
  // laser_scan_t channels: for checking units and consistency.
  int32_t min_beams = 0;
  int32_t max_beams = 0;
  int64_t readings = 0;
  int64_t no_returns = 0;  // readings at or above the scan's range_max_m
  float min_return_m = 0;  // shortest reading below range_max_m [m]
  float max_return_m = 0;  // longest reading below range_max_m [m]
  float max_range_m = 0;   // largest range_max_m declared [m]
  // odometry_t and pose_t channels.
  double path_length_m = 0;  // sum of the distances between consecutive positions [m]
};

// Only this many error messages are kept; error_count counts all of them.
inline constexpr size_t kMaxStoredErrors = 100;

struct ImportReport {
  std::string input;                             // the file or folder imported
  std::map<std::string, ChannelStats> channels;  // messages written, per channel
  std::map<std::string, int64_t> skipped;        // inputs not converted, by kind (message type, class)
  int64_t comment_lines = 0;                     // text inputs: '#' lines
  int64_t error_count = 0;                       // malformed lines, corrupt data, unreadable files
  std::vector<std::string> errors;               // the first kMaxStoredErrors, "FILE:LINE: reason"
  std::vector<std::string> notes;                // decisions the user should know about
  int64_t synthesized_utimes = 0;                // messages whose time was synthesized
  int64_t out_of_order = 0;                      // messages whose utime is before the previous one's

  bool ok() const { return error_count == 0; }
  int64_t Count(const std::string& channel) const;
  int64_t TotalMessages() const;
  int64_t TotalSkipped() const;
  void AddError(std::string message);
};

// Human-readable summary: counts per channel, time span, skipped kinds, notes, errors.
void PrintSummary(const ImportReport& report, std::ostream& out);

struct Progress {
  int64_t done = 0;   // units processed so far
  int64_t total = 0;  // 0 if unknown
  std::string unit;   // "bytes", "rows"
};
using ProgressFn = std::function<void(const Progress&)>;

// Where message times come from in a CARMEN log.
enum class TimeSource {
  kAuto,        // the log's timestamps if usable (> 0, strictly increasing per stream), else synthesized
  kLog,         // the log's timestamps as they are
  kSynthesize,  // one message line every 1/rate_hz seconds
};
TimeSource ParseTimeSource(const std::string& text);  // "auto" | "log" | "synthesize"; throws std::invalid_argument
std::string ToString(TimeSource source);

// ---------------------------------------------------------------- CARMEN
// SICK scanners report "no return" as 81.91 m; CARMEN logs keep that value.
inline constexpr double kCarmenNoReturnThresholdM = 81.9;  // a reading at or above this is no return
inline constexpr double kCarmenDefaultMaxRangeM = 81.91;   // range_max_m written for FLASER scans

struct CarmenOptions {
  ChannelNames channels;
  double flaser_fov_deg = 180.0;                        // FLASER field of view, centred ahead [deg]
  double flaser_max_range_m = kCarmenDefaultMaxRangeM;  // FLASER range_max_m; readings at or above: no return [m]
  TimeSource time_source = TimeSource::kAuto;
  double rate_hz = 10.0;    // synthesized time: message lines per second [Hz]
  int64_t total_bytes = 0;  // input size for progress reports [bytes]; 0 if unknown
  ProgressFn progress;      // called every progress_every_bytes
  int64_t progress_every_bytes = 1 << 20;

  void Validate() const;  // throws std::invalid_argument
};

// Parses a CARMEN log from `in`; `name` names it in errors ("name:LINE: reason").
// Holds the parsed lines in memory (about the size of the text) to decide, before writing,
// where odometry and time come from.
ImportReport ImportCarmen(std::istream& in, const std::string& name, Sink& sink, const CarmenOptions& options);
// Same for a file, plain or gzip-compressed (detected by content). A truncated or corrupt gzip
// stream is an error naming the file.
ImportReport ImportCarmenFile(const std::string& path, Sink& sink, const CarmenOptions& options);

// ---------------------------------------------------------------- MRPT rawlog
struct RawlogOptions {
  ChannelNames channels;
  double rate_hz = 10.0;  // an entry without timestamp gets the previous time + 1/rate_hz [Hz]
  // MRPT's deserializers trust the counts in the file (a corrupt beam count makes
  // CObservation2DRangeScan allocate and zero gigabytes, or write through a null pointer when
  // that fails). So MRPT reads the file in a child process whose address space may grow by at
  // most this much; if it fails or dies, the import stops there with an error naming the byte
  // offset, and this process keeps everything converted before [bytes].
  size_t reader_memory_limit_bytes = size_t{1} << 30;
  bool isolate_reader = true;  // false: read in this process, without the limit (for debugging)
  ProgressFn progress;         // called every progress_every_objects objects
  int64_t progress_every_objects = 500;

  void Validate() const;  // throws std::invalid_argument
};

ImportReport ImportRawlog(const std::string& path, Sink& sink, const RawlogOptions& options);

// ---------------------------------------------------------------- image folder
struct ImageOptions {
  ChannelNames channels;
  std::string sensor_name = "omni";
  bool panorama = false;  // frames are unwrapped panoramas (else raw catadioptric images)
  // Mirror calibration of raw images (see omni_frame_t); must stay 0 for panoramas.
  double mirror_center_x_px = 0.0;
  double mirror_center_y_px = 0.0;
  double mirror_inner_radius_px = 0.0;
  double mirror_outer_radius_px = 0.0;
  double mirror_elevation_inner_rad = 0.0;  // elevation seen at the inner radius [rad]
  double mirror_elevation_outer_rad = 0.0;  // elevation seen at the outer radius [rad]
  // Panorama geometry (see omni_frame_t); must stay 0 for raw images.
  double bearing_col0_rad = 0.0;              // bearing of column 0 [rad]
  double elevation_top_rad = 0.0;             // elevation of row 0 [rad]
  double elevation_bottom_rad = 0.0;          // elevation of the last row [rad]
  double rate_hz = 10.0;                      // synthesized time when the CSV has no utime column [Hz]
  size_t max_image_bytes = size_t{64} << 20;  // larger files are errors [bytes]
  ProgressFn progress;                        // called every progress_every_rows rows
  int64_t progress_every_rows = 100;

  void Validate() const;  // throws std::invalid_argument
};

// `positions_csv`: header line naming the columns file, x_m, y_m, heading_rad and optionally
// utime [microseconds]; `file` is relative to `folder` unless absolute.
ImportReport ImportImages(const std::string& folder, const std::string& positions_csv, Sink& sink,
                          const ImageOptions& options);

}  // namespace snapnav::importers
