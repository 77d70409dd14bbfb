#pragma once
// Where omni-camera's images come from: a V4L2 camera device, a video file, or a
// folder of image files, all read with OpenCV.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace snapnav::processes {

enum class SourceKind { kDevice, kVideoFile, kImageFolder };

struct FrameSourceSpec {
  SourceKind kind = SourceKind::kDevice;
  int device_index = 0;  // kDevice: N of /dev/videoN
  std::string path;      // kVideoFile, kImageFolder (relative to the working directory)

  // "device:N", "file:PATH" or "folder:PATH"; throws std::invalid_argument.
  static FrameSourceSpec Parse(const std::string& text);
  std::string ToString() const;
};

struct FrameSourceOptions {
  FrameSourceSpec source;
  // Expected frame size [pixels]; a device is asked for it. 0 x 0: whatever the first frame has.
  int width_px = 0;
  int height_px = 0;
  // File/folder: publish rate (0: as fast as possible). Device: frame rate asked of the
  // camera (0: its default); the camera sets the pace.
  double rate_hz = 0;
  bool loop = false;  // file/folder: start again at the end

  void Validate() const;  // throws std::invalid_argument
};

enum class ReadStatus {
  kFrame,   // *image holds the next frame
  kFailed,  // this frame could not be read (*error says why); the next may work
  kEnd,     // no more frames (end of a file or folder without loop)
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual ReadStatus Read(cv::Mat* image, std::string* error) = 0;
  // E.g. "camera device 0 (/dev/video0)", "video file x.avi", "image folder imgs/ (12 images)".
  virtual std::string description() const = 0;
  // A device sets its own pace; files and folders are paced by rate_hz.
  virtual bool is_device() const = 0;
  // Unusable frames in a row after which the source is considered broken (for a
  // folder: every image of one pass).
  virtual int64_t max_consecutive_failures() const = 0;
};

// Opens the source. Throws std::runtime_error naming exactly what is missing, e.g.
// "cannot open camera device 0 (/dev/video0 does not exist)".
std::unique_ptr<FrameSource> OpenFrameSource(const FrameSourceOptions& options);

// The image files (png, jpg, jpeg, bmp, pgm; any letter case) directly in `folder`,
// sorted by file name. Throws std::runtime_error when the folder does not exist.
std::vector<std::string> ListImageFiles(const std::string& folder);

}  // namespace snapnav::processes
