#include "frame_source.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

namespace snapnav::processes {
namespace {

namespace fs = std::filesystem;

// A device that delivers no usable frame this many times in a row is considered lost.
constexpr int64_t kDeviceMaxConsecutiveFailures = 30;
// A video file whose frames keep failing the size check this many times in a row is rejected.
constexpr int64_t kVideoMaxConsecutiveFailures = 30;

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsImageFile(const fs::path& path) {
  const std::string ext = Lower(path.extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".pgm";
}

class DeviceSource : public FrameSource {
 public:
  explicit DeviceSource(const FrameSourceOptions& options) : index_(options.source.device_index) {
    const std::string node = "/dev/video" + std::to_string(index_);
    description_ = "camera device " + std::to_string(index_) + " (" + node + ")";
    const std::string prefix = "cannot open camera device " + std::to_string(index_) + " (";
    struct stat st {};
    if (stat(node.c_str(), &st) != 0) {
      if (errno == ENOENT) throw std::runtime_error(prefix + node + " does not exist)");
      throw std::runtime_error(prefix + node + ": " + std::strerror(errno) + ")");
    }
    if (!S_ISCHR(st.st_mode)) throw std::runtime_error(prefix + node + " is not a device)");
    if (access(node.c_str(), R_OK | W_OK) != 0) {
      throw std::runtime_error(prefix + "permission denied on " + node +
                               ": add your user to the 'video' group and log in again)");
    }
    if (!capture_.open(index_, cv::CAP_V4L2)) {
      throw std::runtime_error(prefix + node +
                               " exists but OpenCV's V4L2 backend cannot open it: is it a capture device, "
                               "or in use by another program?)");
    }
    if (options.width_px > 0) {
      capture_.set(cv::CAP_PROP_FRAME_WIDTH, options.width_px);
      capture_.set(cv::CAP_PROP_FRAME_HEIGHT, options.height_px);
    }
    if (options.rate_hz > 0) capture_.set(cv::CAP_PROP_FPS, options.rate_hz);
  }

  ReadStatus Read(cv::Mat* image, std::string* error) override {
    if (capture_.read(*image) && !image->empty()) return ReadStatus::kFrame;
    *error = description_ + " delivered no frame";
    return ReadStatus::kFailed;
  }
  std::string description() const override { return description_; }
  bool is_device() const override { return true; }
  int64_t max_consecutive_failures() const override { return kDeviceMaxConsecutiveFailures; }

 private:
  int index_;
  std::string description_;
  cv::VideoCapture capture_;
};

class VideoFileSource : public FrameSource {
 public:
  explicit VideoFileSource(const FrameSourceOptions& options) : path_(options.source.path), loop_(options.loop) {
    description_ = "video file " + path_;
    const std::string prefix = "cannot open video file " + path_ + " (";
    std::error_code ec;
    const auto status = fs::status(path_, ec);
    if (!fs::exists(status)) throw std::runtime_error(prefix + "file does not exist)");
    if (fs::is_directory(status)) {
      throw std::runtime_error(prefix + "it is a folder; use source = folder:" + path_ + " for a folder of images)");
    }
    if (access(path_.c_str(), R_OK) != 0)
      throw std::runtime_error(prefix + "not readable: " + std::strerror(errno) + ")");
    if (!Open()) throw std::runtime_error(prefix + "OpenCV's FFmpeg backend cannot decode it)");
    // Read the first frame now so a file without a decodable frame fails at start-up.
    if (!capture_.read(pending_) || pending_.empty()) {
      throw std::runtime_error(prefix + "opened, but not one frame could be decoded)");
    }
  }

  ReadStatus Read(cv::Mat* image, std::string*) override {
    if (!pending_.empty()) {
      *image = pending_;
      pending_.release();
      return ReadStatus::kFrame;
    }
    if (capture_.read(*image) && !image->empty()) return ReadStatus::kFrame;
    // OpenCV does not tell the end of the file from a frame it cannot decode: both end the pass.
    if (!loop_) return ReadStatus::kEnd;
    if (Open() && capture_.read(*image) && !image->empty()) return ReadStatus::kFrame;
    return ReadStatus::kEnd;
  }
  std::string description() const override { return description_; }
  bool is_device() const override { return false; }
  int64_t max_consecutive_failures() const override { return kVideoMaxConsecutiveFailures; }

 private:
  bool Open() { return capture_.open(path_, cv::CAP_FFMPEG) && capture_.isOpened(); }

  std::string path_;
  bool loop_;
  std::string description_;
  cv::VideoCapture capture_;
  cv::Mat pending_;
};

class ImageFolderSource : public FrameSource {
 public:
  explicit ImageFolderSource(const FrameSourceOptions& options) : loop_(options.loop) {
    files_ = ListImageFiles(options.source.path);
    if (files_.empty()) {
      throw std::runtime_error("image folder " + options.source.path +
                               " contains no images (*.png, *.jpg, *.jpeg, *.bmp, *.pgm)");
    }
    description_ = "image folder " + options.source.path + " (" + std::to_string(files_.size()) + " images)";
  }

  ReadStatus Read(cv::Mat* image, std::string* error) override {
    if (next_ == files_.size()) {
      if (!loop_) return ReadStatus::kEnd;
      next_ = 0;
    }
    const std::string& file = files_[next_++];
    // Gray stays gray, colour becomes 8-bit BGR, alpha and 16-bit depth are dropped.
    *image = cv::imread(file, cv::IMREAD_ANYCOLOR);
    if (image->empty()) {
      *error = "cannot read image " + file;
      return ReadStatus::kFailed;
    }
    return ReadStatus::kFrame;
  }
  std::string description() const override { return description_; }
  bool is_device() const override { return false; }
  int64_t max_consecutive_failures() const override { return static_cast<int64_t>(files_.size()); }

 private:
  bool loop_;
  std::vector<std::string> files_;
  size_t next_ = 0;
  std::string description_;
};

}  // namespace

FrameSourceSpec FrameSourceSpec::Parse(const std::string& text) {
  FrameSourceSpec spec;
  const auto colon = text.find(':');
  const std::string kind = colon == std::string::npos ? text : text.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : text.substr(colon + 1);
  const std::string expected = " (expected device:N, file:PATH or folder:PATH)";
  if (kind == "device") {
    spec.kind = SourceKind::kDevice;
    char* end = nullptr;
    errno = 0;
    const long index = std::strtol(rest.c_str(), &end, 10);
    if (rest.empty() || *end != '\0' || errno == ERANGE || index < 0 || index > 1024) {
      throw std::invalid_argument("bad camera device index '" + rest + "' in source '" + text + "'" + expected);
    }
    spec.device_index = static_cast<int>(index);
  } else if (kind == "file" || kind == "folder") {
    spec.kind = kind == "file" ? SourceKind::kVideoFile : SourceKind::kImageFolder;
    if (rest.empty()) throw std::invalid_argument("empty path in source '" + text + "'" + expected);
    spec.path = rest;
  } else {
    throw std::invalid_argument("unknown source '" + text + "'" + expected);
  }
  return spec;
}

std::string FrameSourceSpec::ToString() const {
  switch (kind) {
    case SourceKind::kDevice:
      return "device:" + std::to_string(device_index);
    case SourceKind::kVideoFile:
      return "file:" + path;
    case SourceKind::kImageFolder:
      return "folder:" + path;
  }
  return "?";
}

void FrameSourceOptions::Validate() const {
  if ((width_px == 0) != (height_px == 0) || width_px < 0 || height_px < 0 || width_px > 16384 || height_px > 16384) {
    throw std::invalid_argument("width_px x height_px = " + std::to_string(width_px) + "x" + std::to_string(height_px) +
                                ": both must be in 1..16384, or both 0 (any size)");
  }
  if (!std::isfinite(rate_hz) || rate_hz < 0 || rate_hz > 1000) {
    throw std::invalid_argument("rate_hz must be in 0..1000, got " + std::to_string(rate_hz));
  }
  if (source.kind != SourceKind::kDevice && source.path.empty()) throw std::invalid_argument("source path is empty");
  if (source.kind == SourceKind::kDevice && source.device_index < 0) {
    throw std::invalid_argument("camera device index must be >= 0");
  }
}

std::unique_ptr<FrameSource> OpenFrameSource(const FrameSourceOptions& options) {
  options.Validate();
  switch (options.source.kind) {
    case SourceKind::kDevice:
      return std::make_unique<DeviceSource>(options);
    case SourceKind::kVideoFile:
      return std::make_unique<VideoFileSource>(options);
    case SourceKind::kImageFolder:
      return std::make_unique<ImageFolderSource>(options);
  }
  throw std::invalid_argument("bad source kind");
}

std::vector<std::string> ListImageFiles(const std::string& folder) {
  const std::string prefix = "cannot open image folder " + folder + " (";
  std::error_code ec;
  const auto status = fs::status(folder, ec);
  if (!fs::exists(status)) throw std::runtime_error(prefix + "folder does not exist)");
  if (!fs::is_directory(status)) {
    throw std::runtime_error(prefix + "not a folder; use source = file:" + folder + " for a video file)");
  }
  std::vector<fs::path> paths;
  fs::directory_iterator it(folder, ec);
  if (ec) throw std::runtime_error(prefix + ec.message() + ")");
  for (const auto& entry : it) {
    std::error_code entry_ec;
    if (entry.is_regular_file(entry_ec) && IsImageFile(entry.path())) paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end(),
            [](const fs::path& a, const fs::path& b) { return a.filename().string() < b.filename().string(); });
  std::vector<std::string> files;
  for (const auto& p : paths) files.push_back(p.string());
  return files;
}

}  // namespace snapnav::processes
