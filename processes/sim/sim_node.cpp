#include "sim_node.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::processes {
namespace {

constexpr double kDeg = M_PI / 180.0;

int EveryNSteps(double physics_hz, double rate_hz, const char* what) {
  const double n = physics_hz / rate_hz;
  if (std::abs(n - std::round(n)) > 1e-6 || n < 1) {
    throw std::invalid_argument(std::string(what) + " must divide [sim] physics_rate_hz");
  }
  return static_cast<int>(std::round(n));
}

// The keys of [sim], [camera], [effects], [laser] and [robot], declared once: read, printed and
// described from here ([mirror] and [panorama] are glue's; the presets' derived options are set
// after reading).
using Table = glue::OptionTable<SimConfig>;

const Table& SimTable() {
  using C = SimConfig;
  static const auto table =
      Table()
          .Text("scene", &C::scene)
          .Number("seed", "", &C::seed)
          .Choice("mode", &C::realtime, std::vector<std::pair<std::string, bool>>{{"realtime", true}, {"lockstep", false}})
          .Number("realtime_factor", "", &C::realtime_factor)
          .Number("duration_s", "s", &C::duration_s)
          .Custom(
              "start_time_s", "s",
              [](const glue::IniFile& ini, const std::string& s, const std::string& k, C& c) {
                c.start_at_wall_clock = ini.GetString(s, k) == "now";
                if (!c.start_at_wall_clock) c.start_utime = static_cast<int64_t>(ini.GetDouble(s, k) * 1e6);
              },
              [](std::ostream& out, const C& c) {
                if (c.start_at_wall_clock) {
                  out << "now";
                } else {
                  out << c.start_utime / 1'000'000;
                  if (c.start_utime % 1'000'000) out << "." << std::setw(6) << std::setfill('0') << c.start_utime % 1'000'000 << std::setfill(' ');
                }
              })
          .Custom(
              "clock_offset_s", "s",
              [](const glue::IniFile& ini, const std::string& s, const std::string& k, C& c) {
                c.clock_offset_us = std::llround(ini.GetDouble(s, k) * 1e6);
              },
              [](std::ostream& out, const C& c) { out << c.clock_offset_us * 1e-6; })
          .Number("physics_rate_hz", "Hz", &C::physics_rate_hz)
          .Text("drive", &C::drive)
          .Number("route_speed_mps", "m/s", &C::route_speed_mps)
          .Number("route_tolerance_m", "m", &C::route_tolerance_m)
          .Flag("route_loop", &C::route_loop)
          .Number("command_timeout_s", "s", &C::command_timeout_s)
          .Number("command_watchdog_s", "s", &C::command_watchdog_s)
          .Number("command_max_age_s", "s", &C::command_max_age_s);
  return table;
}

const Table& CameraTable() {
  using C = SimConfig;
  static const auto table =
      Table()
          .Text("preset", &C::camera_preset)
          .Number("rate_hz", "Hz", &C::camera_rate_hz)
          .Flag("publish_raw", &C::publish_raw)
          .Flag("publish_panorama", &C::publish_panorama)
          .Custom(
              "encoding", "",
              [](const glue::IniFile& ini, const std::string& s, const std::string& k, C& c) {
                try {
                  c.encoding = glue::ParseFrameEncoding(ini.GetString(s, k));
                } catch (const std::invalid_argument& e) {
                  ini.FailKey(s, k, e.what());
                }
              },
              [](std::ostream& out, const C& c) { out << glue::FrameEncodingName(c.encoding); })
          .Number("jpeg_quality", "", &C::jpeg_quality)
          .Number("width_px", "px", [](auto& c) -> auto& { return c.camera.omni_width_px; })
          .Number("height_px", "px", [](auto& c) -> auto& { return c.camera.omni_height_px; })
          .Number("height_m", "m", [](auto& c) -> auto& { return c.camera.height_m; })
          .Number("offset_x_m", "m", [](auto& c) -> auto& { return c.camera.offset_x_m; });
  return table;
}

const Table& EffectsTable() {
  static const auto table =
      Table()
          .Number("blur_sigma_px", "px", [](auto& c) -> auto& { return c.effects.blur_sigma_px; })
          .Number("noise_sigma", "grey", [](auto& c) -> auto& { return c.effects.noise_sigma; })
          .Number("salt_pepper_fraction", "", [](auto& c) -> auto& { return c.effects.salt_pepper_fraction; })
          .Number("illumination_gain", "", [](auto& c) -> auto& { return c.effects.gain; })
          .Number("illumination_offset", "grey", [](auto& c) -> auto& { return c.effects.offset; });
  return table;
}

const Table& LaserTable() {
  using C = SimConfig;
  static const auto table = Table()
                                .Number("rate_hz", "Hz", &C::laser_rate_hz)
                                .Number("beams", "", [](auto& c) -> auto& { return c.laser.beams; })
                                .Degrees("angle_min_deg", [](auto& c) -> auto& { return c.laser.angle_min_rad; })
                                .Degrees("angle_max_deg", [](auto& c) -> auto& { return c.laser.angle_max_rad; })
                                .Number("range_min_m", "m", [](auto& c) -> auto& { return c.laser.range_min_m; })
                                .Number("range_max_m", "m", [](auto& c) -> auto& { return c.laser.range_max_m; })
                                .Number("range_noise_m", "m", [](auto& c) -> auto& { return c.laser.range_noise_m; })
                                .Number("mount_height_m", "m", [](auto& c) -> auto& { return c.laser.mount_height_m; })
                                .Number("mount_x_m", "m", [](auto& c) -> auto& { return c.laser.mount_x_m; })
                                .Text("preset", &C::laser_preset);
  return table;
}

const Table& RobotTable() {
  using C = SimConfig;
  static const auto table =
      Table()
          .Number("odometry_rate_hz", "Hz", &C::odometry_rate_hz)
          .Number("max_linear_mps", "m/s", [](auto& c) -> auto& { return c.drive_options.max_linear_mps; })
          .Number("max_angular_radps", "rad/s", [](auto& c) -> auto& { return c.drive_options.max_angular_radps; })
          .Number("heading_drift_deg_per_m", "deg/m", [](auto& c) -> auto& { return c.drive_options.heading_drift_deg_per_m; })
          .Number("linear_noise_frac", "", [](auto& c) -> auto& { return c.drive_options.linear_noise_frac; })
          .Number("angular_noise_radps", "rad/s", [](auto& c) -> auto& { return c.drive_options.angular_noise_radps; })
          .Number("odometry_linear_noise_frac", "", [](auto& c) -> auto& { return c.drive_options.odometry_linear_noise_frac; })
          .Number("odometry_angular_noise_frac", "", [](auto& c) -> auto& { return c.drive_options.odometry_angular_noise_frac; })
          .Number("radius_m", "m", [](auto& c) -> auto& { return c.drive_options.robot_radius_m; })
          .Number("kidnap_at_s", "s", [](auto& c) -> auto& { return c.kidnap.at_s; })
          .Custom(
              "kidnap_to", "m,m,deg",
              [](const glue::IniFile& ini, const std::string& s, const std::string& k, C& c) {
                const std::vector<double> to = ini.GetDoubleList(s, k);
                if (to.size() != 3) {
                  ini.FailKey(s, k, "expected x_m,y_m,theta_deg (3 values, got " + std::to_string(to.size()) + ")");
                }
                c.kidnap.to = {to[0], to[1], to[2] * kDeg};
              },
              [](std::ostream& out, const C& c) {
                out << c.kidnap.to.x_m << "," << c.kidnap.to.y_m << "," << c.kidnap.to.theta_rad / kDeg;
              });
  return table;
}

}  // namespace

