#pragma once
// Trajectory comparison: time association, SE(2) alignment and absolute
// trajectory error (ATE), as used by every evaluation.

#include <cstdint>
#include <optional>
#include <vector>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct StampedPose {
  int64_t utime = 0;
  Pose2 pose;
};

// Index of the reference pose nearest in time to `utime` (binary search; `reference`
// sorted by utime), or nullopt if none lies within max_dt_us.
std::optional<size_t> NearestInTime(const std::vector<StampedPose>& reference, int64_t utime, int64_t max_dt_us);

// Pairs each estimate with the reference pose nearest in time (within max_dt_us).
// Both must be sorted by utime. Returns (estimate, reference) pairs.
std::vector<std::pair<Pose2, Pose2>> AssociateByTime(const std::vector<StampedPose>& estimate,
                                                     const std::vector<StampedPose>& reference, int64_t max_dt_us);

// The rigid transform T minimising sum |T(est_i) - ref_i|^2 over positions
// (closed form, Umeyama without scale). Throws std::invalid_argument with fewer than 2 pairs.
Pose2 AlignSE2(const std::vector<std::pair<Pose2, Pose2>>& pairs);

struct AteResult {
  int pairs = 0;
  double rmse_m = 0;
  double mean_m = 0;
  double max_m = 0;
  double final_m = 0;  // error of the last pair
};
// Position errors after applying `align` to every estimate.
AteResult ComputeAte(const std::vector<std::pair<Pose2, Pose2>>& pairs, const Pose2& align = {});

}  // namespace snapnav::nav
