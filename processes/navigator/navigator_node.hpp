#pragma once
// navigator: route following (thesis 5.1.2-5.1.3). Tracks the pose from ODOMETRY and place-cell
// fixes (POSE_PLACE_CELLS, pose_t with covariance), follows a route of waypoints (ROUTE, or one
// from the config: the thesis' figure 5.5 routes scaled to a square), steers the last part of
// each leg by HOMING_VECTOR when one is fresh, and publishes DRIVE_COMMAND and NAVIGATOR_STATUS.
//
// One drive command per odometry message while a route is set (zero until the first fix and
// after the route is finished), stamped with the odometry's utime: the simulator's lockstep
// mode waits for exactly that. Message time only, never the wall clock.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>

#include "snapnav/drive_command_t.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/message_clock.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/nav/places/navigator.hpp"
#include "snapnav/navigator_status_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"
#include "snapnav/waypoint_route_t.hpp"

namespace snapnav::processes {

struct NavigatorConfig {
  std::string odometry_channel;       // odometry_t in
  std::string pose_channel;           // pose_t in: place-cell fixes
  std::string homing_vector_channel;  // homing_vector_t in (optional input)
  std::string route_channel;          // waypoint_route_t in: replaces the route
  std::string drive_command_channel;  // drive_command_t out
  std::string status_channel;         // navigator_status_t out

  // The route at start: none (wait for ROUTE), or a thesis route scaled to the square.
  std::string route_source = "none";  // none | thesis1 | thesis2
  Eigen::Vector2d route_origin = Eigen::Vector2d::Zero();
  double route_size_m = 3.5;
  bool route_loop = true;
  int route_laps = 0;              // also applies to routes from ROUTE
  double route_tolerance_m = 0.1;  // of the configured route (a ROUTE message brings its own)
  int route_first_waypoint = 1;    // of the configured route: the robot starts on waypoint 0

  nav::PoseTrackerOptions tracker;
  double unknown_fix_position_sigma_m = 0.1;  // a fix with an all-zero covariance gets these
  double unknown_fix_heading_sigma_rad = 0.17;
  nav::FollowerOptions follower;
  double homing_arrived_magnitude = 0;  // a valid homing vector below this magnitude says "arrived"; 0: never
  double status_period_s = 0.5;         // status every this much message time; 0: with every command

  // The configured route (nullopt for none).
  std::optional<nav::Route> ConfiguredRoute() const;

  // Reads [channels], [route], [tracker], [follower], [homing], [navigator]; every key is
  // required, unknown keys and invalid values are glue::ConfigError.
  static NavigatorConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  // The effective configuration, as an INI file FromIni reads back (channels with their prefix).
  void Print(std::ostream& out) const;
};

class NavigatorNode {
 public:
  // Subscribes to the odometry, pose, homing vector and route channels; takes the configured route.
  NavigatorNode(glue::Bus& bus, const NavigatorConfig& config);

  const nav::PoseTracker& tracker() const { return tracker_; }
  const nav::RouteFollower& follower() const { return follower_; }
  int64_t commands() const { return commands_; }
  int64_t statuses() const { return statuses_; }
  int64_t routes() const { return routes_; }                  // routes taken (configured one included)
  int64_t homing_used() const { return homing_used_; }        // valid homing vectors handed to the follower
  int64_t homing_invalid() const { return homing_invalid_; }  // homing vectors with valid = false
  // Fix outcomes by name ("initialized", "accepted", "reset", "gate", "stale").
  const std::map<std::string, int64_t>& fixes() const { return fixes_; }
  // Messages skipped, by reason ("non-finite pose", "empty route", ...).
  const std::map<std::string, int64_t>& rejected() const { return rejected_; }
  int64_t rejected_total() const;
  // The node's counts, one line each.
  void Report(std::ostream& out) const;

 private:
  void OnOdometry(const odometry_t& msg);
  void OnPose(const pose_t& msg);
  void OnHomingVector(const homing_vector_t& msg);
  void OnRoute(const waypoint_route_t& msg);
  void Reject(const std::string& reason, const std::string& detail);
  void PublishStatus(int64_t utime, int8_t state);

  glue::Bus& bus_;
  NavigatorConfig config_;
  nav::PoseTracker tracker_;
  nav::RouteFollower follower_;
  nav::FollowStep last_step_;
  nav::DriveCommand last_command_;
  std::optional<int64_t> last_odometry_utime_;
  glue::MessageClock odometry_clock_;
  std::optional<int64_t> last_status_utime_;
  int64_t commands_ = 0, statuses_ = 0, routes_ = 0, homing_used_ = 0, homing_invalid_ = 0;
  std::map<std::string, int64_t> fixes_;
  std::map<std::string, int64_t> rejected_;
};

}  // namespace snapnav::processes
