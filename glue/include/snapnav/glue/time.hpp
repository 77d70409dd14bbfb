#pragma once
// Wall clock for drivers and tools. Algorithms never call this: they use message utime.

#include <chrono>
#include <cstdint>

namespace snapnav::glue {

inline int64_t WallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

inline int64_t MonotonicUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace snapnav::glue
