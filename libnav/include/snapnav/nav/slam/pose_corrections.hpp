#pragma once
// Corrections of poses already published, for those who stored them (issue 22). With the graph
// back end a loop closure moves the past trajectory, and not by one rigid motion: a process that
// placed something at a pose it received (a place cell, a grid image, a scan of an exported map)
// must move it with the part of the trajectory it was placed on.
//
// The publisher keeps, per range of publication times, the keyframe its poses were relative to and
// that keyframe's pose when they were published (PublishedPoses). A published pose p = K_then (+) r
// (r the pose relative to the keyframe, which the graph never changes) is now K_now (+) r =
// (K_now (+) K_then^-1) (+) p: one rigid transform per range, composed on the left of what was
// published. Consumers keep what they received and apply the newest table (CorrectPublishedPose):
// the tables are complete, so applying one twice, or skipping one, changes nothing.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// The poses published from from_utime on (to the next range's from_utime) are corrected by
// `transform` (composed on the left).
struct PoseCorrection {
  int64_t from_utime = 0;
  Pose2 transform;
};
// Ranges in increasing from_utime.
using PoseCorrectionTable = std::vector<PoseCorrection>;

// `published`, published at `utime`, corrected by the range that holds utime; before the first
// range (or with an empty table), unchanged.
Pose2 CorrectPublishedPose(const PoseCorrectionTable& table, int64_t utime, const Pose2& published);

// A transform beyond these is garbage (no map is 1000 km across).
inline constexpr double kMaxCorrectionM = 1e6;
inline constexpr double kMaxCorrectionRad = 1e3;
// "" when the table can be applied (ranges in strictly increasing from_utime, finite transforms
// within the bounds above), else what is wrong with it (naming the range).
std::string PoseCorrectionTableProblem(const PoseCorrectionTable& table);

// The publisher's record: per range of publication times, the keyframe its poses were relative to
// (-1: none, the start's frame, never corrected) and that keyframe's pose then. One range per
// change of keyframe or of its pose (a correction): a few tens of bytes per keyframe passed.
class PublishedPoses {
 public:
  // A pose published at `utime`, relative to keyframe `anchor`, whose pose was `anchor_pose` then.
  // A utime before the last one's is not recorded (the ranges stay in time order; it takes the
  // range that holds its time).
  void Note(int64_t utime, int anchor, const Pose2& anchor_pose);
  // The table now, with `anchor_now(k)` keyframe k's current pose; consecutive ranges whose
  // transforms agree within 1e-9 m and rad merged.
  PoseCorrectionTable Table(const std::function<Pose2(int)>& anchor_now) const;
  size_t ranges() const { return ranges_.size(); }

 private:
  struct Range {
    int64_t from_utime = 0;
    int anchor = -1;
    Pose2 anchor_pose;
  };
  std::vector<Range> ranges_;
  int64_t last_utime_ = 0;
};

}  // namespace snapnav::nav
