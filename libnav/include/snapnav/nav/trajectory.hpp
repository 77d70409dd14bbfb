#pragma once
// Trajectory comparison: time association, SE(2) alignment, absolute trajectory
// error (ATE) and relative pose error (RPE), as used by every evaluation.

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

struct RpeResult {
  int segments = 0;                // pose pairs (i, j) compared
  double delta_m = 0;              // the travelled distance of each segment (at least this)
  double translation_rmse_m = 0;
  double translation_mean_m = 0;
  double translation_max_m = 0;
  double rotation_rmse_deg = 0;
  double rotation_max_deg = 0;
};
// Relative pose error over a fixed travelled distance: for every pair i, j is the first later
// pair whose reference has travelled at least delta_m along its path (sum of the distances
// between consecutive reference positions) since i. The error of the segment is the motion
// the reference made from i to j expressed against the motion the estimate made,
// E = (ref_i^-1 ref_j)^-1 (est_i^-1 est_j): its translation [m] and |rotation| [deg]. It
// measures local drift per delta_m independently of where the estimate started or how it is
// aligned (the frames of estimate and reference may differ by any rigid transform). Pairs in
// order along the trajectory, (estimate, reference) as from AssociateByTime; every pair that
// has such a j starts a segment (segments overlap). No segment (the reference travels less
// than delta_m): segments == 0 and zero errors. Throws std::invalid_argument unless delta_m
// is positive and finite.
RpeResult ComputeRpe(const std::vector<std::pair<Pose2, Pose2>>& pairs, double delta_m);

}  // namespace snapnav::nav
