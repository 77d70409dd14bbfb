#pragma once
// Shared by the placecells tests: the indoor13 scene rendered with the camera of the shipped
// config, and the shipped config with edits.

#include <cstdint>
#include <initializer_list>
#include <string>

#include <opencv2/core.hpp>

#include "placecells_node.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::processes::test {

inline const std::string kShippedConfig = std::string(SNAPNAV_CONFIG_DIR) + "/placecells.ini";

std::string ReadText(const std::string& path);

// `text` with the line of `key` in [section] replaced by `key = value` (removed when `value` is
// null). Fails the test when the key is not there.
std::string Edit(const std::string& text, const std::string& section, const std::string& key, const char* value);

struct Override {
  const char* section;
  const char* key;
  const char* value;
};
// The shipped config with `overrides`, as INI text and parsed.
std::string ConfigText(std::initializer_list<Override> overrides);
PlaceCellsConfig Config(const std::string& prefix, std::initializer_list<Override> overrides,
                        const std::string& origin = "test.ini");

// indoor13 (its grid spans x 2.3..4.7 m, y 1.8..4.2 m) seen by the camera of the shipped config
// (720x120 panoramas over +-20 deg, the mirror of [mirror]). Rendered once per process.
class Indoor13 {
 public:
  static Indoor13& Get();
  cv::Mat Panorama(const nav::Pose2& robot);  // CV_8UC3
  omni_frame_t PanoramaFrame(const nav::Pose2& robot, int64_t utime);
  omni_frame_t RawFrame(const nav::Pose2& robot, int64_t utime);
  const nav::PanoramaModel& panorama() const;

 private:
  Indoor13();
  struct Impl;
  Impl* impl_;
};

}  // namespace snapnav::processes::test
