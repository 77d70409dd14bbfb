// RatSLAM experience map: experiences, odometry links, graph relaxation (OpenRatSLAM's).
#include <cmath>
#include <stdexcept>
#include <string>

#include "snapnav/nav/ratslam/ratslam.hpp"

namespace snapnav::nav {
namespace {

// The signed angle from a to b, in [-pi, pi).
double SignedDelta(double a_rad, double b_rad) { return WrapAngle(b_rad - a_rad); }

}  // namespace

void ExperienceMapOptions::Validate() const {
  if (exp_loops < 0) throw std::invalid_argument("ratslam experience map: exp_loops must be >= 0");
  if (!(exp_correction >= 0 && exp_correction <= 1)) {
    throw std::invalid_argument("ratslam experience map: exp_correction must be in [0, 1]");
  }
}

ExperienceMap::ExperienceMap(const ExperienceMapOptions& options, const Pose2& start)
    : options_(options), origin_(start), accum_facing_rad_(WrapAngle(start.theta_rad)) {
  options_.Validate();
  if (!std::isfinite(start.x_m) || !std::isfinite(start.y_m) || !std::isfinite(start.theta_rad)) {
    throw std::invalid_argument("ratslam experience map: the start pose must be finite");
  }
  experiences_.reserve(1024);
  links_.reserve(2048);
}

void ExperienceMap::OnOdometry(const Pose2& delta, double dt_s) {
  // The increment composed exactly: forward and left in the robot frame, then the turn.
  const double c = std::cos(accum_facing_rad_), s = std::sin(accum_facing_rad_);
  accum_x_m_ += c * delta.x_m - s * delta.y_m;
  accum_y_m_ += s * delta.x_m + c * delta.y_m;
  accum_facing_rad_ = WrapAngle(accum_facing_rad_ + delta.theta_rad);
  accum_time_s_ += dt_s;
}

Pose2 ExperienceMap::robot_pose() const {
  const Pose2& base = current_ >= 0 ? experiences_[static_cast<size_t>(current_)].pose : origin_;
  return {base.x_m + accum_x_m_, base.y_m + accum_y_m_, accum_facing_rad_};
}

int ExperienceMap::CreateExperience(int view_template, double relative_rad) {
  Experience e;
  e.pose = robot_pose();
  e.view_template = view_template;
  e.view_relative_rad = relative_rad;
  experiences_.push_back(std::move(e));
  const int id = static_cast<int>(experiences_.size()) - 1;
  if (current_ >= 0) LinkTo(id, relative_rad, false);
  SetExperience(id, relative_rad);
  return id;
}

bool ExperienceMap::LinkTo(int to, double relative_rad, bool loop_closure) {
  if (current_ < 0) throw std::out_of_range("ratslam experience map: a link needs a current experience");
  if (to < 0 || to >= static_cast<int>(experiences_.size())) {
    throw std::out_of_range("ratslam experience map: no experience " + std::to_string(to));
  }
  if (to == current_) return false;
  for (int l : experiences_[static_cast<size_t>(current_)].links_from) {
    if (links_[static_cast<size_t>(l)].to == to) return false;
  }
  for (int l : experiences_[static_cast<size_t>(to)].links_from) {
    if (links_[static_cast<size_t>(l)].to == current_) return false;
  }
  const Pose2& from = experiences_[static_cast<size_t>(current_)].pose;
  ExperienceLink link;
  link.from = current_;
  link.to = to;
  link.d_m = std::hypot(accum_x_m_, accum_y_m_);
  link.heading_rad = SignedDelta(from.theta_rad, std::atan2(accum_y_m_, accum_x_m_));
  // The robot faces its heading now; the template of `to` was learnt facing that minus relative_rad,
  // and `to` faces the template's heading plus the offset it was created with.
  const double to_facing = accum_facing_rad_ - relative_rad + experiences_[static_cast<size_t>(to)].view_relative_rad;
  link.facing_rad = SignedDelta(from.theta_rad, WrapAngle(to_facing));
  link.dt_s = accum_time_s_;
  link.loop_closure = loop_closure;
  links_.push_back(link);
  const int id = static_cast<int>(links_.size()) - 1;
  experiences_[static_cast<size_t>(current_)].links_from.push_back(id);
  experiences_[static_cast<size_t>(to)].links_to.push_back(id);
  return true;
}

void ExperienceMap::SetExperience(int id, double relative_rad) {
  if (id < 0 || id >= static_cast<int>(experiences_.size())) {
    throw std::out_of_range("ratslam experience map: no experience " + std::to_string(id));
  }
  if (id == current_) return;
  current_ = id;
  accum_x_m_ = accum_y_m_ = 0;
  accum_time_s_ = 0;
  const Experience& e = experiences_[static_cast<size_t>(id)];
  accum_facing_rad_ = WrapAngle(e.pose.theta_rad - e.view_relative_rad + relative_rad);
}

void ExperienceMap::Relax() {
  // OpenRatSLAM's iterate(): each link pulls its two ends towards agreement with what the odometry
  // said, by exp_correction of the disagreement each, in position and in heading.
  const double k = options_.exp_correction;
  for (int loop = 0; loop < options_.exp_loops; ++loop) {
    for (Experience& from : experiences_) {
      for (int l : from.links_from) {
        const ExperienceLink& link = links_[static_cast<size_t>(l)];
        Experience& to = experiences_[static_cast<size_t>(link.to)];
        const double lx = from.pose.x_m + link.d_m * std::cos(from.pose.theta_rad + link.heading_rad);
        const double ly = from.pose.y_m + link.d_m * std::sin(from.pose.theta_rad + link.heading_rad);
        const double ex = (to.pose.x_m - lx) * k, ey = (to.pose.y_m - ly) * k;
        from.pose.x_m += ex;
        from.pose.y_m += ey;
        to.pose.x_m -= ex;
        to.pose.y_m -= ey;
        const double df = SignedDelta(from.pose.theta_rad + link.facing_rad, to.pose.theta_rad) * k;
        from.pose.theta_rad = WrapAngle(from.pose.theta_rad + df);
        to.pose.theta_rad = WrapAngle(to.pose.theta_rad - df);
      }
    }
  }
}

}  // namespace snapnav::nav
