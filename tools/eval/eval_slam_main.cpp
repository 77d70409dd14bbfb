// eval-slam: dead reckoning and laser SLAM (thesis 5.3) run in lockstep over an LCM log of
// laser scans and odometry (made by log-import), with the absolute trajectory error against a
// reference: a CSV of utime,x,y,theta, or a CARMEN log of corrected poses whose scans are
// paired with the log's by identical ranges.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgproc.hpp>

#include "importers.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/laser_slam.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/plot/plot.hpp"
#include "snapnav/pose_t.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using Clock = std::chrono::steady_clock;

// The ranges of a scan as a key: scans of the same reading are byte-identical floats.
std::string RangesKey(const laser_scan_t& s) {
  return std::string(reinterpret_cast<const char*>(s.ranges_m.data()), s.ranges_m.size() * sizeof(float));
}

struct ScanRecord {
  int64_t utime = 0;
  std::string key;
  nav::Pose2 slam, dead_reckoning;
};

// Reference poses keyed by scan ranges (CARMEN) or by time (CSV).
struct Reference {
  std::map<std::string, nav::Pose2> by_ranges;
  std::vector<nav::StampedPose> by_time;
};

class VectorSink : public importers::Sink {
 public:
  void Write(const std::string& channel, int64_t utime, const std::string& payload) override {
    events.push_back({channel, utime, payload});
  }
  struct Event {
    std::string channel;
    int64_t utime;
    std::string payload;
  };
  std::vector<Event> events;
};

Reference LoadReference(const std::string& path) {
  Reference ref;
  const bool csv = path.size() > 4 && path.substr(path.size() - 4) == ".csv";
  if (csv) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot open reference " + path);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      if (line.empty() || line[0] == '#' || line.rfind("utime", 0) == 0) continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream s(line);
      nav::StampedPose p;
      if (!(s >> p.utime >> p.pose.x_m >> p.pose.y_m >> p.pose.theta_rad)) {
        throw std::runtime_error(path + ":" + std::to_string(n) + ": expected utime,x,y,theta");
      }
      ref.by_time.push_back(p);
    }
    std::sort(ref.by_time.begin(), ref.by_time.end(), [](auto& a, auto& b) { return a.utime < b.utime; });
    return ref;
  }
  VectorSink sink;
  importers::CarmenOptions options;
  options.time_source = importers::TimeSource::kLog;
  const auto report = importers::ImportCarmenFile(path, sink, options);
  // Each FLASER line gives a scan and its pose, next to each other in the output (the
  // corrected log's times are truncated, so times do not tell lines apart).
  std::optional<std::string> pending_scan;
  std::optional<nav::Pose2> pending_pose;
  for (const auto& e : sink.events) {
    if (e.channel == channels::kLaserScan) {
      laser_scan_t s;
      if (s.decode(e.payload.data(), 0, static_cast<int>(e.payload.size())) <= 0) continue;
      if (pending_pose) {
        ref.by_ranges.emplace(RangesKey(s), *pending_pose);
        pending_pose.reset();
      } else {
        pending_scan = RangesKey(s);
      }
    } else if (e.channel == importers::kPoseCarmen) {
      pose_t p;
      if (p.decode(e.payload.data(), 0, static_cast<int>(e.payload.size())) <= 0) continue;
      if (pending_scan) {
        ref.by_ranges.emplace(*pending_scan, glue::FromPoseMsg(p));
        pending_scan.reset();
      } else {
        pending_pose = glue::FromPoseMsg(p);
      }
    }
  }
  (void)report;
  std::cerr << "eval-slam: reference " << path << ": " << ref.by_ranges.size() << " scans with poses\n";
  if (ref.by_ranges.empty()) throw std::runtime_error("reference " + path + " holds no scans with poses");
  return ref;
}

