#pragma once
// Wall time of an evaluation's steps (ms per view, per query, per update in the reports).
#include <chrono>

namespace snapnav::eval {

using Clock = std::chrono::steady_clock;

// Milliseconds since `since`.
inline double MsSince(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

}  // namespace snapnav::eval
