#pragma once
// sim: the simulated lab. Moves a differential-drive robot through a scene
// (following DRIVE_COMMAND or its scripted route) and publishes what its
// sensors see, with the ground truth: OMNI_FRAME (raw catadioptric) and/or
// OMNI_PANORAMA, LASER_SCAN, ODOMETRY, POSE_GROUND_TRUTH.

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "snapnav/drive_command_t.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::processes {

struct SimConfig {
  std::string scene = "indoor13";     // scene name (config/scenes/NAME.scene) or path
  uint64_t seed = 1;
  bool realtime = false;              // false: lockstep, as fast as possible
  double realtime_factor = 1.0;       // realtime: simulated seconds per wall-clock second (< 1: slower than life)
  double duration_s = 60;             // simulated time to run; 0: until stopped
  int64_t start_utime = 1'700'000'000'000'000;  // utime of the first message [us] (without the offset)
  bool start_at_wall_clock = false;   // start_time_s = now: the first message is stamped with the wall clock
  int64_t clock_offset_us = 0;        // added to every utime: a robot whose clock is off [us]
  double physics_rate_hz = 100;
  std::string drive = "route";        // route | grid | commands | still
  double route_speed_mps = 0.3;
  double route_tolerance_m = 0.1;
  bool route_loop = true;
  double command_timeout_s = 1.0;     // lockstep + commands: longest wait for a command per frame (wall clock)
  double command_watchdog_s = 0.5;    // commands: no accepted command for this long (robot time) stops the robot; 0: off
  double command_max_age_s = 1.0;     // commands: one stamped further than this from the robot's clock is ignored; 0: off

  double camera_rate_hz = 10;
  bool publish_raw = true;
  bool publish_panorama = false;
  int8_t encoding = 1;                // omni_frame_t::RGB8
  int jpeg_quality = 90;
  nav::sim::OmniCameraOptions camera;  // camera.optics: the [camera] preset's (clean: none)
  std::string camera_preset = "clean";  // clean | realistic (docs/simulator.md)
  std::string laser_preset = "clean";   // clean | realistic: laser.faults (docs/simulator.md)
  nav::sim::ImageEffectsOptions effects;

  double laser_rate_hz = 10;
  nav::sim::LaserOptions laser;
  double odometry_rate_hz = 50;
  nav::sim::DriveOptions drive_options;
  nav::sim::KidnapOptions kidnap;     // [robot] kidnap_at_s, kidnap_to (x_m, y_m, theta_deg); disabled by default

  std::string omni_channel, panorama_channel, scan_channel, odometry_channel, ground_truth_channel, command_channel;

  // Reads every section of config/sim.ini; a missing or unknown key is an error.
  static SimConfig FromIni(const glue::IniFile& ini, const std::string& channel_prefix);
  void Validate() const;  // throws std::invalid_argument
  void Print(std::ostream& out) const;
};

class SimNode {
 public:
  SimNode(glue::Bus& bus, const SimConfig& config, const nav::sim::Scene& scene);

  // From now on, one CSV line "utime,publish_utime" per raw frame: its stamp and the wall-clock
  // time when it was handed to the bus (null: none). Another process of the same clock that
  // notes its arrival gets the frame's time on the bus.
  void LogFramePublishTimes(std::ostream* out) { frame_times_ = out; }

  // Runs until duration_s of simulated time, the end of the route, or shutdown.
  void Run(std::ostream* progress);
  // One physics step, publishing the sensors that are due. Returns false when done.
  bool Step();

  int64_t utime() const;
  const nav::sim::World& world() const { return world_; }
  int64_t frames() const { return frames_; }
  int64_t scans() const { return scans_; }
  int64_t odometry_messages() const { return odometry_; }
  int64_t commands() const { return commands_; }              // accepted drive commands
  int64_t stale_commands() const { return stale_commands_; }  // ignored: stamped too far from the robot's clock
  int64_t watchdog_stops() const { return watchdog_stops_; }  // the robot stopped because commands stopped
  int64_t start_utime() const { return start_utime_; }        // utime of the first message

 private:
  void OnDriveCommand(const drive_command_t& msg);
  void PublishFrames();
  void PublishScan();
  void PublishOdometry();
  void WaitForCommand();
  void CheckWatchdog();

  glue::Bus& bus_;
  std::ostream* frame_times_ = nullptr;
  SimConfig config_;
  const nav::sim::Scene& scene_;
  nav::sim::World world_;
  nav::sim::OmniRenderer renderer_;
  std::optional<nav::sim::RouteDriver> route_;
  int64_t step_ = 0;
  int64_t dt_us_ = 0;
  int camera_every_ = 1, laser_every_ = 1, odometry_every_ = 1;
  double cmd_linear_ = 0, cmd_angular_ = 0;
  int64_t start_utime_ = 0;
  int64_t last_command_utime_ = -1;          // the newest accepted command's stamp
  int64_t last_command_arrival_utime_ = -1;  // robot time when it arrived
  int64_t frames_ = 0, scans_ = 0, odometry_ = 0, commands_ = 0, stale_commands_ = 0, watchdog_stops_ = 0;
  std::mt19937_64 effects_rng_;
  nav::MirrorModel reported_mirror_;  // the calibration the raw frames carry
  cv::Mat image_;
  std::vector<uint8_t> jpeg_;  // the realistic camera's own JPEG of the last frame
  bool route_restarted_ = false;  // the route driver went on after the kidnapping
};

}  // namespace snapnav::processes
