#pragma once
// calibrate-mirror's parts that the tests use: the frames of a log, the mean image, and the
// config file with its [mirror] section replaced.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "snapnav/nav/homing/omni_geometry.hpp"

namespace snapnav::calibrate {

// Up to `max_frames` RAW_OMNI frames of `channel` in an LCM log, spread evenly over it (every
// frame when there are fewer). Throws std::runtime_error naming the log when it cannot be read
// or holds no such frame (with the channels that hold omni frames, if any).
std::vector<cv::Mat> LogFrames(const std::string& log_path, const std::string& channel, int max_frames);

// The per-pixel mean of frames of one size (8-bit, as the first). Throws std::invalid_argument
// on no frames or frames of different sizes.
cv::Mat MeanImage(const std::vector<cv::Mat>& frames);

// `template_text` (an INI file's text) with its [mirror] section's calibration keys replaced
// by `mirror`'s and its `mask` key (when the section has one) by `mask_path`; comments and
// other sections are kept. A template without a [mirror] section gets one appended (with a mask
// key). `mask_written` (if given) says whether the mask key was written.
std::string WithMirrorSection(const std::string& template_text, const nav::MirrorModel& mirror,
                              const std::string& mask_path, bool* mask_written = nullptr);

}  // namespace snapnav::calibrate
