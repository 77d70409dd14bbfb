#include "snapnav/nav/places/navigator.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "snapnav/nav/covariance.hpp"

namespace snapnav::nav {
namespace {

bool Finite(const Pose2& p) { return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad); }

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

// ------------------------------------------------------------------------------------- routes
std::vector<Eigen::Vector2d> ThesisRoute(int which, const Eigen::Vector2d& origin, double size_m) {
  Require(which == 1 || which == 2, "thesis route must be 1 (left) or 2 (right), not " + std::to_string(which));
  Require(std::isfinite(size_m) && size_m > 0, "thesis route: size_m must be positive");
  Require(origin.allFinite(), "thesis route: origin must be finite");
  // Thesis figure 5.5, in its 0..100 units.
  static const double kLeft[][2] = {{100, 0}, {54, 81}, {0, 0}, {0, 100}, {100, 100}, {100, 0}};
  static const double kRight[][2] = {{100, 0}, {54, 81}, {100, 0}, {0, 0}, {0, 100}, {100, 0}};
  const auto& units = which == 1 ? kLeft : kRight;
  std::vector<Eigen::Vector2d> route;
  for (const auto& u : units) route.push_back(origin + Eigen::Vector2d(u[0], u[1]) * (size_m / 100.0));
  return route;
}

std::optional<int> ParseThesisRoute(const std::string& name) {
  if (name == "thesis1") return 1;
  if (name == "thesis2") return 2;
  return std::nullopt;
}

// ------------------------------------------------------------------------------- pose tracker
void PoseTrackerOptions::Validate() const {
  odometry.Validate();
  Require(std::isfinite(initial_position_sigma_m) && initial_position_sigma_m >= 0,
          "tracker: initial_position_sigma_m must be finite and >= 0");
  Require(std::isfinite(initial_heading_sigma_rad) && initial_heading_sigma_rad >= 0,
          "tracker: initial_heading_sigma_rad must be finite and >= 0");
  Require(std::isfinite(gate_chi2), "tracker: gate_chi2 must be finite (<= 0: no gate)");
  Require(reset_after_rejections >= 0, "tracker: reset_after_rejections must be >= 0");
  Require(std::isfinite(min_fix_position_sigma_m) && min_fix_position_sigma_m > 0,
          "tracker: min_fix_position_sigma_m must be positive");
  Require(std::isfinite(min_fix_heading_sigma_rad) && min_fix_heading_sigma_rad > 0,
          "tracker: min_fix_heading_sigma_rad must be positive");
  Require(std::isfinite(max_fix_age_s) && max_fix_age_s >= 0, "tracker: max_fix_age_s must be finite and >= 0");
}

const char* FixOutcomeName(FixOutcome outcome) {
  switch (outcome) {
    case FixOutcome::kInitialized:
      return "initialized";
    case FixOutcome::kAccepted:
      return "accepted";
    case FixOutcome::kReset:
      return "reset";
    case FixOutcome::kRejectedGate:
      return "gate";
    case FixOutcome::kRejectedStale:
      return "stale";
  }
  return "?";
}

PoseTracker::PoseTracker(const PoseTrackerOptions& options) : options_(options) { options_.Validate(); }

void PoseTracker::Initialize(int64_t utime, const Pose2& pose) {
  const double sp = options_.initial_position_sigma_m, sh = options_.initial_heading_sigma_rad;
  Initialize(utime, pose, Eigen::Vector3d(sp * sp, sp * sp, sh * sh).asDiagonal());
}

void PoseTracker::Initialize(int64_t utime, const Pose2& pose, const Eigen::Matrix3d& covariance) {
  Require(Finite(pose), "tracker: initial pose is not finite");
  Require(covariance.allFinite(), "tracker: initial covariance is not finite");
  pose_ = {pose.x_m, pose.y_m, WrapAngle(pose.theta_rad)};
  covariance_ = 0.5 * (covariance + covariance.transpose());
  initialized_ = true;
  consecutive_rejections_ = 0;
  if (!have_time_ || utime > utime_) utime_ = utime;
  have_time_ = true;
}

double PoseTracker::position_sigma_m() const { return PositionSigmaM(covariance_); }

void PoseTracker::AddOdometry(int64_t utime, const Pose2& delta) {
  Require(Finite(delta), "tracker: odometry increment is not finite");
  Require(!have_time_ || utime >= utime_,
          "tracker: odometry utime " + std::to_string(utime) + " is before the previous " + std::to_string(utime_));
  if (initialized_) PredictWithOdometry(options_.odometry, delta, &pose_, &covariance_);
  utime_ = utime;
  have_time_ = true;
  history_.emplace_back(utime, delta);
  const int64_t keep_us = static_cast<int64_t>(options_.max_fix_age_s * 1e6);
  while (!history_.empty() && history_.front().first < utime - keep_us) history_.pop_front();
}

FixOutcome PoseTracker::AddFix(int64_t utime, const Pose2& pose, const Eigen::Matrix3d& covariance) {
  Require(Finite(pose), "tracker: fix pose is not finite");
  Require(covariance.allFinite(), "tracker: fix covariance is not finite");
  Require(covariance(0, 0) >= 0 && covariance(1, 1) >= 0 && covariance(2, 2) >= 0,
          "tracker: fix covariance has a negative variance");
  if (have_time_ && utime < utime_ - static_cast<int64_t>(options_.max_fix_age_s * 1e6)) {
    ++rejected_;
    return FixOutcome::kRejectedStale;
  }
  // The fix's covariance, its variances floored.
  Eigen::Matrix3d r = 0.5 * (covariance + covariance.transpose());
  const double fp = options_.min_fix_position_sigma_m, fh = options_.min_fix_heading_sigma_rad;
  const Eigen::Vector3d floor(fp * fp, fp * fp, fh * fh);
  for (int i = 0; i < 3; ++i) r(i, i) += std::max(0.0, floor(i) - r(i, i));
  // A late fix is carried forward by the odometry since its time (with the motion noise).
  Pose2 z{pose.x_m, pose.y_m, WrapAngle(pose.theta_rad)};
  for (const auto& [t, delta] : history_) {
    if (t > utime) PredictWithOdometry(options_.odometry, delta, &z, &r);
  }
  if (!initialized_ ||
      (options_.reset_after_rejections > 0 && consecutive_rejections_ >= options_.reset_after_rejections)) {
    const bool reset = initialized_;
    Eigen::Matrix3d p0 = r;
    if (!options_.use_fix_heading && initialized_) {
      // Keep the tracked heading and its variance; take the fix's position.
      p0.row(2).setZero();
      p0.col(2).setZero();
      p0(2, 2) = covariance_(2, 2);
      z.theta_rad = pose_.theta_rad;
    }
    const int64_t now = have_time_ ? std::max(utime_, utime) : utime;
    Initialize(now, z, p0);
    last_mahalanobis2_ = 0;
    ++accepted_;
    if (reset) ++resets_;
    return reset ? FixOutcome::kReset : FixOutcome::kInitialized;
  }
  double d2 = 0;
  if (options_.use_fix_heading) {
    const Eigen::Vector3d y(z.x_m - pose_.x_m, z.y_m - pose_.y_m, WrapAngle(z.theta_rad - pose_.theta_rad));
    const Eigen::Matrix3d s = covariance_ + r;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(s);
    d2 = y.dot(ldlt.solve(y));
    last_mahalanobis2_ = d2;
    if (options_.gate_chi2 > 0 && !(d2 <= options_.gate_chi2)) {
      ++rejected_;
      ++consecutive_rejections_;
      return FixOutcome::kRejectedGate;
    }
    const Eigen::Matrix3d k = ldlt.solve(covariance_).transpose();  // P S^-1 (P and S symmetric)
    const Eigen::Vector3d dx = k * y;
    const Eigen::Matrix3d ikh = Eigen::Matrix3d::Identity() - k;
    covariance_ = ikh * covariance_ * ikh.transpose() + k * r * k.transpose();
    pose_ = {pose_.x_m + dx(0), pose_.y_m + dx(1), WrapAngle(pose_.theta_rad + dx(2))};
  } else {
    Eigen::Matrix<double, 2, 3> h = Eigen::Matrix<double, 2, 3>::Zero();
    h(0, 0) = h(1, 1) = 1;
    const Eigen::Vector2d y(z.x_m - pose_.x_m, z.y_m - pose_.y_m);
    const Eigen::Matrix2d rp = r.topLeftCorner<2, 2>();
    const Eigen::Matrix2d s = h * covariance_ * h.transpose() + rp;
    const Eigen::LDLT<Eigen::Matrix2d> ldlt(s);
    d2 = y.dot(ldlt.solve(y));
    last_mahalanobis2_ = d2;
    if (options_.gate_chi2 > 0 && !(d2 <= options_.gate_chi2)) {
      ++rejected_;
      ++consecutive_rejections_;
      return FixOutcome::kRejectedGate;
    }
    const Eigen::Matrix<double, 3, 2> k = covariance_ * h.transpose() * s.inverse();
    const Eigen::Vector3d dx = k * y;
    const Eigen::Matrix3d ikh = Eigen::Matrix3d::Identity() - k * h;
    covariance_ = ikh * covariance_ * ikh.transpose() + k * rp * k.transpose();
    pose_ = {pose_.x_m + dx(0), pose_.y_m + dx(1), WrapAngle(pose_.theta_rad + dx(2))};
  }
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  if (utime > utime_) utime_ = utime;
  ++accepted_;
  consecutive_rejections_ = 0;
  return FixOutcome::kAccepted;
}

// ------------------------------------------------------------------------------ route follower
bool Route::closed() const { return waypoints.size() >= 2 && (waypoints.front() - waypoints.back()).norm() < 1e-9; }

void Route::Validate() const {
  Require(!waypoints.empty(), "route '" + name + "' has no waypoints");
  for (const auto& w : waypoints) Require(w.allFinite(), "route '" + name + "' has a non-finite waypoint");
  Require(std::isfinite(tolerance_m) && tolerance_m > 0, "route '" + name + "': tolerance_m must be positive");
  Require(laps >= 0, "route '" + name + "': laps must be >= 0");
  if (loop) {
    bool distinct = false;
    for (const auto& w : waypoints) distinct = distinct || (w - waypoints.front()).norm() > tolerance_m;
    Require(distinct, "route '" + name + "': a loop needs waypoints farther apart than the tolerance");
  }
}

const char* FollowStateName(FollowState state) {
  switch (state) {
    case FollowState::kIdle:
      return "idle";
    case FollowState::kTurning:
      return "turning";
    case FollowState::kDriving:
      return "driving";
    case FollowState::kHoming:
      return "homing";
    case FollowState::kFinished:
      return "finished";
  }
  return "?";
}

std::optional<ArrivalRule> ParseArrivalRule(const std::string& name) {
  if (name == "estimate") return ArrivalRule::kEstimate;
  if (name == "homing") return ArrivalRule::kHoming;
  if (name == "either") return ArrivalRule::kEither;
  return std::nullopt;
}

const char* ArrivalRuleName(ArrivalRule rule) {
  switch (rule) {
    case ArrivalRule::kEstimate:
      return "estimate";
    case ArrivalRule::kHoming:
      return "homing";
    case ArrivalRule::kEither:
      return "either";
  }
  return "?";
}

const char* ArrivalReasonName(ArrivalReason reason) {
  switch (reason) {
    case ArrivalReason::kNone:
      return "none";
    case ArrivalReason::kEstimate:
      return "estimate";
    case ArrivalReason::kHoming:
      return "homing";
    case ArrivalReason::kTimeout:
      return "timeout";
  }
  return "?";
}

void FollowerOptions::Validate() const {
  Require(std::isfinite(max_linear_mps) && max_linear_mps > 0, "follower: max_linear_mps must be positive");
  Require(std::isfinite(min_linear_mps) && min_linear_mps >= 0 && min_linear_mps <= max_linear_mps,
          "follower: min_linear_mps must be in [0, max_linear_mps]");
  Require(std::isfinite(max_angular_radps) && max_angular_radps > 0, "follower: max_angular_radps must be positive");
  Require(std::isfinite(heading_gain_per_s) && heading_gain_per_s > 0, "follower: heading_gain_per_s must be positive");
  Require(std::isfinite(align_rad) && align_rad > 0, "follower: align_rad must be positive");
  Require(std::isfinite(turn_in_place_rad) && turn_in_place_rad >= align_rad && turn_in_place_rad <= M_PI,
          "follower: turn_in_place_rad must be in [align_rad, pi]");
  Require(std::isfinite(slow_down_m) && slow_down_m >= 0, "follower: slow_down_m must be >= 0");
  Require(std::isfinite(homing_radius_m) && homing_radius_m >= 0, "follower: homing_radius_m must be >= 0");
  Require(std::isfinite(homing_speed_mps) && homing_speed_mps > 0 && homing_speed_mps <= max_linear_mps,
          "follower: homing_speed_mps must be in (0, max_linear_mps]");
  Require(std::isfinite(homing_max_age_s) && homing_max_age_s >= 0, "follower: homing_max_age_s must be >= 0");
  Require(std::isfinite(homing_max_deviation_rad) && homing_max_deviation_rad > 0 && homing_max_deviation_rad <= M_PI,
          "follower: homing_max_deviation_rad must be in (0, pi]");
  Require(std::isfinite(approach_timeout_s) && approach_timeout_s >= 0, "follower: approach_timeout_s must be >= 0");
}

RouteFollower::RouteFollower(const FollowerOptions& options) : options_(options) { options_.Validate(); }

void RouteFollower::SetRoute(const Route& route, int first) {
  route.Validate();
  Require(first >= 0 && first < static_cast<int>(route.waypoints.size()),
          "follower: first waypoint " + std::to_string(first) + " outside the route");
  route_ = route;
  waypoint_ = first;
  laps_ = 0;
  arrivals_ = 0;
  state_ = FollowState::kTurning;
  homing_.reset();
  approach_since_.reset();
  waypoint_since_.reset();
}

void RouteFollower::SetHoming(const HomingInput& homing) {
  Require(std::isfinite(homing.direction_rad), "follower: homing direction is not finite");
  // A homing result computed before the current waypoint was taken on belongs to the previous one.
  if (waypoint_since_ && homing.utime < *waypoint_since_) return;
  homing_ = homing;
}

bool RouteFollower::HomingFresh(int64_t utime) const {
  return homing_ && utime - homing_->utime <= static_cast<int64_t>(options_.homing_max_age_s * 1e6) &&
         homing_->utime <= utime + static_cast<int64_t>(options_.homing_max_age_s * 1e6);
}

void RouteFollower::Advance(FollowStep* step) {
  ++arrivals_;
  step->arrived_waypoint = waypoint_;
  homing_.reset();
  approach_since_.reset();
  const int last = static_cast<int>(route_.waypoints.size()) - 1;
  if (waypoint_ < last) {
    ++waypoint_;
    return;
  }
  ++laps_;
  step->lap_completed = true;
  if (!route_.loop || (route_.laps > 0 && laps_ >= route_.laps)) {
    state_ = FollowState::kFinished;
    return;
  }
  waypoint_ = route_.closed() ? 1 : 0;
}

FollowStep RouteFollower::Update(int64_t utime, const Pose2& pose) {
  Require(Finite(pose), "follower: pose is not finite");
  FollowStep step;
  if (!has_route() || state_ == FollowState::kIdle) {
    state_ = FollowState::kIdle;
    return step;
  }
  if (!waypoint_since_) waypoint_since_ = utime;
  const Eigen::Vector2d here(pose.x_m, pose.y_m);
  auto geometry = [&](double* distance, double* bearing_error) {
    const Eigen::Vector2d to = route_.waypoints[waypoint_] - here;
    *distance = to.norm();
    *bearing_error = WrapAngle(std::atan2(to.y(), to.x()) - pose.theta_rad);
  };
  double d = 0, err = 0;
  if (state_ != FollowState::kFinished) {
    geometry(&d, &err);
    const bool near = options_.homing_radius_m > 0 && d < options_.homing_radius_m;
    if (near && !approach_since_) approach_since_ = utime;
    if (!near) approach_since_.reset();
    const bool fresh = HomingFresh(utime);
    const bool by_estimate = d < route_.tolerance_m;
    const bool by_homing = fresh && homing_->arrived;
    ArrivalReason reason = ArrivalReason::kNone;
    switch (options_.arrival) {
      case ArrivalRule::kEstimate:
        if (by_estimate) reason = ArrivalReason::kEstimate;
        break;
      case ArrivalRule::kHoming:
        if (fresh) {
          if (by_homing) reason = ArrivalReason::kHoming;
        } else if (by_estimate) {
          reason = ArrivalReason::kEstimate;
        }
        break;
      case ArrivalRule::kEither:
        if (by_homing) {
          reason = ArrivalReason::kHoming;
        } else if (by_estimate) {
          reason = ArrivalReason::kEstimate;
        }
        break;
    }
    if (reason == ArrivalReason::kNone && approach_since_ && options_.approach_timeout_s > 0 &&
        utime - *approach_since_ >= static_cast<int64_t>(options_.approach_timeout_s * 1e6)) {
      reason = ArrivalReason::kTimeout;
    }
    if (reason != ArrivalReason::kNone) {
      step.arrival = reason;
      Advance(&step);
      waypoint_since_ = utime;
      if (state_ != FollowState::kFinished) {
        state_ = FollowState::kTurning;
        geometry(&d, &err);
      }
    }
  }
  step.waypoint = waypoint_;
  if (state_ == FollowState::kFinished) {
    step.state = state_;
    return step;
  }
  step.distance_m = d;
  const bool near = options_.homing_radius_m > 0 && d < options_.homing_radius_m;
  bool use_homing = near && HomingFresh(utime);
  if (use_homing && std::abs(WrapAngle(homing_->direction_rad - err)) > options_.homing_max_deviation_rad) {
    use_homing = false;
    step.homing_refused = true;
  }
  if (use_homing) err = WrapAngle(homing_->direction_rad);
  step.heading_error_rad = err;
  step.homing_used = use_homing;

  if (state_ == FollowState::kTurning) {
    if (std::abs(err) < options_.align_rad) state_ = FollowState::kDriving;
  } else if (std::abs(err) > options_.turn_in_place_rad) {
    state_ = FollowState::kTurning;
  } else {
    state_ = FollowState::kDriving;
  }
  const double w =
      std::clamp(options_.heading_gain_per_s * err, -options_.max_angular_radps, options_.max_angular_radps);
  if (state_ == FollowState::kTurning) {
    step.command = {0.0, w};
  } else {
    const double ramp = options_.slow_down_m > 0 ? std::min(1.0, d / options_.slow_down_m) : 1.0;
    double v = std::max(options_.min_linear_mps, options_.max_linear_mps * ramp);
    if (use_homing) v = std::min(v, options_.homing_speed_mps);
    step.command = {v * std::cos(err), w};
    if (use_homing) state_ = FollowState::kHoming;
  }
  step.state = state_;
  return step;
}

}  // namespace snapnav::nav
