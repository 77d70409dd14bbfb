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

#include "slam_log.hpp"
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

  const eval::SlamLog log = eval::LoadSlamLog(log_path);
  const eval::SlamRun run = eval::RunSlam(log, options);
  const double ms_per_scan = run.ms_per_scan();
  std::cerr << "eval-slam: laser slam " << ms_per_scan << " ms/scan, map " << run.map.size() << " points\n";

  std::ostringstream json;
  json << std::fixed << std::setprecision(4) << "{\n  \"log\": \"" << log_path << "\",\n  \"scans\": " << log.scans
       << ",\n  \"odometry\": " << log.odometry << ",\n  \"rejected\": " << log.rejected << ",\n  \"laser_slam_ms_per_scan\": "
       << ms_per_scan << ",\n  \"map_points\": " << run.map.size();
  std::vector<nav::Pose2> ref_track;
  std::vector<std::vector<nav::Pose2>> tracks = {run.slam, run.dead_reckoning};
  std::vector<std::string> names = {"laser slam", "dead reckoning"};
  std::string title = "laser slam on " + fs::path(log_path).filename().string();
  if (!reference_path.empty()) {
    const eval::Reference ref = eval::LoadReference(reference_path);
    const auto slam_pairs = eval::PairWithReference(run.slam, run, ref);
    const auto dr_pairs = eval::PairWithReference(run.dead_reckoning, run, ref);
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
  plot::SavePng(DrawRun(tracks, names, run.map, title), (out / "trajectories.png").string());
  {
    std::ofstream csv(out / "trajectories.csv");
    csv << "utime,slam_x_m,slam_y_m,slam_theta_rad,dr_x_m,dr_y_m,dr_theta_rad\n" << std::setprecision(9);
    for (size_t i = 0; i < run.slam.size(); ++i) {
      const nav::Pose2 &s = run.slam[i], &d = run.dead_reckoning[i];
      csv << run.utime[i] << "," << s.x_m << "," << s.y_m << "," << s.theta_rad << "," << d.x_m << "," << d.y_m << ","
          << d.theta_rad << "\n";
    }
  }
  std::cerr << "eval-slam: wrote " << (out / "summary.json").string() << ", trajectories.png, trajectories.csv\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
