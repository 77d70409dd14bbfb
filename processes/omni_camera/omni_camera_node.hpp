#pragma once
// omni-camera: captures raw catadioptric images from a camera device, a video file
// or a folder of images and publishes them as omni_frame_t (kind RAW_OMNI) with the
// mirror calibration.
//
// utime is the wall-clock time at which the frame was captured (glue::WallUtime()),
// for files and folders too: the driver acts as a live source. A recorded log keeps
// those times; the original time of a file's frames is not carried over.

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>

#include "frame_source.hpp"
#include "omni_frame_conversion.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav::processes {

struct OmniCameraConfig {
  std::string frame_channel;
  FrameSourceOptions capture;
  OmniFrameOptions frame;
  std::string mask_path;  // [mirror] mask ("": none): read by the processes that take the frames; checked here

  // Reads [channels], [camera] and [mirror]; every key is required, unknown keys and
  // invalid values are glue::ConfigError naming the file.
  static OmniCameraConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Validate() const;  // throws std::invalid_argument
  void Print(std::ostream& out) const;
};

class OmniCameraNode {
 public:
  enum class StepResult { kPublished, kSkipped, kEnd };
  enum class StopReason { kEndOfSource, kMaxFrames, kShutdown };

  // Opens the source; throws std::runtime_error naming what is missing. Warnings about
  // skipped frames go to `log` (may be null).
  OmniCameraNode(glue::Bus& bus, const OmniCameraConfig& config, std::ostream* log = nullptr);

  // Reads one frame and publishes it. A frame that cannot be read, has another size
  // than expected or fails to convert is counted and skipped; too many in a row
  // (FrameSource::max_consecutive_failures) throw std::runtime_error.
  StepResult Step();
  // Steps until the end of the source, `max_frames` published (0: no limit) or
  // glue::ShutdownRequested(); paces files and folders at rate_hz.
  StopReason Run(int64_t max_frames);

  int64_t published() const { return published_; }
  int64_t read_failures() const { return read_failures_; }
  int64_t size_mismatches() const { return size_mismatches_; }
  int64_t conversion_errors() const { return conversion_errors_; }
  const std::string& source_description() const { return source_description_; }
  // "published N frames on CHANNEL from SOURCE (R unreadable, S wrong size, C not converted)".
  void Report(std::ostream& out) const;

 private:
  StepResult Skip(int64_t* counter, const std::string& reason);

  glue::Bus& bus_;
  OmniCameraConfig config_;
  std::ostream* log_;
  std::unique_ptr<FrameSource> source_;
  std::string source_description_;
  int expected_width_px_ = 0;
  int expected_height_px_ = 0;
  int64_t frames_read_ = 0;
  int64_t published_ = 0;
  int64_t read_failures_ = 0;
  int64_t size_mismatches_ = 0;
  int64_t conversion_errors_ = 0;
  int64_t consecutive_unusable_ = 0;
  std::string last_error_;
};

}  // namespace snapnav::processes
