#include "navigator_node.hpp"

#include <cmath>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/options.hpp"

namespace snapnav::processes {
namespace {

constexpr double kDeg = M_PI / 180.0;

bool Finite(const nav::Pose2& p) { return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad); }

int8_t StateCode(nav::FollowState s) {
  switch (s) {
    case nav::FollowState::kIdle:
      return navigator_status_t::IDLE;
    case nav::FollowState::kTurning:
      return navigator_status_t::TURNING;
    case nav::FollowState::kDriving:
      return navigator_status_t::DRIVING;
    case nav::FollowState::kHoming:
      return navigator_status_t::HOMING;
    case nav::FollowState::kFinished:
      return navigator_status_t::FINISHED;
  }
  return navigator_status_t::IDLE;
}

// The options of every section but [channels], declared once: read, printed and described from here.
using Table = glue::OptionTable<NavigatorConfig>;
const std::vector<std::pair<std::string, Table>>& Sections() {
  using C = NavigatorConfig;
  static const std::vector<std::pair<std::string, Table>> sections = {
      {"route", Table()
                    .Choice("route", &C::route_source,
                            std::vector<std::pair<std::string, std::string>>{
                                {"none", "none"}, {"thesis1", "thesis1"}, {"thesis2", "thesis2"}})
                    .Number("origin_x_m", "m", [](auto& c) -> auto& { return c.route_origin.x(); })
                    .Number("origin_y_m", "m", [](auto& c) -> auto& { return c.route_origin.y(); })
                    .Number("size_m", "m", &C::route_size_m)
                    .Flag("loop", &C::route_loop)
                    .Number("laps", "", &C::route_laps)
                    .Number("tolerance_m", "m", &C::route_tolerance_m)
                    .Number("first_waypoint", "", &C::route_first_waypoint)},
      {"tracker", Table()
                      .Number("translation_noise_m_per_m", "m/m",
                              [](auto& c) -> auto& { return c.tracker.odometry.translation_noise_m_per_m; })
                      .Number("rotation_noise_rad_per_rad", "rad/rad",
                              [](auto& c) -> auto& { return c.tracker.odometry.rotation_noise_rad_per_rad; })
                      .Degrees("rotation_noise_deg_per_m", [](auto& c) -> auto& { return c.tracker.odometry.rotation_noise_rad_per_m; },
                               "deg/m")
                      .Number("initial_position_sigma_m", "m", [](auto& c) -> auto& { return c.tracker.initial_position_sigma_m; })
                      .Degrees("initial_heading_sigma_deg", [](auto& c) -> auto& { return c.tracker.initial_heading_sigma_rad; })
                      .Number("gate_chi2", "", [](auto& c) -> auto& { return c.tracker.gate_chi2; })
                      .Number("reset_after_rejections", "", [](auto& c) -> auto& { return c.tracker.reset_after_rejections; })
                      .Flag("use_fix_heading", [](auto& c) -> auto& { return c.tracker.use_fix_heading; })
                      .Number("min_fix_position_sigma_m", "m", [](auto& c) -> auto& { return c.tracker.min_fix_position_sigma_m; })
                      .Degrees("min_fix_heading_sigma_deg", [](auto& c) -> auto& { return c.tracker.min_fix_heading_sigma_rad; })
                      .Number("max_fix_age_s", "s", [](auto& c) -> auto& { return c.tracker.max_fix_age_s; })
                      .Number("unknown_fix_position_sigma_m", "m", &C::unknown_fix_position_sigma_m)
                      .Degrees("unknown_fix_heading_sigma_deg", &C::unknown_fix_heading_sigma_rad)},
      {"follower", Table()
                       .Number("max_linear_mps", "m/s", [](auto& c) -> auto& { return c.follower.max_linear_mps; })
                       .Number("min_linear_mps", "m/s", [](auto& c) -> auto& { return c.follower.min_linear_mps; })
                       .Degrees("max_angular_deg_per_s", [](auto& c) -> auto& { return c.follower.max_angular_radps; }, "deg/s")
                       .Number("heading_gain_per_s", "1/s", [](auto& c) -> auto& { return c.follower.heading_gain_per_s; })
                       .Degrees("turn_in_place_deg", [](auto& c) -> auto& { return c.follower.turn_in_place_rad; })
                       .Degrees("align_deg", [](auto& c) -> auto& { return c.follower.align_rad; })
                       .Number("slow_down_m", "m", [](auto& c) -> auto& { return c.follower.slow_down_m; })
                       .Number("homing_radius_m", "m", [](auto& c) -> auto& { return c.follower.homing_radius_m; })
                       .Number("homing_speed_mps", "m/s", [](auto& c) -> auto& { return c.follower.homing_speed_mps; })
                       .Number("homing_max_age_s", "s", [](auto& c) -> auto& { return c.follower.homing_max_age_s; })
                       .Degrees("homing_max_deviation_deg", [](auto& c) -> auto& { return c.follower.homing_max_deviation_rad; })
                       .Choice("arrival", [](auto& c) -> auto& { return c.follower.arrival; },
                               {nav::ArrivalRule::kEstimate, nav::ArrivalRule::kHoming, nav::ArrivalRule::kEither},
                               nav::ArrivalRuleName)
                       .Number("approach_timeout_s", "s", [](auto& c) -> auto& { return c.follower.approach_timeout_s; })},
      {"homing", Table().Number("arrived_magnitude", "", &C::homing_arrived_magnitude)},
      {"navigator", Table().Number("status_period_s", "s", &C::status_period_s)},
  };
  return sections;
}

}  // namespace