SimConfig SimConfig::FromIni(const glue::IniFile& ini, const std::string& prefix) {
  SimConfig c;
  SimTable().ReadKeys(ini, "sim", &c);
  CameraTable().ReadKeys(ini, "camera", &c);
  auto& cam = c.camera;
  cam.mirror = glue::ReadMirrorConfig(ini);
  cam.panorama = glue::ReadPanoramaConfig(ini);
  try {
    cam.optics = nav::sim::CameraOpticsPreset(c.camera_preset);
  } catch (const std::invalid_argument& e) {
    ini.FailKey("camera", "preset", e.what());
  }
  cam.optics.seed = c.seed ^ 0x0b71c5ULL;  // the sensor noise follows the seed
  // The realistic camera compresses its own frames (an MJPEG camera) at the frames' quality.
  if (cam.optics.enabled) cam.optics.jpeg_quality = c.jpeg_quality;
  EffectsTable().ReadKeys(ini, "effects", &c);
  LaserTable().ReadKeys(ini, "laser", &c);
  try {
    c.laser.faults = nav::sim::LaserFaultsPreset(c.laser_preset);
  } catch (const std::invalid_argument& e) {
    ini.FailKey("laser", "preset", e.what());
  }
  RobotTable().ReadKeys(ini, "robot", &c);

  c.omni_channel = prefix + ini.GetString("channels", "omni");
  c.panorama_channel = prefix + ini.GetString("channels", "panorama");
  c.scan_channel = prefix + ini.GetString("channels", "scan");
  c.odometry_channel = prefix + ini.GetString("channels", "odometry");
  c.ground_truth_channel = prefix + ini.GetString("channels", "ground_truth");
  c.command_channel = prefix + ini.GetString("channels", "drive_command");
  ini.CheckAllUsed();
  ini.Check([&c] { c.Validate(); });
  return c;
}

