#include "omni_camera_node.hpp"

#include <algorithm>
#include <chrono>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::processes {
namespace {

std::string SizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

// Warnings of one kind: the first few, then every 100th.
bool ShouldWarn(int64_t count) { return count <= 5 || count % 100 == 0; }

// Sleeps until the monotonic time `due_utime`, waking up early on a shutdown request.
void SleepUntil(int64_t due_utime) {
  for (;;) {
    const int64_t left = due_utime - glue::MonotonicUtime();
    if (left <= 0 || glue::ShutdownRequested()) return;
    std::this_thread::sleep_for(std::chrono::microseconds(std::min<int64_t>(left, 50000)));
  }
}

}  // namespace

OmniCameraConfig OmniCameraConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  OmniCameraConfig c;
  c.frame_channel = channel_prefix + ini.GetString("channels", "frame");
  c.frame.sensor_name = ini.GetString("camera", "sensor_name");
  const std::string source = ini.GetString("camera", "source");
  c.capture.width_px = ini.GetInt("camera", "width_px");
  c.capture.height_px = ini.GetInt("camera", "height_px");
  c.capture.rate_hz = ini.GetDouble("camera", "rate_hz");
  c.capture.loop = ini.GetBool("camera", "loop");
  const std::string encoding = ini.GetString("camera", "encoding");
  c.frame.jpeg_quality = ini.GetInt("camera", "jpeg_quality");
  c.frame.mirror = glue::ReadMirrorConfig(ini);
  // The mask is for the processes that read the frames; the camera checks that it fits.
  c.mask_path = glue::ReadMirrorMask(ini, c.capture.width_px > 0 ? cv::Size(c.capture.width_px, c.capture.height_px)
                                                                 : cv::Size()).path;
  ini.CheckAllUsed();
  try {
    c.capture.source = FrameSourceSpec::Parse(source);
    c.frame.encoding = glue::ParseFrameEncoding(encoding);
    c.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  return c;
}

void OmniCameraConfig::Validate() const {
  if (frame_channel.empty()) throw std::invalid_argument("[channels] frame must not be empty");
  capture.Validate();
  frame.Validate();
  if (capture.width_px > 0) CheckMirrorFitsImage(frame.mirror, capture.width_px, capture.height_px);
}

void OmniCameraConfig::Print(std::ostream& out) const {
  out << "[channels]\nframe = " << frame_channel << "\n"
      << "[camera]\nsensor_name = " << frame.sensor_name << "\nsource = " << capture.source.ToString()
      << "\nwidth_px = " << capture.width_px << "\nheight_px = " << capture.height_px
      << "\nrate_hz = " << capture.rate_hz << "\nloop = " << (capture.loop ? "true" : "false")
      << "\nencoding = " << glue::FrameEncodingName(frame.encoding) << "\njpeg_quality = " << frame.jpeg_quality << "\n";
  glue::PrintMirrorConfig(out, frame.mirror, mask_path, "mirror");
}

OmniCameraNode::OmniCameraNode(glue::Bus& bus, const OmniCameraConfig& config, std::ostream* log)
    : bus_(bus), config_(config), log_(log) {
  config_.Validate();
  source_ = OpenFrameSource(config_.capture);
  source_description_ = source_->description();
  expected_width_px_ = config_.capture.width_px;
  expected_height_px_ = config_.capture.height_px;
}

OmniCameraNode::StepResult OmniCameraNode::Skip(int64_t* counter, const std::string& reason) {
  ++*counter;
  ++consecutive_unusable_;
  last_error_ = reason;
  if (log_ && ShouldWarn(*counter)) *log_ << "omni-camera: skipped frame " << frames_read_ << ": " << reason << "\n";
  if (consecutive_unusable_ >= source_->max_consecutive_failures()) {
    throw std::runtime_error(source_description_ + ": " + std::to_string(consecutive_unusable_) +
                             " frames in a row unusable (last: " + reason + ")");
  }
  return StepResult::kSkipped;
}

OmniCameraNode::StepResult OmniCameraNode::Step() {
  cv::Mat image;
  std::string error;
  const ReadStatus status = source_->Read(&image, &error);
  if (status == ReadStatus::kEnd) return StepResult::kEnd;
  const int64_t utime = glue::WallUtime();  // capture time: this driver is a live source
  ++frames_read_;
  if (status == ReadStatus::kFailed) return Skip(&read_failures_, error);

  if (expected_width_px_ == 0) {
    // No size configured: the first frame fixes it, and the mirror centre must lie inside.
    CheckMirrorFitsImage(config_.frame.mirror, image.cols, image.rows);
    expected_width_px_ = image.cols;
    expected_height_px_ = image.rows;
  }
  if (image.cols != expected_width_px_ || image.rows != expected_height_px_) {
    return Skip(&size_mismatches_, "frame is " + SizeText(image.cols, image.rows) + ", expected " +
                                       SizeText(expected_width_px_, expected_height_px_) +
                                       " ([camera] width_px, height_px; the mirror calibration is for that size)");
  }
  omni_frame_t msg;
  try {
    msg = MatToOmniFrame(image, utime, config_.frame);
  } catch (const std::exception& e) {
    return Skip(&conversion_errors_, e.what());
  }
  bus_.Publish(config_.frame_channel, msg);
  ++published_;
  consecutive_unusable_ = 0;
  return StepResult::kPublished;
}

OmniCameraNode::StopReason OmniCameraNode::Run(int64_t max_frames) {
  const bool paced = !source_->is_device() && config_.capture.rate_hz > 0;
  const int64_t period_us = paced ? static_cast<int64_t>(1e6 / config_.capture.rate_hz) : 0;
  int64_t due = glue::MonotonicUtime();
  for (;;) {
    if (glue::ShutdownRequested()) return StopReason::kShutdown;
    if (max_frames > 0 && published_ >= max_frames) return StopReason::kMaxFrames;
    if (paced) {
      SleepUntil(due);
      if (glue::ShutdownRequested()) return StopReason::kShutdown;
      // Late by more than a period (slow disk, suspended process): restart the schedule, no burst.
      const int64_t now = glue::MonotonicUtime();
      due = (now - due > period_us) ? now + period_us : due + period_us;
    }
    if (Step() == StepResult::kEnd) return StopReason::kEndOfSource;
  }
}

void OmniCameraNode::Report(std::ostream& out) const {
  out << "published " << published_ << " frames on " << config_.frame_channel << " from " << source_description_ << " ("
      << read_failures_ << " unreadable, " << size_mismatches_ << " wrong size, " << conversion_errors_
      << " not converted)";
  if (!last_error_.empty()) out << "; last problem: " << last_error_;
  out << "\n";
}

}  // namespace snapnav::processes