std::optional<nav::Route> NavigatorConfig::ConfiguredRoute() const {
  const auto which = nav::ParseThesisRoute(route_source);
  if (!which) return std::nullopt;
  nav::Route r;
  r.name = route_source;
  r.waypoints = nav::ThesisRoute(*which, route_origin, route_size_m);
  r.loop = route_loop;
  r.laps = route_laps;
  r.tolerance_m = route_tolerance_m;
  return r;
}

NavigatorConfig NavigatorConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  NavigatorConfig c;
  c.odometry_channel = channel_prefix + ini.GetString("channels", "odometry");
  c.pose_channel = channel_prefix + ini.GetString("channels", "pose");
  c.homing_vector_channel = channel_prefix + ini.GetString("channels", "homing_vector");
  c.route_channel = channel_prefix + ini.GetString("channels", "route");
  c.drive_command_channel = channel_prefix + ini.GetString("channels", "drive_command");
  c.status_channel = channel_prefix + ini.GetString("channels", "status");

  for (const auto& [section, table] : Sections()) table.Read(ini, section, &c);
  for (const char* key : {"origin_x_m", "origin_y_m"}) {
    if (!std::isfinite(ini.GetDouble("route", key))) ini.FailKey("route", key, "must be finite");
  }
  ini.CheckAllUsed();

  try {
    c.tracker.Validate();
    c.follower.Validate();
    if (!(c.unknown_fix_position_sigma_m > 0) || !(c.unknown_fix_heading_sigma_rad > 0)) {
      throw std::invalid_argument(
          "[tracker] unknown_fix_position_sigma_m and unknown_fix_heading_sigma_deg must be positive");
    }
    if (!(c.homing_arrived_magnitude >= 0)) throw std::invalid_argument("[homing] arrived_magnitude must be >= 0");
    if (!(c.status_period_s >= 0)) throw std::invalid_argument("[navigator] status_period_s must be >= 0");
    if (c.route_laps < 0) throw std::invalid_argument("[route] laps must be >= 0");
    if (const auto r = c.ConfiguredRoute()) {
      r->Validate();
      if (c.route_first_waypoint < 0 || c.route_first_waypoint >= static_cast<int>(r->waypoints.size())) {
        throw std::invalid_argument("[route] first_waypoint must be a waypoint of the route (0.." +
                                    std::to_string(r->waypoints.size() - 1) + ")");
      }
    } else if (!(c.route_tolerance_m > 0)) {
      throw std::invalid_argument("[route] tolerance_m must be positive");
    }
  } catch (const std::invalid_argument& e) {
    throw ini.ValidationError(e.what());
  }
  const std::pair<const char*, const std::string*> ins[] = {{"odometry", &c.odometry_channel},
                                                            {"pose", &c.pose_channel},
                                                            {"homing_vector", &c.homing_vector_channel},
                                                            {"route", &c.route_channel}};
  for (const auto& [in_key, in] : ins) {
    for (const auto& [out_key, out] :
         {std::pair<const char*, const std::string*>{"drive_command", &c.drive_command_channel},
          std::pair<const char*, const std::string*>{"status", &c.status_channel}}) {
      if (*in == *out) {
        throw ini.ValidationError(std::string("[channels] ") + out_key + " and " + in_key + " are both '" + *in +
                                  "': the output channels must differ from the inputs");
      }
    }
  }
  return c;
}