cv::Mat DrawRun(const std::vector<std::vector<nav::Pose2>>& tracks, const std::vector<std::string>& names,
                const std::vector<Eigen::Vector2d>& map, const std::string& title) {
  double xmin = 1e18, xmax = -1e18, ymin = 1e18, ymax = -1e18;
  auto grow = [&](double x, double y) {
    xmin = std::min(xmin, x); xmax = std::max(xmax, x);
    ymin = std::min(ymin, y); ymax = std::max(ymax, y);
  };
  for (const auto& p : map) grow(p.x(), p.y());
  for (const auto& t : tracks) for (const auto& p : t) grow(p.x_m, p.y_m);
  const int size = 900, top = 40;
  const double scale = (size - 40) / std::max({xmax - xmin, ymax - ymin, 1e-3});
  cv::Mat img(size + top, size, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double x, double y) {
    return cv::Point(static_cast<int>(20 + (x - xmin) * scale), static_cast<int>(top + size - 20 - (y - ymin) * scale));
  };
  for (const auto& p : map) img.at<cv::Vec3b>(px(p.x(), p.y())) = cv::Vec3b(80, 80, 80);
  for (size_t k = 0; k < tracks.size(); ++k) {
    const cv::Scalar c = plot::SeriesColour(static_cast<int>(k));
    for (size_t i = 1; i < tracks[k].size(); ++i) {
      cv::line(img, px(tracks[k][i - 1].x_m, tracks[k][i - 1].y_m), px(tracks[k][i].x_m, tracks[k][i].y_m), c, 2, cv::LINE_AA);
    }
    cv::putText(img, names[k], {size - 260, top + 20 + 22 * static_cast<int>(k)}, cv::FONT_HERSHEY_SIMPLEX, 0.55, c, 2, cv::LINE_AA);
  }
  cv::putText(img, title, {12, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  const int bar = static_cast<int>(5.0 * scale);
  cv::line(img, {20, top + size - 8}, {20 + bar, top + size - 8}, cv::Scalar(0, 0, 0), 2);
  cv::putText(img, "5 m", {24 + bar, top + size - 4}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return img;
}

int Main(int argc, char** argv) {
  std::string log_path, reference_path, out_dir;
  nav::LaserSlamOptions options;
  glue::Flags flags("eval-slam",
                    "Runs dead reckoning and laser SLAM in lockstep over an LCM log of LASER_SCAN and ODOMETRY\n"
                    "(see log-import) and writes trajectories, a map image and summary.json; with --reference,\n"
                    "the ATE (RMSE after SE(2) alignment) of each against a CSV (utime,x,y,theta) or a CARMEN log\n"
                    "of corrected poses, paired with the log's scans by identical ranges.");
  flags.AddString("log", &log_path, "LCM log (required)");
  flags.AddString("reference", &reference_path, "reference trajectory: .csv or CARMEN log (.log, .clf, .gz)");
  flags.AddDouble("match-distance-m", &options.match_distance_m, "laser slam: match distance [m]");
  flags.AddInt("icp-iterations", &options.icp_iterations, "laser slam: ICP iterations per scan");
  flags.AddDouble("map-resolution-m", &options.map_resolution_m, "laser slam: map cell [m]");
  flags.AddDouble("add-distance-m", &options.add_distance_m, "laser slam: new map point if nothing this close [m]");
  flags.AddInt("scan-step", &options.scan_step, "laser slam: use every n-th beam");
  flags.AddString("out", &out_dir, "output folder (required)");
  if (!flags.Parse(argc, argv)) return 0;
  if (log_path.empty() || out_dir.empty()) throw glue::FlagError("--log LOG and --out DIR are required");
  options.Validate();
  fs::create_directories(out_dir);
  const fs::path out(out_dir);

  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error("cannot open LCM log " + log_path);
  nav::LaserSlam slam(options);
  nav::DeadReckoning dr({});
  std::vector<ScanRecord> records;
  int64_t odometry = 0, bad = 0, events = 0;
  double update_s = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++events;
    const std::string channel = e->channel;
    if (channel == channels::kOdometry) {
      odometry_t m;
      if (m.decode(e->data, 0, static_cast<int>(e->datalen)) < 0) { ++bad; continue; }
      const nav::Pose2 d = glue::OdometryDelta(m);
      if (!std::isfinite(d.x_m) || !std::isfinite(d.y_m) || !std::isfinite(d.theta_rad)) { ++bad; continue; }
      slam.Predict(d);
      dr.AddOdometry(d);
      ++odometry;
    } else if (channel == channels::kLaserScan) {
      laser_scan_t s;
      if (s.decode(e->data, 0, static_cast<int>(e->datalen)) < 0 || s.ranges_m.empty() ||
          !std::isfinite(s.angle_increment_rad)) { ++bad; continue; }
      const auto points = nav::ScanToPoints(s.ranges_m, s.angle_min_rad, s.angle_increment_rad, s.range_min_m,
                                            s.range_max_m, nav::Pose2{s.sensor_x_m, s.sensor_y_m, s.sensor_theta_rad});
      const auto t0 = Clock::now();
      slam.Update(points);
      update_s += std::chrono::duration<double>(Clock::now() - t0).count();
      records.push_back({s.utime, RangesKey(s), slam.pose(), dr.pose()});
      if (records.size() % 200 == 0) std::cerr << "eval-slam: " << records.size() << " scans\r" << std::flush;
    }
  }
  if (records.empty()) throw std::runtime_error(log_path + " holds no " + std::string(channels::kLaserScan) + " messages");
  const double ms_per_scan = 1000 * update_s / records.size();
  std::cerr << "eval-slam: " << records.size() << " scans, " << odometry << " odometry, " << bad
            << " undecodable or invalid, " << events << " events; laser slam " << ms_per_scan << " ms/scan, map "
            << slam.map().size() << " points\n";

  std::ostringstream json;
  json << std::fixed << std::setprecision(4) << "{\n  \"log\": \"" << log_path << "\",\n  \"scans\": " << records.size()
       << ",\n  \"odometry\": " << odometry << ",\n  \"rejected\": " << bad << ",\n  \"laser_slam_ms_per_scan\": "
       << ms_per_scan << ",\n  \"map_points\": " << slam.map().size();
  std::vector<nav::Pose2> ref_track, slam_track, dr_track;
  for (const auto& r : records) {
    slam_track.push_back(r.slam);
    dr_track.push_back(r.dead_reckoning);
  }
  std::vector<std::vector<nav::Pose2>> tracks = {slam_track, dr_track};
  std::vector<std::string> names = {"laser slam", "dead reckoning"};
  std::string title = "laser slam on " + fs::path(log_path).filename().string();
  if (!reference_path.empty()) {
    const Reference ref = LoadReference(reference_path);
    std::vector<std::pair<nav::Pose2, nav::Pose2>> slam_pairs, dr_pairs;
    for (const auto& r : records) {
      std::optional<nav::Pose2> truth;
      if (!ref.by_ranges.empty()) {
        const auto it = ref.by_ranges.find(r.key);
        if (it != ref.by_ranges.end()) truth = it->second;
      } else if (const auto i = nav::NearestInTime(ref.by_time, r.utime, 50000)) {
        truth = ref.by_time[*i].pose;
      }
      if (!truth) continue;
      slam_pairs.push_back({r.slam, *truth});
      dr_pairs.push_back({r.dead_reckoning, *truth});
    }
    if (slam_pairs.size() < 2) throw std::runtime_error("fewer than 2 scans of the log pair with the reference");
    const auto slam_ate = nav::ComputeAte(slam_pairs, nav::AlignSE2(slam_pairs));
    const auto dr_ate = nav::ComputeAte(dr_pairs, nav::AlignSE2(dr_pairs));
    std::cerr << "eval-slam: " << slam_pairs.size() << " scans paired with the reference; ATE RMSE: laser slam "
              << slam_ate.rmse_m << " m, dead reckoning " << dr_ate.rmse_m << " m\n";
    json << ",\n  \"reference\": \"" << reference_path << "\",\n  \"reference_pairs\": " << slam_pairs.size()
         << ",\n  \"laser_slam_ate_rmse_m\": " << slam_ate.rmse_m << ",\n  \"laser_slam_ate_max_m\": " << slam_ate.max_m
         << ",\n  \"dead_reckoning_ate_rmse_m\": " << dr_ate.rmse_m << ",\n  \"dead_reckoning_ate_max_m\": " << dr_ate.max_m;
    // Draw the reference in the SLAM frame.
    const nav::Pose2 to_ref = nav::AlignSE2(slam_pairs);
    const nav::Pose2 to_slam = to_ref.Inverse();
    for (const auto& [est, truth] : slam_pairs) ref_track.push_back(to_slam.Compose(truth));
    tracks.push_back(ref_track);
    names.push_back("reference");
    title += ": ATE " + std::to_string(slam_ate.rmse_m).substr(0, 5) + " m (dead reckoning " +
             std::to_string(dr_ate.rmse_m).substr(0, 5) + " m)";
  }
  json << "\n}\n";
  std::ofstream(out / "summary.json") << json.str();
  plot::SavePng(DrawRun(tracks, names, slam.map().points(), title), (out / "trajectories.png").string());
  {
    std::ofstream csv(out / "trajectories.csv");
    csv << "utime,slam_x_m,slam_y_m,slam_theta_rad,dr_x_m,dr_y_m,dr_theta_rad\n" << std::setprecision(9);
    for (const auto& r : records) {
      csv << r.utime << "," << r.slam.x_m << "," << r.slam.y_m << "," << r.slam.theta_rad << "," << r.dead_reckoning.x_m
          << "," << r.dead_reckoning.y_m << "," << r.dead_reckoning.theta_rad << "\n";
    }
  }
  std::cerr << "eval-slam: wrote " << (out / "summary.json").string() << ", trajectories.png, trajectories.csv\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