void SimConfig::Validate() const {
  if (drive != "route" && drive != "grid" && drive != "commands" && drive != "still") {
    throw std::invalid_argument("drive must be route, grid, commands or still");
  }
  if (!(physics_rate_hz > 0)) throw std::invalid_argument("[sim] physics_rate_hz must be positive");
  if (!(camera_rate_hz > 0)) throw std::invalid_argument("[camera] rate_hz must be positive");
  if (!(laser_rate_hz > 0)) throw std::invalid_argument("[laser] rate_hz must be positive");
  if (!(odometry_rate_hz > 0)) throw std::invalid_argument("[robot] odometry_rate_hz must be positive");
  if (std::abs(1e6 / physics_rate_hz - std::round(1e6 / physics_rate_hz)) > 1e-9) {
    throw std::invalid_argument("physics_rate_hz must give a whole number of microseconds per step");
  }
  EveryNSteps(physics_rate_hz, camera_rate_hz, "[camera] rate_hz");
  EveryNSteps(physics_rate_hz, laser_rate_hz, "[laser] rate_hz");
  EveryNSteps(physics_rate_hz, odometry_rate_hz, "[robot] odometry_rate_hz");
  if (!(duration_s >= 0)) throw std::invalid_argument("duration_s must be >= 0");
  if (!(realtime_factor >= 0.01 && realtime_factor <= 100)) throw std::invalid_argument("realtime_factor must be in 0.01..100");
  if (!(command_watchdog_s >= 0) || !(command_max_age_s >= 0)) {
    throw std::invalid_argument("command_watchdog_s and command_max_age_s must be >= 0 (0: off)");
  }
  // (No std::abs: a value beyond int64's range arrives as its most negative value, whose negation overflows.)
  constexpr int64_t kDayUs = int64_t{86'400} * 1'000'000;
  if (clock_offset_us < -kDayUs || clock_offset_us > kDayUs) {
    throw std::invalid_argument("clock_offset_s must be within a day");
  }
  if (!publish_raw && !publish_panorama) {
    throw std::invalid_argument("[camera] publish_raw and publish_panorama are both false: publish at least one");
  }
  if (jpeg_quality < 1 || jpeg_quality > 100) throw std::invalid_argument("jpeg_quality must be in 1..100");
  camera.Validate();
  effects.Validate();
  laser.Validate();
  drive_options.Validate();
  kidnap.Validate();
}

void SimConfig::Print(std::ostream& o) const {
  o << "[sim]\n";
  SimTable().Print(o, *this);
  o << "[camera]\n";
  CameraTable().Print(o, *this);
  if (camera.optics.enabled) {
    o << "; the realistic camera: auto-exposure " << (camera.optics.auto_exposure ? "on" : "off") << " (target grey "
      << static_cast<int>(camera.optics.exposure_target_grey) << "), own JPEG quality " << camera.optics.jpeg_quality
      << ", shutter " << std::lround(camera.optics.exposure_time_s * 1000) << " ms (motion blur), calibration off by ("
      << camera.optics.calibration_error_x_px << ", " << camera.optics.calibration_error_y_px << ") px\n";
  }
  glue::PrintMirrorConfig(o, camera.mirror);
  glue::PrintPanoramaConfig(o, camera.panorama);
  o << "[effects]\n";
  EffectsTable().Print(o, *this);
  o << "[laser]\n";
  LaserTable().Print(o, *this);
  if (laser.faults.enabled) {
    o << "; the realistic laser: range x" << laser.faults.range_scale << " + " << laser.faults.range_bias_m
      << " m, mixed pixels at edges over " << laser.faults.mixed_pixel_jump_m << " m, no return from surfaces darker than grey "
      << static_cast<int>(laser.faults.dark_grey) << ", people as legs\n";
  }
  o << "[robot]\n";
  RobotTable().Print(o, *this);
  o << "[channels]\nomni = " << omni_channel << "\npanorama = " << panorama_channel << "\nscan = " << scan_channel
    << "\nodometry = " << odometry_channel << "\nground_truth = " << ground_truth_channel
    << "\ndrive_command = " << command_channel << "\n";
}

SimNode::SimNode(glue::Bus& bus, const SimConfig& config, const nav::sim::Scene& scene)
    : bus_(bus),
      config_(config),
      scene_(scene),
      world_(scene, config.drive_options, config.laser, config.seed),
      renderer_(scene, config.camera),
      effects_rng_(config.seed ^ 0x9e3779b97f4a7c15ULL) {
  config_.Validate();
  reported_mirror_ = config_.camera.ReportedMirror();
  start_utime_ = (config_.start_at_wall_clock ? glue::WallUtime() : config_.start_utime) + config_.clock_offset_us;
  dt_us_ = static_cast<int64_t>(std::llround(1e6 / config_.physics_rate_hz));
  camera_every_ = EveryNSteps(config_.physics_rate_hz, config_.camera_rate_hz, "camera");
  laser_every_ = EveryNSteps(config_.physics_rate_hz, config_.laser_rate_hz, "laser");
  odometry_every_ = EveryNSteps(config_.physics_rate_hz, config_.odometry_rate_hz, "odometry");
  if (config_.drive == "route") {
    if (scene.route.empty()) throw std::invalid_argument("scene '" + scene.name + "' has no route for drive = route");
    route_.emplace(scene.route, config_.route_speed_mps, config_.route_tolerance_m, config_.route_loop);
  }
  if (config_.drive == "grid") {
    // An exploration drive: every grid node as a waypoint, row by row, each row the other way
    // round (boustrophedon), once.
    if (scene.grid.nx < 1 || scene.grid.ny < 1) throw std::invalid_argument("scene '" + scene.name + "' has no grid for drive = grid");
    std::vector<Eigen::Vector2d> nodes;
    for (int iy = 0; iy < scene.grid.ny; ++iy) {
      for (int k = 0; k < scene.grid.nx; ++k) nodes.push_back(scene.grid.Position(iy % 2 == 0 ? k : scene.grid.nx - 1 - k, iy));
    }
    route_.emplace(nodes, config_.route_speed_mps, config_.route_tolerance_m, false);
  }
  if (config_.drive == "commands") bus_.Subscribe(config_.command_channel, &SimNode::OnDriveCommand, this);
  world_.SetKidnap(config_.kidnap);  // throws when the robot does not fit at the destination
}

int64_t SimNode::utime() const { return start_utime_ + step_ * dt_us_; }

void SimNode::OnDriveCommand(const drive_command_t& msg) {
  if (!std::isfinite(msg.linear_velocity_mps) || !std::isfinite(msg.angular_velocity_radps)) {
    throw std::invalid_argument("drive command is not finite");
  }
  // A command is answered to this robot's own sensor time: one stamped far from it comes from
  // elsewhere (a replayed log, another robot's controller, a clock that is off) and is not obeyed.
  const double age_s = (utime() - msg.utime) * 1e-6;
  if (config_.command_max_age_s > 0 && std::abs(age_s) > config_.command_max_age_s) {
    if (++stale_commands_ <= 5 || stale_commands_ % 100 == 0) {
      std::cerr << "sim: ignored drive command #" << stale_commands_ << " from '" << msg.source << "': stamped "
                << std::fixed << std::setprecision(3) << -age_s << " s from the robot's clock (command_max_age_s "
                << config_.command_max_age_s << ")\n";
    }
    return;
  }
  cmd_linear_ = msg.linear_velocity_mps;
  cmd_angular_ = msg.angular_velocity_radps;
  last_command_utime_ = msg.utime;
  last_command_arrival_utime_ = utime();
  ++commands_;
}

void SimNode::CheckWatchdog() {
  if (config_.command_watchdog_s <= 0 || (cmd_linear_ == 0 && cmd_angular_ == 0)) return;
  const int64_t since = last_command_arrival_utime_ < 0 ? utime() - start_utime_ : utime() - last_command_arrival_utime_;
  if (since <= static_cast<int64_t>(config_.command_watchdog_s * 1e6)) return;
  cmd_linear_ = cmd_angular_ = 0;
  ++watchdog_stops_;
  std::cerr << "sim: watchdog: no drive command for " << std::fixed << std::setprecision(2) << since * 1e-6
            << " s at t=" << (utime() - start_utime_) * 1e-6 << " s: robot stopped (command_watchdog_s "
            << config_.command_watchdog_s << ")\n";
}

void SimNode::WaitForCommand() {
  // Lockstep with a controller: it answers each frame with a command stamped at least the frame's utime.
  const int64_t deadline = glue::MonotonicUtime() + static_cast<int64_t>(config_.command_timeout_s * 1e6);
  while (last_command_utime_ < utime() && !glue::ShutdownRequested() && glue::MonotonicUtime() < deadline) {
    bus_.HandleOnce(5);
  }
}

void SimNode::PublishFrames() {
  const nav::Pose2& pose = world_.true_pose();
  auto publish = [&](const std::string& channel, bool raw) {
    // A camera that compresses its own frames, published as JPEG with no [effects] on top: the
    // frame carries the camera's bytes as an MJPEG camera's driver passes them on (no re-encoding).
    const bool camera_jpeg = raw && config_.camera.optics.enabled && config_.camera.optics.jpeg_quality > 0 &&
                             config_.encoding == omni_frame_t::JPEG && config_.effects.IsIdentity();
    omni_frame_t f{};
    if (raw) {
      renderer_.RenderOmni(pose, world_.people(), &image_, {cmd_linear_, cmd_angular_}, camera_jpeg ? &jpeg_ : nullptr);
    } else {
      renderer_.RenderPanorama(pose, world_.people(), &image_);
    }
    if (camera_jpeg) {
      f.width = image_.cols;
      f.height = image_.rows;
      f.row_stride = 0;
      f.encoding = omni_frame_t::JPEG;
      f.data = jpeg_;
      f.data_size = static_cast<int32_t>(f.data.size());
    } else {
      nav::sim::ApplyImageEffects(config_.effects, effects_rng_, &image_);
      f = glue::ImageToFrame(image_, config_.encoding, config_.jpeg_quality);
    }
    f.utime = utime();
    f.sensor_name = "sim_omni";
    f.kind = raw ? omni_frame_t::RAW_OMNI : omni_frame_t::PANORAMA;
    if (raw) {
      glue::SetMirror(reported_mirror_, &f);  // off by a few pixels with the realistic optics
    } else {
      glue::SetPanorama(config_.camera.panorama, &f);
    }
    if (raw && frame_times_) *frame_times_ << f.utime << "," << glue::WallUtime() << "\n";
    bus_.Publish(channel, f);
  };
  if (config_.publish_raw) publish(config_.omni_channel, true);
  if (config_.publish_panorama) publish(config_.panorama_channel, false);
  ++frames_;
}

void SimNode::PublishScan() {
  laser_scan_t s{};
  s.utime = utime();
  s.sensor_name = "sim_hokuyo";
  s.sensor_x_m = static_cast<float>(config_.laser.mount_x_m);
  s.sensor_y_m = 0;
  s.sensor_theta_rad = 0;
  s.angle_min_rad = static_cast<float>(config_.laser.angle_min_rad);
  s.angle_increment_rad = static_cast<float>(config_.laser.AngleIncrement());
  s.time_increment_s = 0;
  s.range_min_m = static_cast<float>(config_.laser.range_min_m);
  s.range_max_m = static_cast<float>(config_.laser.range_max_m);
  s.ranges_m = world_.Scan();
  s.nranges = static_cast<int32_t>(s.ranges_m.size());
  s.nintensities = 0;
  bus_.Publish(config_.scan_channel, s);
  ++scans_;
}

void SimNode::PublishOdometry() {
  const nav::sim::OdometryReading r = world_.TakeOdometry();
  const odometry_t o = glue::ToOdometryMsg(utime(), "sim_wheels", r.cumulative, r.delta, r.dt_s);
  bus_.Publish(config_.odometry_channel, o);
  bus_.Publish(config_.ground_truth_channel,
               glue::ToPoseMsg(utime(), "ground_truth", "map", world_.true_pose(), Eigen::Matrix3d::Zero()));
  ++odometry_;
}

bool SimNode::Step() {
  if (config_.duration_s > 0 && step_ * dt_us_ >= static_cast<int64_t>(config_.duration_s * 1e6)) return false;
  if (route_ && route_->finished()) return false;
  // Sensors first: what the robot sees at time t, then it moves to t + dt.
  if (step_ % odometry_every_ == 0) PublishOdometry();
  if (step_ % laser_every_ == 0) PublishScan();
  if (step_ % camera_every_ == 0) {
    PublishFrames();
    if (config_.drive == "commands" && !config_.realtime) WaitForCommand();
  }
  if (config_.drive == "commands") {
    while (bus_.HandleOnce(0)) {
    }
    CheckWatchdog();
  } else if (route_) {
    const Eigen::Vector2d cmd = route_->Command(world_.true_pose());
    cmd_linear_ = cmd.x();
    cmd_angular_ = cmd.y();
  }
  world_.Step(cmd_linear_, cmd_angular_, dt_us_ * 1e-6);
  if (world_.kidnapped() && !route_restarted_) {
    route_restarted_ = true;  // carried off: the scripted driver goes on from the nearest waypoint ahead
    if (route_) route_->Restart(world_.true_pose());
  }
  ++step_;
  return true;
}

void SimNode::Run(std::ostream* progress) {
  const int64_t wall_start = glue::MonotonicUtime();
  int64_t next_report_s = 10;
  while (!glue::ShutdownRequested()) {
    if (config_.realtime) {
      // Simulated time runs realtime_factor times as fast as the wall clock (1: a live robot).
      const int64_t due = wall_start + std::llround(static_cast<double>(step_ * dt_us_) / config_.realtime_factor);
      for (int64_t now = glue::MonotonicUtime(); now < due; now = glue::MonotonicUtime()) {
        bus_.HandleOnce(static_cast<int>(std::max<int64_t>(1, (due - now) / 1000)));
      }
    }
    if (!Step()) break;
    const double t = step_ * dt_us_ * 1e-6;
    if (progress && t >= next_report_s) {
      const nav::Pose2& p = world_.true_pose();
      *progress << "sim: t=" << std::fixed << std::setprecision(1) << t << " s  frames " << frames_ << "  scans "
                << scans_ << "  pose (" << std::setprecision(2) << p.x_m << ", " << p.y_m << ", "
                << p.theta_rad / kDeg << " deg)  distance " << world_.distance_m() << " m  wall "
                << (glue::MonotonicUtime() - wall_start) * 1e-6 << " s\n";
      next_report_s += 10;
    }
  }
}

}  // namespace snapnav::processes