void NavigatorConfig::Print(std::ostream& out) const {
  out << "[channels]\nodometry = " << odometry_channel << "\npose = " << pose_channel
      << "\nhoming_vector = " << homing_vector_channel << "\nroute = " << route_channel
      << "\ndrive_command = " << drive_command_channel << "\nstatus = " << status_channel << "\n";
  for (const auto& [section, table] : Sections()) {
    out << "[" << section << "]\n";
    table.Print(out, *this);
  }
}

NavigatorNode::NavigatorNode(glue::Bus& bus, const NavigatorConfig& config)
    : bus_(bus), config_(config), tracker_(config.tracker), follower_(config.follower) {
  if (const auto route = config_.ConfiguredRoute()) {
    follower_.SetRoute(*route, config_.route_first_waypoint);
    ++routes_;
  }
  bus_.Subscribe(config_.odometry_channel, &NavigatorNode::OnOdometry, this, glue::Bus::kOdometryQueueCapacity);
  bus_.Subscribe(config_.pose_channel, &NavigatorNode::OnPose, this);
  bus_.Subscribe(config_.homing_vector_channel, &NavigatorNode::OnHomingVector, this);
  bus_.Subscribe(config_.route_channel, &NavigatorNode::OnRoute, this);
}

int64_t NavigatorNode::rejected_total() const {
  int64_t n = 0;
  for (const auto& [reason, count] : rejected_) n += count;
  return n;
}

void NavigatorNode::Reject(const std::string& reason, const std::string& detail) {
  ++rejected_[reason];
  bus_.CountDecodeError(reason + ": " + detail);  // per channel; printed to stderr, rate-limited
}

