// map-export (./snapnav map export LOG --out DIR): the occupancy grid of a recorded run as the files
// labs' other tools read: ROS map_server's map.pgm + map.yaml, MRPT's map.gridmap and
// map.simplemap (pf-localization, the map viewers), and map.png with the trajectory.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>

#include "slam_config.hpp"
#include "slam_graph.hpp"
#include "slam_log.hpp"
#include "map_export.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/grid_scan_msg.hpp"
#include "snapnav/glue/occupancy_grid_msg.hpp"
#include "snapnav/map_request_t.hpp"
#include "snapnav/occupancy_grid_t.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/log_reader.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/pose_correction_t.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/slam/occupancy_grid.hpp"
#include "snapnav/pose_t.hpp"

namespace {

using namespace snapnav;

// The poses of `channel` in the log, by utime, as the last correction table for them on
// `correction_channel` puts them (laser-slam's graph back end moves its past poses when it closes a loop).
std::map<int64_t, nav::Pose2> ReadPoses(const std::string& path, const std::string& channel,
                                        const std::string& correction_channel, int* rejected) {
  glue::LogReader file(path);
  glue::LogEvent e;
  std::map<int64_t, nav::Pose2> poses;
  glue::PoseCorrections corrections(channel);
  int bad_corrections = 0;
  while (file.Next(&e)) {
    if (!correction_channel.empty() && e.channel == correction_channel) {
      std::string error;
      const auto c = glue::Decode<pose_correction_t>(e.data.data(), e.data.size(), &error);
      if (!c || corrections.Take(*c, &error) == glue::PoseCorrections::Taken::kInvalid) {
        ++bad_corrections;
        std::cerr << "map-export: " << path << ": a pose correction at byte " << e.offset << " refused: " << error << "\n";
      }
      continue;
    }
    if (e.channel != channel) continue;
    std::string error;
    const auto p = glue::Decode<pose_t>(e.data.data(), e.data.size(), &error);
    if (!p || !std::isfinite(p->x_m) || !std::isfinite(p->y_m) || !std::isfinite(p->theta_rad)) {
      ++*rejected;
      continue;
    }
    poses[p->utime] = {p->x_m, p->y_m, p->theta_rad};
  }
  if (corrections.tables() > 0) {
    for (auto& [utime, pose] : poses) pose = corrections.Correct(utime, pose);
    std::cerr << "map-export: the poses of " << channel << " as correction " << corrections.corrections() << " on "
              << correction_channel << " puts them (" << corrections.tables() << " tables, the last of "
              << corrections.ranges() << " ranges; " << bad_corrections << " refused)\n";
  }
  return poses;
}

// --live: the next grid on `channel` (after a request on `request_channel`, repeated every 2 s),
// written as the same files but the simplemap and the trajectory (a grid holds no scans).
int ExportLive(const std::string& url, const std::string& channel, const std::string& request_channel, double timeout_s,
               const std::string& out_dir, const std::string& name, const nav::OccupancyGridOptions& grid_options) {
  glue::Bus bus(url);
  std::optional<occupancy_grid_t> grid;
  std::map<std::string, int64_t> malformed;
  bus.Subscribe<occupancy_grid_t>(channel, [&](const occupancy_grid_t& msg) {
    if (grid) return;
    if (const auto problem = glue::CheckOccupancyGrid(msg)) {
      if (++malformed[problem->reason] <= 3) std::cerr << "map-export: refused a grid on " << channel << " (" << problem->reason << "): " << problem->detail << "\n";
      return;
    }
    if (msg.origin_theta_rad != 0) {
      if (++malformed["rotated grid"] <= 3) std::cerr << "map-export: refused a grid on " << channel << ": origin_theta_rad " << msg.origin_theta_rad << " (only 0: map_server's YAML)\n";
      return;
    }
    grid = msg;
  });
  std::cerr << "map-export: waiting up to " << timeout_s << " s for an occupancy grid on " << channel
            << (request_channel.empty() ? std::string() : ", asking on " + request_channel) << " (" << bus.url() << ")\n";
  const auto start = std::chrono::steady_clock::now();
  auto last_request = start - std::chrono::hours(1);
  while (!grid) {
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - start).count() > timeout_s) break;
    if (!request_channel.empty() && now - last_request >= std::chrono::seconds(2)) {
      map_request_t r{};
      r.utime = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
      r.requester = "map-export";
      bus.Publish(request_channel, r);
      last_request = now;
    }
    bus.HandleOnce(100);
  }
  int64_t refused = 0;
  for (const auto& [_, n] : malformed) refused += n;
  if (!grid) {
    throw std::runtime_error("no occupancy grid on " + channel + " within " + std::to_string(timeout_s) + " s (" +
                             std::to_string(refused) + " malformed ones refused; is laser-slam running with a grid channel?)");
  }
  nav::OccupancyCells cells = glue::FromOccupancyGridMsg(*grid, grid_options.occupied_threshold, grid_options.free_threshold);
  const std::filesystem::path out(out_dir);
  map::WriteRosMap(cells, grid_options, out_dir, name);
  map::WriteGridmap(nav::FromOccupancyCells(cells), (out / (name + ".gridmap")).string());
  map::WriteMapPng(cells, grid_options, {}, (out / (name + ".png")).string());
  std::cout << "map-export: the grid of " << grid->source << " on " << channel << " (utime " << grid->utime << "): " << cells.width
            << " x " << cells.height << " cells of " << cells.resolution_m << " m from (" << cells.origin_x_m << ", "
            << cells.origin_y_m << "): " << cells.occupied << " occupied, " << cells.free << " free, " << cells.unknown
            << " unknown; " << refused << " malformed grids refused\nmap-export: wrote " << (out / (name + ".pgm")).string() << ", "
            << name << ".yaml, " << name << ".gridmap, " << name << ".png\n";
  return 0;
}

