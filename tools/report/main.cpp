// log-report: what a recorded run contains and how well each estimator did.
// Reads an LCM log and writes into --out: report.md, summary.json,
// trajectories.png (every pose channel against the ground truth, over the laser
// map drawn from the ground-truth poses) and the first omni frame as PNG.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "snapnav/glue/app.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/log_reader.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/pose_t.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

struct ChannelInfo {
  int64_t count = 0, bytes = 0, first_us = 0, last_us = 0, rejected = 0;
};

// World (x, y) -> image pixel for a plot covering `lo`..`hi`.
struct Plot {
  Eigen::Vector2d lo, hi;
  double scale = 1;
  int margin = 40;
  cv::Point Px(double x, double y) const {
    return {margin + static_cast<int>((x - lo.x()) * scale), margin + static_cast<int>((hi.y() - y) * scale)};
  }
};

int Main(int argc, char** argv) {
  std::string out_dir, truth_channel = channels::kPoseGroundTruth, scan_channel = channels::kLaserScan;
  glue::Flags flags("log-report LOG",
                    "Summarises an LCM log: messages per channel, and for every pose_t channel its trajectory\n"
                    "error (ATE) against the ground truth; writes report.md, summary.json and PNG plots.\n"
                    "A damaged log (truncated, corrupt) is reported with the byte offset of each damaged place\n"
                    "and summarised from its intact events; the exit status is then 3.");
  flags.AddString("out", &out_dir, "output folder (default: beside the log)");
  flags.AddString("truth", &truth_channel, "ground-truth pose channel");
  flags.AddString("scan", &scan_channel, "laser channel for the map drawn from the ground truth");
  flags.AllowPositional("LOG", "the LCM log");
  if (!flags.Parse(argc, argv)) return 0;
  if (flags.positional().size() != 1) throw glue::FlagError("expected one LOG (see --help)");
  const std::string log_path = flags.positional()[0];
  if (out_dir.empty()) out_dir = fs::path(log_path).parent_path().string();
  if (out_dir.empty()) out_dir = ".";
  fs::create_directories(out_dir);

  // glue::LogReader reads every intact event and names the byte offset of any damage.
  glue::LogReader log(log_path);
  const auto file_size = static_cast<int64_t>(log.file_size());
  std::map<std::string, ChannelInfo> info;
  std::map<std::string, std::vector<nav::StampedPose>> poses;  // by channel
  std::vector<laser_scan_t> scans;
  std::optional<omni_frame_t> first_frame;
  glue::LogEvent ev;
  while (log.Next(&ev)) {
    ChannelInfo& ci = info[ev.channel];
    if (ci.count == 0) ci.first_us = ev.timestamp_us;
    ++ci.count;
    ci.bytes += static_cast<int64_t>(ev.data.size());
    ci.last_us = ev.timestamp_us;
    const auto fp = glue::PayloadFingerprint(ev.data.data(), ev.data.size());
    if (!fp) {
      ++ci.rejected;
      continue;
    }
    std::string error;
    if (*fp == static_cast<uint64_t>(pose_t::getHash())) {
      const auto p = glue::Decode<pose_t>(ev.data.data(), ev.data.size(), &error);
      const nav::Pose2 pose = p ? glue::FromPoseMsg(*p) : nav::Pose2{};
      if (p && std::isfinite(pose.x_m) && std::isfinite(pose.y_m) && std::isfinite(pose.theta_rad)) {
        poses[ev.channel].push_back({p->utime, pose});
      } else {
        ++ci.rejected;  // undecodable, or a pose that is not finite (it would wreck the plot)
      }
    } else if (*fp == static_cast<uint64_t>(laser_scan_t::getHash()) && ev.channel == scan_channel) {
      if (auto s = glue::Decode<laser_scan_t>(ev.data.data(), ev.data.size(), &error)) {
        if (scans.size() < 5000 && ci.count % 5 == 1) scans.push_back(std::move(*s));
      } else {
        ++ci.rejected;
      }
    } else if (*fp == static_cast<uint64_t>(omni_frame_t::getHash()) && !first_frame) {
      if (auto f = glue::Decode<omni_frame_t>(ev.data.data(), ev.data.size(), &error)) {
        first_frame = std::move(*f);
      } else {
        ++ci.rejected;
      }
    }
  }
  const bool damaged = log.damaged();
  const auto good_bytes = static_cast<int64_t>(log.file_size() - log.damaged_bytes());
  if (damaged) {
    log.ReportDamage(std::cerr, "log-report: warning");
    std::cerr << "log-report: " << log_path << " is damaged (" << log.damage().size() << " place(s), "
              << log.damaged_bytes() << " of " << file_size << " bytes lost): reporting the " << log.events()
              << " intact events\n";
  }

  // Trajectory errors against the ground truth.
  std::ostringstream json;
  json << std::fixed << std::setprecision(4) << "{\n  \"log\": \"" << log_path << "\",\n  \"log_bytes\": " << file_size
       << ",\n  \"log_valid_bytes\": " << good_bytes
       << ",\n  \"log_damaged_places\": " << log.damage().size();
  std::ostringstream table;
  table << "| channel | messages | rate (Hz) | MB |\n|---|---|---|---|\n";
  for (const auto& [ch, ci] : info) {
    const double span = (ci.last_us - ci.first_us) * 1e-6;
    table << "| " << ch << " | " << ci.count << " | " << std::fixed << std::setprecision(1)
          << (span > 0 ? (ci.count - 1) / span : 0.0) << " | " << std::setprecision(2) << ci.bytes / 1e6 << " |\n";
    json << ",\n  \"messages_" << ch << "\": " << ci.count;
    if (ci.rejected > 0) json << ",\n  \"rejected_" << ch << "\": " << ci.rejected;
  }
  std::ostringstream ate_table;
  const auto truth_it = poses.find(truth_channel);
  if (truth_it != poses.end()) {
    ate_table << "| estimator channel | poses | ATE RMSE (m) | ATE RMSE after SE(2) alignment (m) | final error (m) |\n"
              << "|---|---|---|---|---|\n";
    for (const auto& [ch, traj] : poses) {
      if (ch == truth_channel) continue;
      const auto pairs = nav::AssociateByTime(traj, truth_it->second, 20000);
      if (pairs.size() < 2) continue;
      const nav::AteResult raw = nav::ComputeAte(pairs);
      const nav::AteResult aligned = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
      ate_table << "| " << ch << " | " << pairs.size() << " | " << std::setprecision(3) << raw.rmse_m << " | "
                << aligned.rmse_m << " | " << raw.final_m << " |\n";
      std::string key = ch;
      for (auto& c : key) c = static_cast<char>(std::tolower(c));
      json << ",\n  \"" << key << "_ate_rmse_m\": " << raw.rmse_m << ",\n  \"" << key
           << "_aligned_ate_rmse_m\": " << aligned.rmse_m << ",\n  \"" << key << "_final_error_m\": " << raw.final_m;
    }
  }
  json << "\n}\n";
  std::ofstream(fs::path(out_dir) / "summary.json") << json.str();

  // The plot: laser map from the ground truth, then every trajectory.
  std::vector<Eigen::Vector2d> map_points;
  if (truth_it != poses.end()) {
    const auto& truth = truth_it->second;
    for (const auto& s : scans) {
      const auto j = nav::NearestInTime(truth, s.utime, 20000);
      if (!j) continue;
      const nav::Pose2 sensor = truth[*j].pose.Compose({s.sensor_x_m, s.sensor_y_m, s.sensor_theta_rad});
      for (int i = 0; i < s.nranges; i += 2) {
        const double r = s.ranges_m[i];
        if (!(r < s.range_max_m) || r < s.range_min_m) continue;
        const double a = s.angle_min_rad + i * s.angle_increment_rad;
        const Eigen::Vector2d p = sensor.Transform({r * std::cos(a), r * std::sin(a)});
        if (p.allFinite()) map_points.push_back(p);
      }
    }
  }
  bool have_plot = false;
  if (!poses.empty()) {
    Plot plot;
    plot.lo = Eigen::Vector2d::Constant(1e18);
    plot.hi = Eigen::Vector2d::Constant(-1e18);
    auto extend = [&](double x, double y) {
      plot.lo = plot.lo.cwiseMin(Eigen::Vector2d(x, y));
      plot.hi = plot.hi.cwiseMax(Eigen::Vector2d(x, y));
    };
    for (const auto& [_, t] : poses)
      for (const auto& p : t) extend(p.pose.x_m, p.pose.y_m);
    for (const auto& p : map_points) extend(p.x(), p.y());
    const double span = std::max({plot.hi.x() - plot.lo.x(), plot.hi.y() - plot.lo.y(), 0.5});
    plot.scale = 820.0 / span;
    cv::Mat img(static_cast<int>((plot.hi.y() - plot.lo.y()) * plot.scale) + 2 * plot.margin + 40,
                static_cast<int>((plot.hi.x() - plot.lo.x()) * plot.scale) + 2 * plot.margin, CV_8UC3,
                cv::Scalar(255, 255, 255));
    for (const auto& p : map_points) img.at<cv::Vec3b>(plot.Px(p.x(), p.y()).y, plot.Px(p.x(), p.y()).x) = {150, 150, 150};
    const cv::Scalar colours[] = {{0, 0, 220}, {220, 120, 0}, {0, 160, 0}, {200, 0, 200}, {0, 140, 255}, {128, 128, 0}};
    int k = 0, legend_y = img.rows - 15;
    int legend_x = 10;
    // Ground truth first, so the estimates are drawn on top of it.
    std::vector<std::string> order;
    if (truth_it != poses.end()) order.push_back(truth_channel);
    for (const auto& [ch, _] : poses)
      if (ch != truth_channel) order.push_back(ch);
    for (const auto& ch : order) {
      const auto& traj = poses.at(ch);
      const bool truth = ch == truth_channel;
      const cv::Scalar colour = truth ? cv::Scalar(0, 0, 0) : colours[k++ % 6];
      std::vector<cv::Point> pts;
      for (const auto& p : traj) pts.push_back(plot.Px(p.pose.x_m, p.pose.y_m));
      cv::polylines(img, pts, false, colour, truth ? 2 : 1, cv::LINE_AA);
      cv::putText(img, ch, {legend_x, legend_y}, cv::FONT_HERSHEY_SIMPLEX, 0.45, colour, 1, cv::LINE_AA);
      legend_x += 14 + 9 * static_cast<int>(ch.size());
    }
    // One-metre scale bar.
    cv::line(img, {10, 15}, {10 + static_cast<int>(plot.scale), 15}, cv::Scalar(0, 0, 0), 2);
    cv::putText(img, "1 m", {14 + static_cast<int>(plot.scale), 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0));
    cv::imwrite((fs::path(out_dir) / "trajectories.png").string(), img);
    have_plot = true;
  }
  if (first_frame) {
    try {
      cv::imwrite((fs::path(out_dir) / "first_frame.png").string(), glue::FrameToImage(*first_frame));
    } catch (const std::exception& e) {
      std::cerr << "log-report: first omni frame not written: " << e.what() << "\n";
      first_frame.reset();
    }
  }

  std::ofstream md(fs::path(out_dir) / "report.md");
  md << "# Run report\n\nLog: `" << log_path << "` (" << file_size << " bytes" << (damaged ? ", DAMAGED" : "")
     << ")\n\n";
  if (damaged) {
    md << "The log is damaged; the figures below are of its " << log.events() << " intact events:\n\n";
    for (const auto& d : log.damage()) md << "- " << glue::DescribeLogDamage(log_path, d, log.file_size()) << "\n";
    md << "\n";
  }
  md << "## Messages\n\n" << table.str();
  if (!ate_table.str().empty()) md << "\n## Trajectory error against " << truth_channel << "\n\n" << ate_table.str();
  if (have_plot) md << "\n![trajectories](trajectories.png)\n";
  if (first_frame) md << "\n![first omni frame](first_frame.png)\n";
  std::cout << "log-report: " << out_dir << "/report.md\n" << table.str() << ate_table.str();
  return damaged ? 3 : 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
