#include "grid_publisher.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <ostream>

#include "snapnav/glue/grid_scan_msg.hpp"
#include "snapnav/glue/occupancy_grid_msg.hpp"
#include "snapnav/glue/options.hpp"

namespace snapnav::processes {

namespace {

// The [grid] keys, declared once: read, printed and described from here.
const glue::OptionTable<GridConfig>& GridTable() {
  using C = GridConfig;
  static const auto table = glue::OptionTable<C>()
                                .Number("every_s", "s", &C::every_s)
                                .Number("resolution_m", "m", [](auto& c) -> auto& { return c.grid.resolution_m; })
                                .Number("max_range_m", "m", [](auto& c) -> auto& { return c.grid.max_range_m; })
                                .Number("keyframe_m", "m", &C::keyframe_m)
                                .Degrees("keyframe_deg", &C::keyframe_rad);
  return table;
}

}  // namespace

GridConfig GridConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  GridConfig c;
  c.channel = channel_prefix + ini.GetString("channels", "grid");
  c.request_channel = channel_prefix + ini.GetString("channels", "grid_request");
  GridTable().ReadKeys(ini, "grid", &c);
  try {
    c.grid.Validate();
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  if (!(c.every_s >= 0)) ini.FailKey("grid", "every_s", "must be >= 0 (0: on request only)");
  if (!(c.keyframe_m >= 0)) ini.FailKey("grid", "keyframe_m", "must be >= 0");
  if (!(c.keyframe_rad >= 0)) ini.FailKey("grid", "keyframe_deg", "must be >= 0");
  return c;
}

void GridConfig::Print(std::ostream& out) const {
  out << "[grid]\n";
  GridTable().Print(out, *this);
}

GridPublisher::GridPublisher(glue::Bus& bus, const GridConfig& config, std::string source, glue::HandlerProblems& problems)
    : bus_(bus), config_(config), source_(std::move(source)), problems_(problems), builder_(BuilderOptions()) {
  if (!config_.request_channel.empty()) bus_.Subscribe(config_.request_channel, &GridPublisher::OnRequest, this);
}

void GridPublisher::AddScan(const laser_scan_t& msg, const nav::Pose2& robot_pose) {
  if (fixed_ || msg.nranges < 2) return;
  if (last_inserted_) {
    const nav::Pose2 d = last_inserted_->Between(robot_pose);
    if (std::hypot(d.x_m, d.y_m) < config_.keyframe_m && std::abs(d.theta_rad) < config_.keyframe_rad) return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t too_large = builder_.too_large();
  if (builder_.Insert(glue::GridScanOf(msg, robot_pose))) {
    last_inserted_ = robot_pose;
    ++added_;
  }
  if (builder_.too_large() > too_large) problems_.Skip("grid too large", "a scan at (" + std::to_string(robot_pose.x_m) + ", " + std::to_string(robot_pose.y_m) + ") would grow the grid beyond " + std::to_string(GridConfig::kMaxCells) + " cells", false);
  insert_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

nav::OccupancyGridOptions GridPublisher::BuilderOptions() const {
  nav::OccupancyGridOptions o = config_.grid;
  o.max_cells = GridConfig::kMaxCells;
  return o;
}

void GridPublisher::AddKeyframeScan(int keyframe, const laser_scan_t& msg) {
  if (fixed_ || msg.nranges < 2) return;
  keyframe_scans_[keyframe] = glue::GridScanOf(msg, {});
}

void GridPublisher::Rebuild() {
  rebuild_due_ = false;
  if (!keyframe_poses_) return;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<nav::Pose2> poses = keyframe_poses_();
  nav::OccupancyGridBuilder rebuilt(BuilderOptions());
  for (auto& [k, scan] : keyframe_scans_) {
    if (k < 0 || static_cast<size_t>(k) >= poses.size()) continue;
    scan.robot_pose = poses[static_cast<size_t>(k)];
    rebuilt.Insert(scan);
  }
  builder_ = std::move(rebuilt);
  ++rebuilds_;
  last_rebuild_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void GridPublisher::SetFixed(const nav::OccupancyCells& cells) { fixed_ = cells; }

void GridPublisher::AfterScan(int64_t utime) {
  last_utime_ = std::max(last_utime_, utime);
  if (first_utime_ == 0) first_utime_ = utime;
  const bool have = fixed_ || added_ > 0;
  if (!have) return;
  if (pending_request_) {
    Publish(utime);
    return;
  }
  // A fixed map goes out at once (a viewer shows it from the start), a growing one after every_s.
  const int64_t since = published_ > 0 ? last_published_utime_ : (fixed_ ? utime - static_cast<int64_t>(config_.every_s * 1e6) : first_utime_);
  if (config_.every_s > 0 && utime - since >= static_cast<int64_t>(std::llround(config_.every_s * 1e6))) Publish(utime);
}

void GridPublisher::OnRequest(const map_request_t& msg) {
  problems_.Guard("grid request", [&] {
    (void)msg;
    ++requests_;
    pending_request_ = true;
    if (fixed_ || added_ > 0) Publish(last_utime_ > 0 ? last_utime_ : msg.utime);
  });
}

void GridPublisher::Publish(int64_t utime) {
  if (config_.channel.empty()) return;
  if (!fixed_ && rebuild_due_) Rebuild();
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<nav::OccupancyCells> built;  // a saved map is sent as it is, not copied
  if (!fixed_) built = builder_.Cells();
  const nav::OccupancyCells& cells = fixed_ ? *fixed_ : *built;
  bus_.Publish(config_.channel, glue::ToOccupancyGridMsg(cells, utime, "map", source_));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  publish_ms_ += ms;
  max_publish_ms_ = std::max(max_publish_ms_, ms);
  last_cells_ = static_cast<int64_t>(cells.cells.size());
  ++published_;
  last_published_utime_ = utime;
  pending_request_ = false;
}

void GridPublisher::Report(std::ostream& out) const {
  out << source_.substr(0, source_.find(':')) << " grid: " << published_ << " published on " << config_.channel << " ("
      << requests_ << " requests";
  if (published_ > 0) {
    out << "; the last of " << last_cells_ << " cells; converted and sent in mean " << mean_publish_ms() << " ms, max "
        << max_publish_ms_ << " ms";
  }
  out << "), " << added_ << " scans inserted (mean " << mean_insert_ms() << " ms)";
  if (rebuilds_ > 0 || !keyframe_scans_.empty()) {
    out << ", rebuilt from " << keyframe_scans_.size() << " keyframe scans after corrections " << rebuilds_
        << " times (last " << last_rebuild_ms_ << " ms)";
  }
  out << "\n";
}

}  // namespace snapnav::processes
