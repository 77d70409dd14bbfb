#pragma once
// MRPT timestamps and LCM utimes: mrpt::Clock counts 100 ns ticks since 1601-01-01, utimes are
// microseconds since the Unix epoch. Shared by the rawlog importer and the icp-slam runner, so
// both stamp the same scan with the same time.
#include <cstdint>
#include <optional>

#include <mrpt/core/Clock.h>

namespace snapnav::importers {

inline constexpr int64_t kMrptTicksAtUnixEpoch = 116444736000000000LL;

// The nearest microsecond; nullopt for MRPT's invalid timestamp.
inline std::optional<int64_t> MrptTimeToUtime(const mrpt::Clock::time_point& t) {
  if (t == INVALID_TIMESTAMP) return std::nullopt;
  const int64_t ticks = t.time_since_epoch().count() - kMrptTicksAtUnixEpoch;
  return ticks >= 0 ? (ticks + 5) / 10 : -((-ticks + 5) / 10);
}

inline mrpt::Clock::time_point UtimeToMrptTime(int64_t utime) {
  return mrpt::Clock::time_point(mrpt::Clock::duration(utime * 10 + kMrptTicksAtUnixEpoch));
}

}  // namespace snapnav::importers