int Main(int argc, char** argv) {
  std::string log_path, out_dir, pose_channel, name = "map";
  nav::OccupancyGridOptions grid_options;
  eval::LaserSlamConfigChoice config;
  std::vector<std::string> sets;
  double max_dt_s = 0.05;
  bool live = false;
  std::string correction_channel = channels::kLaserSlamCorrection;
  std::string live_channel = "LASER_SLAM_GRID", request_channel = "LASER_SLAM_GRID_REQUEST", lcm_url;
  double timeout_s = 30;
  glue::Flags flags("map-export",
                    "The occupancy grid of a recorded run (LASER_SCAN and ODOMETRY, as log-import writes them or\n"
                    "lcm-logger records them) as files other tools read: NAME.pgm + NAME.yaml (ROS map_server,\n"
                    "trinary: occupied 0, free 254, unknown 205; origin = the lower-left pixel), NAME.gridmap\n"
                    "(MRPT's COccupancyGridMap2D) and NAME.simplemap (MRPT's keyframes: each scan at its pose), and\n"
                    "NAME.png with the trajectory in red, NAME_trajectory.csv (utime,x_m,y_m,theta_rad: each scan's\n"
                    "pose). The poses: the laser SLAM run over the log with --config\n"
                    "(default: the shipped config/laser_slam.ini) and --set, with its back end (backend = graph:\n"
                    "every scan at its pose after the last loop closure), or with --pose-channel the poses a live\n"
                    "run recorded (e.g. POSE_LASER_SLAM), the nearest within --max-dt-s of each scan, corrected by\n"
                    "the log's last table on --correction-channel for them (a live graph back end's loops). The grid is\n"
                    "MRPT's: each beam clears the cells it crossed and marks its hit.\n"
                    "--live (no LOG): from a running laser-slam instead: asks for its grid (a map_request_t on\n"
                    "--request-channel, every 2 s) and writes the next occupancy_grid_t on --channel as NAME.pgm,\n"
                    "NAME.yaml, NAME.gridmap and NAME.png (no simplemap, no trajectory: a grid holds no scans).");
  flags.AllowPositional("LOG", "the LCM log");
  flags.AddBool("live", &live, "take the grid from the bus (a running laser-slam) instead of a LOG");
  flags.AddString("channel", &live_channel, "--live: the occupancy_grid_t channel");
  flags.AddString("request-channel", &request_channel, "--live: where to ask for it (map_request_t); empty: just wait");
  flags.AddDouble("timeout-s", &timeout_s, "--live: give up after this long without a grid [s]");
  flags.AddString("lcm-url", &lcm_url, "--live: LCM URL (default: LCM_DEFAULT_URL or snapnav's default)");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddString("name", &name, "base name of the files");
  flags.AddDouble("resolution-m", &grid_options.resolution_m, "cell size [m]");
  flags.AddDouble("max-range-m", &grid_options.max_range_m, "beams beyond this insert free cells only up to it [m, 0: the laser's range]");
  flags.AddString("pose-channel", &pose_channel, "take the poses of this channel in the log instead of running the laser SLAM");
  flags.AddString("correction-channel", &correction_channel,
                  "with --pose-channel: pose_correction_t channel of the poses' corrections (empty: none)");
  flags.AddDouble("max-dt-s", &max_dt_s, "with --pose-channel: a scan's pose is the nearest within this [s]");
  flags.AddString("config", &config.path, "laser-slam config whose [laser_slam] options the laser SLAM runs");
  flags.AddStringList("set", &sets, "override of one [laser_slam] key of --config, KEY=VALUE");
  if (!flags.Parse(argc, argv)) return 0;
  if (live) {
    if (!flags.positional().empty()) throw glue::FlagError("--live takes no LOG");
    if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
    if (!(timeout_s > 0)) throw glue::FlagError("--timeout-s must be positive");
    return ExportLive(lcm_url, live_channel, request_channel, timeout_s, out_dir, name, grid_options);
  }
  if (flags.positional().size() != 1) throw glue::FlagError("give one LOG (see --help)");
  log_path = flags.positional()[0];
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  try {
    grid_options.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }

  // The scans as the laser measured them, in log order (the SLAM log's scans, the same checks).
  std::vector<nav::GridScan> scans;
  int64_t rejected_scans = 0;
  {
    glue::LogReader file(log_path);
    glue::LogEvent e;
    while (file.Next(&e)) {
      if (e.channel != channels::kLaserScan) continue;
      std::string error;
      const auto s = glue::Decode<laser_scan_t>(e.data.data(), e.data.size(), &error);
      if (!s || !eval::UsableScan(*s)) {
        ++rejected_scans;
        continue;
      }
      scans.push_back(glue::GridScanOf(*s));
    }
    file.ReportDamage(std::cerr, "map-export");
  }
  if (scans.empty()) throw std::runtime_error(log_path + " holds no usable " + std::string(channels::kLaserScan) + " messages");

  std::vector<nav::Pose2> trajectory;  // of the placed scans, in order
  std::vector<nav::GridScan> placed;
  if (pose_channel.empty()) {
    config.overrides = sets;
    const nav::LaserSlamOptions options = eval::LoadLaserSlamOptions(config);
    const eval::SlamBackendChoice backend = eval::LoadSlamBackend(config);
    const eval::SlamLog log = eval::LoadSlamLog(log_path, true);
    std::vector<nav::Pose2> poses;
    if (backend.graph) {
      // The graph back end: each scan at its pose after the last optimization (the loops closed),
      // not as it was published at the time.
      std::cerr << "map-export: laser SLAM, graph back end, over " << log.scans << " scans (" << config.path << ")\n";
      const eval::GraphSlamRun run = eval::RunGraphSlam(log, options, backend.options);
      std::cerr << "map-export: " << run.keyframes << " keyframes, " << run.loop_accepted << " loop closures, "
                << run.corrections << " corrections; the scans at their optimized poses\n";
      poses = run.run.slam;
    } else {
      std::cerr << "map-export: laser SLAM over " << log.scans << " scans (" << config.path << ")\n";
      poses = eval::RunSlam(log, options).slam;
    }
    if (poses.size() != scans.size()) {
      throw std::runtime_error("internal: " + std::to_string(poses.size()) + " SLAM poses for " +
                               std::to_string(scans.size()) + " scans");
    }
    for (size_t i = 0; i < scans.size(); ++i) {
      scans[i].robot_pose = poses[i];
      trajectory.push_back(poses[i]);
    }
    placed = std::move(scans);
  } else {
    int rejected = 0;
    const std::map<int64_t, nav::Pose2> poses = ReadPoses(log_path, pose_channel, correction_channel, &rejected);
    if (poses.empty()) throw std::runtime_error(log_path + " holds no pose_t messages on " + pose_channel);
    const auto max_dt = static_cast<int64_t>(max_dt_s * 1e6);
    int64_t unplaced = 0;
    for (nav::GridScan& s : scans) {
      auto it = poses.lower_bound(s.utime);
      std::optional<std::pair<int64_t, nav::Pose2>> best;
      for (auto c : {it, it == poses.begin() ? poses.end() : std::prev(it)}) {
        if (c == poses.end()) continue;
        if (!best || std::llabs(c->first - s.utime) < std::llabs(best->first - s.utime)) best = *c;
      }
      if (!best || std::llabs(best->first - s.utime) > max_dt) {
        ++unplaced;
        continue;
      }
      s.robot_pose = best->second;
      trajectory.push_back(best->second);
      placed.push_back(std::move(s));
    }
    std::cerr << "map-export: " << poses.size() << " poses on " << pose_channel << " (" << rejected
              << " undecodable or not finite); " << placed.size() << " scans placed, " << unplaced
              << " without a pose within " << max_dt_s << " s\n";
    if (placed.empty()) throw std::runtime_error("no scan of " + log_path + " has a pose on " + pose_channel + " within " + std::to_string(max_dt_s) + " s");
  }

  const mrpt::maps::COccupancyGridMap2D grid = nav::BuildOccupancyGrid(placed, grid_options);
  const nav::OccupancyCells cells = nav::ToOccupancyCells(grid, grid_options);
  const std::filesystem::path out(out_dir);
  map::WriteRosMap(cells, grid_options, out_dir, name);
  map::WriteGridmap(grid, (out / (name + ".gridmap")).string());
  map::WriteSimplemap(nav::BuildSimpleMap(placed, grid_options.max_range_m), (out / (name + ".simplemap")).string());
  map::WriteMapPng(cells, grid_options, trajectory, (out / (name + ".png")).string());
  {
    const std::string csv = (out / (name + "_trajectory.csv")).string();
    std::ofstream f(csv);
    f << "utime,x_m,y_m,theta_rad\n" << std::setprecision(10);
    for (const nav::GridScan& s : placed) f << s.utime << "," << s.robot_pose.x_m << "," << s.robot_pose.y_m << "," << s.robot_pose.theta_rad << "\n";
    if (!f) throw std::runtime_error(csv + ": cannot write");
  }
  std::cout << "map-export: " << placed.size() << " scans (" << rejected_scans << " unusable), " << cells.width << " x "
            << cells.height << " cells of " << cells.resolution_m << " m from (" << cells.origin_x_m << ", "
            << cells.origin_y_m << "): " << cells.occupied << " occupied, " << cells.free << " free, " << cells.unknown
            << " unknown\nmap-export: wrote " << (out / (name + ".pgm")).string() << ", " << name << ".yaml, " << name
            << ".gridmap, " << name << ".simplemap, " << name << ".png, " << name << "_trajectory.csv\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