void NavigatorNode::OnOdometry(const odometry_t& msg) {
  const nav::Pose2 delta = glue::OdometryDelta(msg);
  if (!Finite(delta)) {
    Reject("non-finite odometry", "increment (" + std::to_string(delta.x_m) + ", " + std::to_string(delta.y_m) + ", " +
                                      std::to_string(delta.theta_rad) + ")");
    return;
  }
  if (const std::string problem = glue::OdometryProblem(msg, false); !problem.empty()) {
    Reject("absurd odometry", problem);
    return;
  }
  switch (odometry_clock_.Check(msg.utime)) {
    case glue::MessageClock::Verdict::kImplausible:
      Reject("implausible utime", "odometry at utime " + std::to_string(msg.utime));
      return;
    case glue::MessageClock::Verdict::kBackInTime:
      Reject("odometry back in time",
             "utime " + std::to_string(msg.utime) + " after " + std::to_string(*last_odometry_utime_));
      return;
    case glue::MessageClock::Verdict::kRestarted:
      std::cerr << "navigator: odometry time restarted at utime " << msg.utime << "\n";
      break;
    case glue::MessageClock::Verdict::kAccepted:
      break;
  }
  if (msg.utime < tracker_.utime()) {
    // A fix stamped later than this odometry came first: its time is kept, the increment is used.
    tracker_.AddOdometry(tracker_.utime(), delta);
  } else {
    tracker_.AddOdometry(msg.utime, delta);
  }
  last_odometry_utime_ = msg.utime;
  if (!follower_.has_route()) return;  // nothing to drive: no commands (a teleop may be driving)

  int8_t state;
  nav::DriveCommand command;
  if (!tracker_.initialized()) {
    state = navigator_status_t::WAITING_FOR_POSE;  // stand still until the first fix
    last_step_ = nav::FollowStep{};
    last_step_.waypoint = follower_.waypoint();
  } else {
    last_step_ = follower_.Update(msg.utime, tracker_.pose());
    if (last_step_.homing_used) ++homing_used_;
    if (last_step_.arrival != nav::ArrivalReason::kNone) {
      const auto& w = follower_.route().waypoints[last_step_.arrived_waypoint];
      std::cerr << "navigator: reached waypoint " << last_step_.arrived_waypoint << " (" << w.x() << ", " << w.y()
                << ") by " << nav::ArrivalReasonName(last_step_.arrival) << " at utime " << msg.utime
                << (last_step_.lap_completed ? ", lap " + std::to_string(follower_.laps()) + " completed" : "")
                << (follower_.state() == nav::FollowState::kFinished ? ", route finished" : "") << "\n";
    }
    command = last_step_.command;
    state = StateCode(last_step_.state);
  }
  drive_command_t cmd{};
  cmd.utime = msg.utime;
  cmd.source = "navigator";
  cmd.linear_velocity_mps = command.linear_mps;
  cmd.angular_velocity_radps = command.angular_radps;
  bus_.Publish(config_.drive_command_channel, cmd);
  last_command_ = command;
  ++commands_;
  if (!last_status_utime_ || msg.utime - *last_status_utime_ >= static_cast<int64_t>(config_.status_period_s * 1e6) ||
      last_step_.arrival != nav::ArrivalReason::kNone) {
    PublishStatus(msg.utime, state);
  }
}

void NavigatorNode::PublishStatus(int64_t utime, int8_t state) {
  navigator_status_t s{};
  s.utime = utime;
  s.state = state;
  const nav::Route& r = follower_.route();
  s.route_name = r.name;
  s.nwaypoints = static_cast<int32_t>(r.waypoints.size());
  s.waypoint_index = follower_.has_route() ? follower_.waypoint() : -1;
  s.laps = follower_.laps();
  s.arrivals = follower_.arrivals();
  if (s.waypoint_index >= 0) {
    const auto& w = r.waypoints[s.waypoint_index];
    s.waypoint_x_m = w.x();
    s.waypoint_y_m = w.y();
    if (tracker_.initialized())
      s.distance_to_waypoint_m = (w - Eigen::Vector2d(tracker_.pose().x_m, tracker_.pose().y_m)).norm();
  }
  s.heading_error_rad = last_step_.heading_error_rad;
  s.x_m = tracker_.pose().x_m;
  s.y_m = tracker_.pose().y_m;
  s.theta_rad = tracker_.pose().theta_rad;
  s.position_sigma_m = tracker_.initialized() ? tracker_.position_sigma_m() : 0;
  s.fixes_accepted = static_cast<int32_t>(tracker_.fixes_accepted());
  s.fixes_rejected = static_cast<int32_t>(tracker_.fixes_rejected());
  s.tracker_resets = static_cast<int32_t>(tracker_.resets());
  s.linear_velocity_mps = last_command_.linear_mps;
  s.angular_velocity_radps = last_command_.angular_radps;
  bus_.Publish(config_.status_channel, s);
  last_status_utime_ = utime;
  ++statuses_;
}

