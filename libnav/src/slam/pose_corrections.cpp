#include "snapnav/nav/slam/pose_corrections.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace snapnav::nav {
namespace {

bool Same(const Pose2& a, const Pose2& b, double tolerance) {
  return std::abs(a.x_m - b.x_m) <= tolerance && std::abs(a.y_m - b.y_m) <= tolerance &&
         std::abs(a.theta_rad - b.theta_rad) <= tolerance;
}

}  // namespace

Pose2 CorrectPublishedPose(const PoseCorrectionTable& table, int64_t utime, const Pose2& published) {
  // The last range starting at or before utime.
  const auto after = std::upper_bound(table.begin(), table.end(), utime,
                                      [](int64_t t, const PoseCorrection& c) { return t < c.from_utime; });
  if (after == table.begin()) return published;
  return std::prev(after)->transform.Compose(published);
}

std::string PoseCorrectionTableProblem(const PoseCorrectionTable& table) {
  for (size_t i = 0; i < table.size(); ++i) {
    const Pose2& t = table[i].transform;
    if (!std::isfinite(t.x_m) || !std::isfinite(t.y_m) || !std::isfinite(t.theta_rad)) {
      return "range " + std::to_string(i) + " has a non-finite transform";
    }
    if (std::abs(t.x_m) > kMaxCorrectionM || std::abs(t.y_m) > kMaxCorrectionM ||
        std::abs(t.theta_rad) > kMaxCorrectionRad) {
      return "range " + std::to_string(i) + " has an absurd transform (beyond " +
             std::to_string(static_cast<int64_t>(kMaxCorrectionM)) + " m or " +
             std::to_string(static_cast<int64_t>(kMaxCorrectionRad)) + " rad)";
    }
    if (i > 0 && table[i].from_utime <= table[i - 1].from_utime) {
      return "range " + std::to_string(i) + " starts at utime " + std::to_string(table[i].from_utime) +
             ", not after range " + std::to_string(i - 1) + "'s " + std::to_string(table[i - 1].from_utime);
    }
  }
  return "";
}

void PublishedPoses::Note(int64_t utime, int anchor, const Pose2& anchor_pose) {
  // A pose stamped before the last one (a scan out of order) starts no range: the ranges stay in
  // increasing time, and that pose takes the range that holds its time.
  if (!ranges_.empty() && utime < last_utime_) return;
  last_utime_ = utime;
  if (!ranges_.empty() && ranges_.back().anchor == anchor &&
      (anchor < 0 || Same(ranges_.back().anchor_pose, anchor_pose, 0.0))) {
    return;
  }
  if (!ranges_.empty() && ranges_.back().from_utime == utime) {
    ranges_.back() = {utime, anchor, anchor_pose};  // two poses at one time: the later one's
    return;
  }
  ranges_.push_back({utime, anchor, anchor_pose});
}

PoseCorrectionTable PublishedPoses::Table(const std::function<Pose2(int)>& anchor_now) const {
  PoseCorrectionTable table;
  table.reserve(ranges_.size());
  for (const Range& r : ranges_) {
    const Pose2 t = r.anchor < 0 ? Pose2{} : anchor_now(r.anchor).Compose(r.anchor_pose.Inverse());
    if (!table.empty() && Same(table.back().transform, t, 1e-9)) continue;
    table.push_back({r.from_utime, t});
  }
  return table;
}

}  // namespace snapnav::nav
