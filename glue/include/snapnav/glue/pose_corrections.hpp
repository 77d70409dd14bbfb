#pragma once
// pose_correction_t <-> libnav's correction tables, and a consumer's side of them: the newest table
// for the one pose channel a process stores poses of (laser-slam publishes the tables with
// backend = graph; docs/laser_slam.md#corrections-of-published-poses).
#include <cstdint>
#include <optional>
#include <string>

#include "snapnav/nav/slam/pose_corrections.hpp"
#include "snapnav/pose_correction_t.hpp"

namespace snapnav::glue {

pose_correction_t ToPoseCorrectionMsg(int64_t utime, const std::string& pose_channel, int64_t corrections,
                                      const nav::PoseCorrectionTable& table);
// The message's table, or nullopt with *problem saying what is wrong (array sizes, order, non-finite).
std::optional<nav::PoseCorrectionTable> FromPoseCorrectionMsg(const pose_correction_t& msg, std::string* problem);

// What a process that stores the poses of `pose_channel` keeps of the corrections: the newest valid
// table for that channel (tables for other channels ignored: another estimator's poses).
class PoseCorrections {
 public:
  explicit PoseCorrections(std::string pose_channel) : pose_channel_(std::move(pose_channel)) {}
  enum class Taken { kTaken, kOtherChannel, kInvalid };
  // Takes the message's table (it replaces the one held: each is complete) when it is for our
  // channel and valid; *problem says why an invalid one was refused.
  Taken Take(const pose_correction_t& msg, std::string* problem);
  // A pose received at `utime` as published, corrected by the newest table.
  nav::Pose2 Correct(int64_t utime, const nav::Pose2& published) const {
    return nav::CorrectPublishedPose(table_, utime, published);
  }
  const std::string& pose_channel() const { return pose_channel_; }
  int64_t tables() const { return tables_; }            // tables taken
  int64_t corrections() const { return corrections_; }  // the held table's corrections count (0: none)
  size_t ranges() const { return table_.size(); }

 private:
  std::string pose_channel_;
  nav::PoseCorrectionTable table_;
  int64_t tables_ = 0, corrections_ = 0;
};

}  // namespace snapnav::glue
