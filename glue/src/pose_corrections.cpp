#include "snapnav/glue/pose_corrections.hpp"

namespace snapnav::glue {

pose_correction_t ToPoseCorrectionMsg(int64_t utime, const std::string& pose_channel, int64_t corrections,
                                      const nav::PoseCorrectionTable& table) {
  pose_correction_t m{};
  m.utime = utime;
  m.pose_channel = pose_channel;
  m.corrections = corrections;
  m.ranges = static_cast<int32_t>(table.size());
  for (const nav::PoseCorrection& c : table) {
    m.from_utime.push_back(c.from_utime);
    m.x_m.push_back(c.transform.x_m);
    m.y_m.push_back(c.transform.y_m);
    m.theta_rad.push_back(c.transform.theta_rad);
  }
  return m;
}

std::optional<nav::PoseCorrectionTable> FromPoseCorrectionMsg(const pose_correction_t& msg, std::string* problem) {
  const size_t n = msg.ranges < 0 ? 0 : static_cast<size_t>(msg.ranges);
  if (msg.ranges < 0 || msg.from_utime.size() != n || msg.x_m.size() != n || msg.y_m.size() != n ||
      msg.theta_rad.size() != n) {
    *problem = "ranges " + std::to_string(msg.ranges) + " does not match its arrays";
    return std::nullopt;
  }
  nav::PoseCorrectionTable table(n);
  for (size_t i = 0; i < n; ++i) table[i] = {msg.from_utime[i], {msg.x_m[i], msg.y_m[i], msg.theta_rad[i]}};
  if (std::string p = nav::PoseCorrectionTableProblem(table); !p.empty()) {
    *problem = p;
    return std::nullopt;
  }
  return table;
}

PoseCorrections::Taken PoseCorrections::Take(const pose_correction_t& msg, std::string* problem) {
  if (msg.pose_channel != pose_channel_) return Taken::kOtherChannel;
  auto table = FromPoseCorrectionMsg(msg, problem);
  if (!table) return Taken::kInvalid;
  table_ = std::move(*table);
  corrections_ = msg.corrections;
  ++tables_;
  return Taken::kTaken;
}

}  // namespace snapnav::glue
