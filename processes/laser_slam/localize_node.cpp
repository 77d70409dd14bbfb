#include "localize_node.hpp"

#include <chrono>
#include <cmath>
#include <ostream>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/laser_scan_checks.hpp"
#include "snapnav/localization_status_t.hpp"
#include "snapnav/nav/covariance.hpp"

namespace snapnav::processes {

namespace {
constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
bool Finite(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }
}  // namespace

LocalizeNode::LocalizeNode(glue::Bus& bus, const LaserSlamConfig& config, const nav::OccupancyCells& map,
                           const std::string& map_path)
    : bus_(bus),
      config_(config),
      map_path_(map_path),
      problems_(bus, "laser-slam"),
      localizer_(map, [&] {
        nav::MapLocalizerOptions o = config.localize.options;
        o.tracking = config.options;
        return o;
      }()),
      grid_(bus, config.grid, "map_file:" + map_path, problems_) {
  grid_.SetFixed(map);
  bus_.Subscribe(config_.odometry_channel, &LocalizeNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
  bus_.Subscribe(config_.scan_channel, &LocalizeNode::OnScan, this);
}

void LocalizeNode::OnOdometry(const odometry_t& msg) {
  problems_.Guard("odometry", [&] { HandleOdometry(msg); });
}

void LocalizeNode::OnScan(const laser_scan_t& msg) {
  problems_.Guard("scan", [&] { HandleScan(msg); });
}

void LocalizeNode::HandleOdometry(const odometry_t& msg) {
  ++odometry_;
  if (!odometry_seen_) {
    // The first message fixes nothing here (the pose comes from the map); its increment is
    // relative to a message never seen.
    if (const std::string problem = glue::OdometryStartProblem(msg); !problem.empty()) {
      problems_.Skip(Finite(msg.x_m, msg.y_m, msg.theta_rad) ? "absurd odometry" : "non-finite odometry", problem, true);
      return;
    }
    odometry_seen_ = true;
    return;
  }
  if (const std::string problem = glue::OdometryProblem(msg, false); !problem.empty()) {
    problems_.Skip(Finite(msg.delta_x_m, msg.delta_y_m, msg.delta_theta_rad) ? "absurd odometry" : "non-finite odometry",
                   problem, true);
    return;
  }
  localizer_.Predict(glue::OdometryDelta(msg), msg.utime);
}

void LocalizeNode::HandleScan(const laser_scan_t& msg) {
  ++scans_;
  if (const auto problem = glue::CheckLaserScan(msg)) {
    problems_.Skip(problem->reason, problem->detail, true);
    return;
  }
  const auto points = glue::LaserScanPoints(msg);
  if (points.empty()) problems_.Skip("no valid points", "", false);
  const auto t0 = std::chrono::steady_clock::now();
  const nav::LocalizationUpdate u = localizer_.Update(points, msg.utime);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ++updates_;
  update_ms_ += ms;
  if (u.searched) {
    last_global_ = u.global;
    last_search_ms_ = ms;
    search_ms_total_ += ms;
    max_search_ms_ = std::max(max_search_ms_, ms);
  }
  if (u.state == nav::LocalizationState::kLocalized) {
    bus_.Publish(config_.pose_channel, glue::ToPoseMsg(msg.utime, "laser_localize", "map", localizer_.pose(), localizer_.covariance()));
    ++poses_published_;
  }
  localization_status_t s{};
  s.utime = msg.utime;
  s.state = u.state == nav::LocalizationState::kLocalized ? localization_status_t::LOCALIZED : localization_status_t::LOST;
  s.score = u.relocalized ? u.refined_fit : u.fit;
  s.global_score = last_global_.score;
  s.global_ambiguity = last_global_.ambiguity;
  s.global_candidates = static_cast<int32_t>(std::min<int64_t>(last_global_.nodes, INT32_MAX));
  s.global_ms = last_search_ms_;
  s.bad_scans = u.bad_scans;
  const Eigen::Matrix3d& p = localizer_.covariance();
  s.position_sigma_m = nav::PositionSigmaM(p);
  s.heading_sigma_deg = std::sqrt(std::max(0.0, p(2, 2))) * kDegPerRad;
  s.scans = scans_;
  s.global_searches = localizer_.global_searches();
  s.relocalizations = localizer_.relocalizations();
  s.losses = localizer_.losses();
  s.map = map_path_;
  bus_.Publish(config_.localize.status_channel, s);
  ++statuses_published_;
  grid_.AfterScan(msg.utime);
}

void LocalizeNode::Report(std::ostream& out) const {
  const auto& l = localizer_;
  out << "laser-slam: localize in " << map_path_ << ": scans " << scans_ << ", odometry " << odometry_ << ", poses published "
      << poses_published_ << ", state " << nav::LocalizationStateName(l.state()) << ", global searches " << l.global_searches()
      << " (mean " << (l.global_searches() > 0 ? search_ms_total_ / static_cast<double>(l.global_searches()) : 0.0)
      << " ms, max " << max_search_ms_ << " ms), relocalizations " << l.relocalizations() << ", losses " << l.losses()
      << ", skipped " << problems_.skipped_total() << ", internal errors " << problems_.internal_errors() << "\n";
  out << "laser-slam: mean update " << mean_update_ms() << " ms per scan, map " << l.map_points() << " points\n";
  out << "laser-slam: ";
  grid_.Report(out);
  problems_.Report(out);
}

}  // namespace snapnav::processes
