#pragma once
// The message times (utime) of one input stream, in arrival order. A node that needs its
// inputs in time order asks Check() for each message: a time that cannot be a sensor time
// (negative, or beyond 2^62 us) is implausible; one older than the last accepted is back in
// time. Both are for the node to reject (counted). So that one absurd future stamp cannot block
// a node for ever, `restart_after` back-in-time messages in a row restart the stream at the
// newest one (a clock jump, or a second log played after the first).

#include <cstdint>
#include <optional>

namespace snapnav::glue {

// A utime that can be a sensor time: 0 .. 2^62 us (differences of two never overflow).
inline bool PlausibleUtime(int64_t utime) { return utime >= 0 && utime <= (int64_t{1} << 62); }

class MessageClock {
 public:
  enum class Verdict { kAccepted, kRestarted, kBackInTime, kImplausible };
  static constexpr int64_t kMaxPlausibleUtime = int64_t{1} << 62;

  explicit MessageClock(int restart_after = 5) : restart_after_(restart_after) {}

  Verdict Check(int64_t utime) {
    if (!PlausibleUtime(utime)) return Verdict::kImplausible;
    if (!last_ || utime >= *last_) {
      last_ = utime;
      behind_ = 0;
      return Verdict::kAccepted;
    }
    if (++behind_ < restart_after_) return Verdict::kBackInTime;
    last_ = utime;
    behind_ = 0;
    return Verdict::kRestarted;
  }
  // The last accepted time.
  std::optional<int64_t> last() const { return last_; }

 private:
  int restart_after_;
  int behind_ = 0;
  std::optional<int64_t> last_;
};

}  // namespace snapnav::glue