void NavigatorNode::OnPose(const pose_t& msg) {
  if (!glue::PlausibleUtime(msg.utime)) {
    Reject("implausible utime", "fix at utime " + std::to_string(msg.utime));
    return;
  }
  const nav::Pose2 pose = glue::FromPoseMsg(msg);
  if (!Finite(pose)) {
    Reject("non-finite pose", "from " + msg.estimator + " at utime " + std::to_string(msg.utime));
    return;
  }
  Eigen::Matrix3d cov = glue::CovarianceOf(msg);
  if (!cov.allFinite()) {
    Reject("non-finite covariance", "from " + msg.estimator + " at utime " + std::to_string(msg.utime));
    return;
  }
  if (cov(0, 0) < 0 || cov(1, 1) < 0 || cov(2, 2) < 0) {
    Reject("negative variance", "from " + msg.estimator + " at utime " + std::to_string(msg.utime));
    return;
  }
  if (cov.isZero(0)) {  // unknown: the configured uncertainty of a place-cell fix
    const double sp = config_.unknown_fix_position_sigma_m, sh = config_.unknown_fix_heading_sigma_rad;
    cov = Eigen::Vector3d(sp * sp, sp * sp, sh * sh).asDiagonal();
  }
  const nav::FixOutcome outcome = tracker_.AddFix(msg.utime, pose, cov);
  ++fixes_[nav::FixOutcomeName(outcome)];
  if (outcome == nav::FixOutcome::kInitialized || outcome == nav::FixOutcome::kReset) {
    std::cerr << "navigator: tracker " << (outcome == nav::FixOutcome::kReset ? "reset" : "initialised") << " at ("
              << pose.x_m << ", " << pose.y_m << ", " << pose.theta_rad / kDeg << " deg) from " << msg.estimator
              << " (utime " << msg.utime << ")\n";
  }
}

void NavigatorNode::OnHomingVector(const homing_vector_t& msg) {
  if (!msg.valid) {
    ++homing_invalid_;
    return;
  }
  if (!std::isfinite(msg.direction_rad) || !std::isfinite(msg.magnitude)) {
    Reject("non-finite homing vector", "utime " + std::to_string(msg.utime));
    return;
  }
  if (!glue::PlausibleUtime(msg.utime)) {
    Reject("implausible utime", "homing vector at utime " + std::to_string(msg.utime));
    return;
  }
  nav::HomingInput h;
  h.utime = msg.utime;
  h.direction_rad = msg.direction_rad;
  h.arrived = config_.homing_arrived_magnitude > 0 && msg.magnitude < config_.homing_arrived_magnitude;
  follower_.SetHoming(h);
}

void NavigatorNode::OnRoute(const waypoint_route_t& msg) {
  if (msg.nwaypoints <= 0) {
    Reject("empty route", "'" + msg.name + "' has " + std::to_string(msg.nwaypoints) + " waypoints");
    return;
  }
  nav::Route r;
  r.name = msg.name;
  r.loop = msg.loop;
  r.laps = config_.route_laps;
  r.tolerance_m = msg.tolerance_m;
  for (int i = 0; i < msg.nwaypoints; ++i) r.waypoints.emplace_back(msg.x_m[i], msg.y_m[i]);
  try {
    r.Validate();
  } catch (const std::invalid_argument& e) {
    Reject("invalid route", e.what());
    return;
  }
  follower_.SetRoute(r, 0);
  ++routes_;
  std::cerr << "navigator: route '" << r.name << "' with " << r.waypoints.size() << " waypoints"
            << (r.loop ? ", looping" : "") << ", tolerance " << r.tolerance_m << " m (utime " << msg.utime << ")\n";
}

void NavigatorNode::Report(std::ostream& out) const {
  out << "navigator: " << commands_ << " drive commands, " << statuses_ << " statuses, " << routes_ << " routes, "
      << follower_.arrivals() << " waypoints reached, " << follower_.laps() << " laps, state "
      << nav::FollowStateName(follower_.state()) << "\n";
  out << "navigator: fixes accepted " << tracker_.fixes_accepted() << ", rejected " << tracker_.fixes_rejected()
      << ", resets " << tracker_.resets() << "; homing vectors used in " << homing_used_ << " commands, "
      << homing_invalid_ << " invalid\n";
  for (const auto& [reason, count] : rejected_) out << "navigator: rejected " << count << " (" << reason << ")\n";
}

}  // namespace snapnav::processes
