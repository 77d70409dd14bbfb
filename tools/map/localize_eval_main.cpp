// localize-eval: laser-slam --mode localize's localizer (nav::MapLocalizer, the same options from
// the same config) over a recorded log in a saved map, against a reference trajectory: from
// several unknown starts, how long until the pose is right (time, scans, distance travelled), how
// well it tracks then (ATE in the map's frame, no alignment), how often it was lost, and whether
// any accepted global pose was wrong.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include "localize_config.hpp"
#include "laser_slam_node.hpp"
#include "map_export.hpp"
#include "results.hpp"
#include "slam_log.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/log_reader.hpp"
#include "snapnav/pose_t.hpp"
#include "snapnav/nav/slam/map_localizer.hpp"

namespace {

using namespace snapnav;
constexpr double kPi = 3.14159265358979323846;

struct StartResult {
  int start_scan = 0;
  int64_t scans = 0;
  bool relocalized = false;       // the pose came within tolerance
  double time_s = 0;              // message time from the start to the first pose within tolerance
  int scans_to = 0;               // scans from the start to it
  double path_m = 0;              // reference path travelled meanwhile (NaN without a reference on the way)
  double compute_s = 0;           // wall time of the localizer meanwhile
  int64_t localized_scans = 0, referenced_localized = 0;
  double ate_rmse_m = 0, ate_max_m = 0, heading_rmse_deg = 0;
  int64_t searches = 0, relocalizations = 0, losses = 0, wrong_accepts = 0;
  double max_search_ms = 0, mean_search_ms = 0, mean_track_ms = 0;
};

double HeadingError(double a, double b) { return std::abs(nav::WrapAngle(a - b)); }

int Main(int argc, char** argv) {
  std::string log_path, map_path, reference_path, out_dir, config_path = SNAPNAV_CONFIG_DIR "/laser_slam.ini";
  std::vector<std::string> sets;
  std::string reference_channel;
  int starts = 4;
  double tol_m = 0.3, tol_deg = 10, wrong_m = 0.5, wrong_deg = 5;
  glue::Flags flags("localize-eval",
                    "laser-slam --mode localize's localizer (the same code and config) over LOG (LASER_SCAN and ODOMETRY,\n"
                    "as log-import writes them) in the saved map --map (map.yaml, .gridmap or .simplemap), against --reference\n"
                    "(a CARMEN log whose scans pair with LOG's by identical ranges, e.g. the corrected log the map was\n"
                    "made from, or a CSV utime,x,y,theta). The localizer starts knowing nothing at --starts scans spread\n"
                    "over the log (the first at scan 0) and runs from each to the log's end. Per start: the time (message\n"
                    "time), scans and reference path until the pose is within --tol-m and --tol-deg of the reference\n"
                    "(relocalized: at the accepted global pose that the next reference pose confirms), the ATE while\n"
                    "localized after that (RMS position error in the map's frame, no alignment), global searches\n"
                    "(ms), losses, and accepted global poses more than --wrong-m or\n"
                    "--wrong-deg from the reference (wrong). Writes DIR/localize.json and DIR/localize.md.");
  flags.AllowPositional("LOG", "the LCM log to localize");
  flags.AddString("map", &map_path, "the saved map (map.yaml, map.gridmap or map.simplemap, MRPT's keyframes as icp-slam writes them; required)");
  flags.AddString("reference", &reference_path, "the reference trajectory (CARMEN log or CSV; required)");
  flags.AddString("reference-channel", &reference_channel,
                  "take the reference from this pose_t channel of LOG instead (e.g. the simulator's POSE_GROUND_TRUTH)");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddString("config", &config_path, "laser-slam config: [laser_slam] the tracker, [localize] the localizer");
  flags.AddStringList("set", &sets, "override of one config key, SECTION.KEY=VALUE (e.g. localize.accept_fit=0.7)");
  flags.AddInt("starts", &starts, "unknown starts spread over the log [count]");
  flags.AddDouble("tol-m", &tol_m, "relocalized: within this distance of the reference [m]");
  flags.AddDouble("tol-deg", &tol_deg, "... and this heading [deg]");
  flags.AddDouble("wrong-m", &wrong_m, "an accepted global pose farther than this from the reference is wrong [m]");
  flags.AddDouble("wrong-deg", &wrong_deg, "... or turned more than this [deg]");
  if (!flags.Parse(argc, argv)) return 0;
  if (flags.positional().size() != 1) throw glue::FlagError("give one LOG (see --help)");
  log_path = flags.positional()[0];
  if (map_path.empty() || (reference_path.empty() == reference_channel.empty()) || out_dir.empty())
    throw glue::FlagError("--map, --out and one of --reference and --reference-channel are required");
  if (starts < 1) throw glue::FlagError("--starts must be >= 1");

  glue::IniFile ini = glue::IniFile::Load(config_path);
  for (const std::string& s : sets) {
    const size_t dot = s.find('.'), eq = s.find('=');
    if (dot == std::string::npos || eq == std::string::npos || dot > eq) throw glue::FlagError("--set " + s + ": expected SECTION.KEY=VALUE");
    ini.Set(s.substr(0, dot), s.substr(dot + 1, eq - dot - 1), s.substr(eq + 1), "--set");
  }
  const processes::LaserSlamConfig config = processes::LaserSlamConfig::FromIni(ini, "");
  const nav::MapLocalizerOptions options = config.localize.options;
  const nav::OccupancyCells map = map::ReadMapFile(map_path, config.grid.grid);
  const eval::SlamLog log = eval::LoadSlamLog(log_path, false);
  eval::Reference reference;
  if (!reference_channel.empty()) {
    reference_path = log_path + ":" + reference_channel;
    glue::LogReader file(log_path);
    glue::LogEvent e;
    while (file.Next(&e)) {
      if (e.channel != reference_channel) continue;
      std::string error;
      const auto p = glue::Decode<pose_t>(e.data.data(), e.data.size(), &error);
      if (p && std::isfinite(p->x_m) && std::isfinite(p->y_m) && std::isfinite(p->theta_rad))
        reference.by_time.push_back({p->utime, {p->x_m, p->y_m, p->theta_rad}});
    }
    std::sort(reference.by_time.begin(), reference.by_time.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  } else {
    reference = eval::LoadReference(reference_path, &log);
  }
  std::cerr << "localize-eval: " << log_path << ": " << log.scans << " scans, " << log.odometry << " odometry; map " << map_path
            << " " << map.width << " x " << map.height << " cells; reference " << reference_path << "\n";

  // Scan indices in the steps.
  std::vector<size_t> scan_steps;
  for (size_t i = 0; i < log.steps.size(); ++i)
    if (log.steps[i].is_scan) scan_steps.push_back(i);
  std::vector<std::optional<nav::Pose2>> ref(scan_steps.size());
  int64_t referenced = 0;
  for (size_t k = 0; k < scan_steps.size(); ++k) {
    const auto& st = log.steps[scan_steps[k]];
    ref[k] = reference.Find(st.ranges_key, st.utime);
    referenced += ref[k].has_value();
  }
  std::cerr << "localize-eval: " << referenced << " of " << scan_steps.size() << " scans have a reference pose\n";
  if (referenced == 0) throw std::runtime_error("no scan of " + log_path + " pairs with " + reference_path);

  std::vector<StartResult> start_results;
  for (int s = 0; s < starts; ++s) {
    StartResult r;
    r.start_scan = static_cast<int>(scan_steps.size() * static_cast<size_t>(s) / static_cast<size_t>(starts));
    nav::MapLocalizer loc(map, options);
    const int64_t t0 = log.steps[scan_steps[static_cast<size_t>(r.start_scan)]].utime;
    double se2 = 0, sh2 = 0, search_ms = 0, track_ms = 0;
    int64_t tracked = 0;
    double path = 0;
    std::optional<nav::Pose2> last_ref;
    bool reached = false;
    double compute = 0, compute_at_accept = 0;
    // The last accepted global pose not lost since: when the first reference after it confirms the
    // pose, the robot was relocalized at that scan (a log whose reference covers only some scans,
    // as CSAIL's keyframes, confirms it later).
    std::optional<std::pair<int64_t, size_t>> accepted;
    double path_at_accept = 0;
    for (size_t i = scan_steps[static_cast<size_t>(r.start_scan)]; i < log.steps.size(); ++i) {
      const eval::SlamStep& st = log.steps[i];
      if (!st.is_scan) {
        loc.Predict(st.odometry_delta, st.utime);
        continue;
      }
      const size_t k = static_cast<size_t>(std::lower_bound(scan_steps.begin(), scan_steps.end(), i) - scan_steps.begin());
      ++r.scans;
      const auto c0 = std::chrono::steady_clock::now();
      const nav::LocalizationUpdate u = loc.Update(st.points, st.utime);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count();
      if (!reached) compute += ms / 1000;
      if (u.searched) {
        search_ms += ms;
        r.max_search_ms = std::max(r.max_search_ms, ms);
      } else {
        track_ms += ms;
        ++tracked;
      }
      if (ref[k]) {
        if (last_ref && !reached) path += std::hypot(ref[k]->x_m - last_ref->x_m, ref[k]->y_m - last_ref->y_m);
        last_ref = ref[k];
      }
      if (u.lost_now) accepted.reset();
      if (u.relocalized && !reached) {
        accepted = {st.utime, k};
        path_at_accept = path;
        compute_at_accept = compute;
      }
      if (u.relocalized && ref[k]) {
        const nav::Pose2& p = loc.pose();
        if (std::hypot(p.x_m - ref[k]->x_m, p.y_m - ref[k]->y_m) > wrong_m || HeadingError(p.theta_rad, ref[k]->theta_rad) > wrong_deg * kPi / 180)
          ++r.wrong_accepts;
      }
      if (u.state != nav::LocalizationState::kLocalized) continue;
      ++r.localized_scans;
      if (!ref[k]) continue;
      const nav::Pose2& p = loc.pose();
      const double e = std::hypot(p.x_m - ref[k]->x_m, p.y_m - ref[k]->y_m), h = HeadingError(p.theta_rad, ref[k]->theta_rad);
      if (!reached && e <= tol_m && h <= tol_deg * kPi / 180) {
        reached = true;
        r.relocalized = true;
        const bool from_accept = accepted.has_value();
        r.time_s = ((from_accept ? accepted->first : st.utime) - t0) * 1e-6;
        r.scans_to = static_cast<int>(from_accept ? accepted->second : k) - r.start_scan;
        r.path_m = from_accept ? path_at_accept : path;
        r.compute_s = from_accept ? compute_at_accept : compute;
      }
      if (reached) {
        ++r.referenced_localized;
        se2 += e * e;
        sh2 += h * h;
        r.ate_max_m = std::max(r.ate_max_m, e);
      }
    }
    if (r.referenced_localized > 0) {
      r.ate_rmse_m = std::sqrt(se2 / r.referenced_localized);
      r.heading_rmse_deg = std::sqrt(sh2 / r.referenced_localized) * 180 / kPi;
    }
    r.searches = loc.global_searches();
    r.relocalizations = loc.relocalizations();
    r.losses = loc.losses();
    r.mean_search_ms = r.searches > 0 ? search_ms / r.searches : 0;
    r.mean_track_ms = tracked > 0 ? track_ms / tracked : 0;
    std::cerr << "localize-eval: start at scan " << r.start_scan << ": "
              << (r.relocalized ? "relocalized after " + std::to_string(r.scans_to) + " scans, " + std::to_string(r.time_s) + " s, " +
                                      std::to_string(r.path_m) + " m"
                                : std::string("never relocalized"))
              << "; ATE " << r.ate_rmse_m << " m over " << r.referenced_localized << " referenced scans; " << r.searches
              << " searches (mean " << r.mean_search_ms << " ms, max " << r.max_search_ms << " ms), " << r.relocalizations
              << " accepted (" << r.wrong_accepts << " wrong), " << r.losses << " losses; tracking " << r.mean_track_ms << " ms/scan\n";
    start_results.push_back(r);
  }

  std::filesystem::create_directories(out_dir);
  const std::filesystem::path out(out_dir);
  {
    results::Json j;
    j["log"] = log_path;
    j["map"] = map_path;
    j["reference"] = reference_path;
    j["config"] = config_path;
    j["scans"] = log.scans;
    j["referenced_scans"] = referenced;
    j["tol_m"] = results::Significant(tol_m);
    j["tol_deg"] = results::Significant(tol_deg);
    j["starts"] = results::Json::array();
    for (const StartResult& r : start_results) {
      results::Json s;
      s["start_scan"] = r.start_scan;
      s["relocalized"] = r.relocalized;
      s["time_s"] = results::Significant(r.time_s);
      s["scans_to"] = r.scans_to;
      s["path_m"] = results::Significant(r.path_m);
      s["compute_s"] = results::Significant(r.compute_s);
      s["ate_rmse_m"] = results::Significant(r.ate_rmse_m);
      s["ate_max_m"] = results::Significant(r.ate_max_m);
      s["heading_rmse_deg"] = results::Significant(r.heading_rmse_deg);
      s["scans"] = r.scans;
      s["localized_scans"] = r.localized_scans;
      s["referenced_localized"] = r.referenced_localized;
      s["searches"] = r.searches;
      s["relocalizations"] = r.relocalizations;
      s["wrong_accepts"] = r.wrong_accepts;
      s["losses"] = r.losses;
      s["mean_search_ms"] = results::Significant(r.mean_search_ms);
      s["max_search_ms"] = results::Significant(r.max_search_ms);
      s["mean_track_ms"] = results::Significant(r.mean_track_ms);
      j["starts"].push_back(s);
    }
    results::WriteJsonFile((out / "localize.json").string(), j);
  }
  {
    std::ofstream m(out / "localize.md");
    m << "# localize-eval: " << log_path << "\n\nmap " << map_path << ", reference " << reference_path << ", " << log.scans
      << " scans (" << referenced << " with a reference)\n\n"
      << "| start scan | relocalized after | scans | path [m] | compute [s] | ATE RMSE [m] | ATE max [m] | heading RMSE [deg] | localized scans | searches (mean / max ms) | accepted (wrong) | losses | tracking ms/scan |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
      << std::fixed;
    for (const StartResult& r : start_results) {
      m << "| " << r.start_scan << " | " << (r.relocalized ? std::to_string(r.time_s).substr(0, 6) + " s" : std::string("never"))
        << " | " << r.scans_to << " | " << std::setprecision(1) << r.path_m << " | " << std::setprecision(2) << r.compute_s << " | "
        << std::setprecision(3) << r.ate_rmse_m << " | " << r.ate_max_m << " | " << std::setprecision(2) << r.heading_rmse_deg
        << " | " << r.localized_scans << " / " << r.scans << " | " << r.searches << " (" << std::setprecision(1) << r.mean_search_ms
        << " / " << r.max_search_ms << ") | " << r.relocalizations << " (" << r.wrong_accepts << ") | " << r.losses << " | "
        << std::setprecision(2) << r.mean_track_ms << " |\n";
    }
  }
  std::cout << "localize-eval: wrote " << (out / "localize.json").string() << " and localize.md\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
