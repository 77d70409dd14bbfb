// log-report: what a recorded run contains and how well each estimator did.
// Reads an LCM log and writes into --out: report.md, summary.json,
// trajectories.png (every pose channel against the ground truth, over the laser
// map drawn from the ground-truth poses, with the navigator's waypoints), the first omni
// frame as PNG, and for the navigation stack's outputs (run_sections.hpp): the homing
// vectors against the true direction home (--home), the place-cell matches, the navigator's
// progress, and with --process-logs the delivery of every message (published / recorded).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
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
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/pose_correction_t.hpp"
#include "snapnav/pose_t.hpp"
#include "process_logs.hpp"
#include "results.hpp"
#include "run_sections.hpp"

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
  std::string home_text, process_logs_dir, prefix;
  double ate_window_s = 0;
  glue::Flags flags("log-report LOG",
                    "Summarises an LCM log: messages per channel, and for every pose_t channel its trajectory\n"
                    "error (ATE) against the ground truth; writes report.md, summary.json and PNG plots. A pose\n"
                    "channel that laser-slam's graph back end corrected (pose_correction_t in the log) is also\n"
                    "reported as the log's last correction puts it (\"CHANNEL (corrected)\").\n"
                    "A damaged log (truncated, corrupt) is reported with the byte offset of each damaged place\n"
                    "and summarised from its intact events; the exit status is then 3.");
  flags.AddString("out", &out_dir, "output folder (default: beside the log)");
  flags.AddString("truth", &truth_channel, "ground-truth pose channel");
  flags.AddString("scan", &scan_channel, "laser channel for the map drawn from the ground truth");
  flags.AddString("channel-prefix", &prefix,
                  "one robot of several on one bus: only the channels with this prefix (the truth and scan channels get it)");
  flags.AddDouble("ate-window-s", &ate_window_s,
                  "also each estimator's error per window of this much message time, its trend and growth "
                  "(ate_over_time.png, ate_windows.csv) [s]; 0: not");
  flags.AddString("home", &home_text, "X,Y: the homing vectors' home in the map frame [m]; judged against the truth");
  flags.AddString("process-logs", &process_logs_dir,
                  "folder of the launcher's process logs (NAME.log): published counts against the recorded ones and\n"
                  "what each subscriber received (also delivery.csv); several folders comma-separated, the processes\n"
                  "then named FOLDER/NAME");
  flags.AllowPositional("LOG", "the LCM log");
  if (!flags.Parse(argc, argv)) return 0;
  if (flags.positional().size() != 1) throw glue::FlagError("expected one LOG (see --help)");
  const std::string log_path = flags.positional()[0];
  if (ate_window_s < 0) throw glue::FlagError("--ate-window-s must be >= 0");
  truth_channel = prefix + truth_channel;
  scan_channel = prefix + scan_channel;
  if (out_dir.empty()) out_dir = fs::path(log_path).parent_path().string();
  if (out_dir.empty()) out_dir = ".";
  fs::create_directories(out_dir);
  std::optional<Eigen::Vector2d> home;
  if (!home_text.empty()) {
    const auto parts = glue::SplitList(home_text);
    char* end1 = nullptr;
    char* end2 = nullptr;
    if (parts.size() != 2) throw glue::FlagError("--home expects X,Y, got '" + home_text + "'");
    const double x = std::strtod(parts[0].c_str(), &end1), y = std::strtod(parts[1].c_str(), &end2);
    if (parts[0].empty() || parts[1].empty() || *end1 || *end2) throw glue::FlagError("--home expects X,Y, got '" + home_text + "'");
    home = Eigen::Vector2d(x, y);
  }
  std::vector<report::ProcessLog> process_logs;
  const std::vector<std::string> process_log_dirs = glue::SplitList(process_logs_dir);
  for (const auto& dir : process_log_dirs) {
    if (!fs::is_directory(dir)) throw glue::FlagError("--process-logs: no folder '" + dir + "'");
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.path().extension() == ".log") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    const std::string folder = fs::path(dir).lexically_normal().filename().string().empty()
                                   ? fs::path(dir).lexically_normal().parent_path().filename().string()
                                   : fs::path(dir).lexically_normal().filename().string();
    for (const auto& f : files) {
      std::ifstream in(f);
      const std::string name = process_log_dirs.size() > 1 ? folder + "/" + f.stem().string() : f.stem().string();
      process_logs.push_back(report::ParseProcessLog(name, in));
    }
  }

  // glue::LogReader reads every intact event and names the byte offset of any damage.
  glue::LogReader log(log_path);
  const auto file_size = static_cast<int64_t>(log.file_size());
  std::map<std::string, ChannelInfo> info;
  std::map<std::string, std::vector<nav::StampedPose>> poses;  // by channel
  std::vector<laser_scan_t> scans;
  std::optional<omni_frame_t> first_frame;
  std::map<std::string, std::vector<homing_vector_t>> homing;        // by channel
  std::map<std::string, std::vector<place_cell_match_t>> matches;    // by channel
  std::map<std::string, std::vector<navigator_status_t>> statuses;   // by channel
  // The newest correction table of each pose channel (laser-slam's graph back end: pose_correction_t).
  std::map<std::string, glue::PoseCorrections> corrections;
  glue::LogEvent ev;
  while (log.Next(&ev)) {
    if (ev.channel.rfind(prefix, 0) != 0) continue;  // another robot's
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
    } else if (*fp == static_cast<uint64_t>(homing_vector_t::getHash())) {
      if (auto v = glue::Decode<homing_vector_t>(ev.data.data(), ev.data.size(), &error)) {
        homing[ev.channel].push_back(std::move(*v));
      } else {
        ++ci.rejected;
      }
    } else if (*fp == static_cast<uint64_t>(place_cell_match_t::getHash())) {
      if (auto m = glue::Decode<place_cell_match_t>(ev.data.data(), ev.data.size(), &error)) {
        matches[ev.channel].push_back(std::move(*m));
      } else {
        ++ci.rejected;
      }
    } else if (*fp == static_cast<uint64_t>(pose_correction_t::getHash())) {
      const auto c = glue::Decode<pose_correction_t>(ev.data.data(), ev.data.size(), &error);
      if (!c || corrections.try_emplace(c->pose_channel, c->pose_channel).first->second.Take(*c, &error) ==
                    glue::PoseCorrections::Taken::kInvalid) {
        ++ci.rejected;
      }
    } else if (*fp == static_cast<uint64_t>(navigator_status_t::getHash())) {
      if (auto st = glue::Decode<navigator_status_t>(ev.data.data(), ev.data.size(), &error)) {
        statuses[ev.channel].push_back(std::move(*st));
      } else {
        ++ci.rejected;
      }
    }
  }
  // A pose channel its estimator corrected afterwards (a loop closure moves the past): beside the
  // poses as published, the trajectory as the log's last correction puts them.
  for (const auto& [ch, c] : corrections) {
    const auto it = poses.find(ch);
    if (it == poses.end() || c.tables() == 0) continue;
    std::vector<nav::StampedPose> corrected = it->second;
    for (nav::StampedPose& p : corrected) p.pose = c.Correct(p.utime, p.pose);
    poses[ch + " (corrected)"] = std::move(corrected);
    std::cerr << "log-report: " << ch << " also as correction " << c.corrections() << " puts it (" << c.tables()
              << " correction tables in the log)\n";
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
  results::Json json;
  json["log"] = log_path;
  json["log_bytes"] = file_size;
  json["log_valid_bytes"] = good_bytes;
  json["log_damaged_places"] = log.damage().size();
  std::ostringstream table;
  table << "| channel | messages | rate (Hz) | MB |\n|---|---|---|---|\n";
  for (const auto& [ch, ci] : info) {
    const double span = (ci.last_us - ci.first_us) * 1e-6;
    table << "| " << ch << " | " << ci.count << " | " << std::fixed << std::setprecision(1)
          << (span > 0 ? (ci.count - 1) / span : 0.0) << " | " << std::setprecision(2) << ci.bytes / 1e6 << " |\n";
    json["messages_" + ch] = ci.count;
    if (ci.rejected > 0) json["rejected_" + ch] = ci.rejected;
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
      std::string key;  // the channel, lower case; " (corrected)" as "_corrected"
      for (const char c : ch) {
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') {
          key += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        } else if (!key.empty() && key.back() != '_') {
          key += '_';
        }
      }
      while (!key.empty() && key.back() == '_') key.pop_back();
      json[key + "_ate_rmse_m"] = results::Rounded(raw.rmse_m, 4);
      json[key + "_aligned_ate_rmse_m"] = results::Rounded(aligned.rmse_m, 4);
      json[key + "_final_error_m"] = results::Rounded(raw.final_m, 4);
    }
  }
  // The navigation stack's outputs, judged against the ground truth; the delivery of every message.
  const std::vector<nav::StampedPose> no_truth;
  const auto& truth = truth_it != poses.end() ? truth_it->second : no_truth;
  int64_t t0_us = truth.empty() ? INT64_MAX : truth.front().utime;
  if (truth.empty()) {
    for (const auto& [_, v] : homing) t0_us = std::min(t0_us, v.front().utime);
    for (const auto& [_, m] : matches) t0_us = std::min(t0_us, m.front().utime);
    for (const auto& [_, st] : statuses) t0_us = std::min(t0_us, st.front().utime);
  }
  std::vector<report::Section> sections;
  for (const auto& [ch, v] : homing) sections.push_back(report::HomingSection(ch, v, truth, home, t0_us, out_dir));
  for (const auto& [ch, m] : matches) sections.push_back(report::PlaceCellSection(ch, m, truth, t0_us, out_dir));
  for (const auto& [ch, st] : statuses) sections.push_back(report::NavigatorSection(ch, st, truth, t0_us, out_dir));
  if (ate_window_s > 0 && !truth.empty()) {
    std::map<std::string, std::vector<nav::StampedPose>> estimates = poses;
    estimates.erase(truth_channel);
    sections.push_back(report::AteOverTimeSection(estimates, truth, t0_us, ate_window_s, out_dir));
  }
  if (!process_logs.empty()) {
    std::map<std::string, int64_t> recorded;
    for (const auto& [ch, ci] : info) recorded[ch] = ci.count;
    sections.push_back(report::DeliverySection(process_logs, recorded));
    std::ofstream(fs::path(out_dir) / "delivery.csv") << report::DeliveryCsv(process_logs, recorded);
  }
  for (const auto& section : sections) json.update(section.json);
  results::WriteJsonFile((fs::path(out_dir) / "summary.json").string(), json);
  // The navigator's waypoints, for the map.
  std::vector<std::pair<int, Eigen::Vector2d>> waypoints;
  for (const auto& [_, sts] : statuses) {
    for (const auto& st : sts) {
      if (st.waypoint_index < 0) continue;
      const Eigen::Vector2d w(st.waypoint_x_m, st.waypoint_y_m);
      bool known = false;
      for (const auto& [i, p] : waypoints) known = known || (i == st.waypoint_index && (p - w).norm() < 1e-6);
      if (!known) waypoints.emplace_back(st.waypoint_index, w);
    }
  }

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
    for (const auto& [_, w] : waypoints) extend(w.x(), w.y());
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
    for (const auto& [i, w] : waypoints) {
      const cv::Point c = plot.Px(w.x(), w.y());
      cv::rectangle(img, c - cv::Point(4, 4), c + cv::Point(4, 4), cv::Scalar(120, 0, 120), 1, cv::LINE_AA);
      cv::putText(img, std::to_string(i), c + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(120, 0, 120), 1,
                  cv::LINE_AA);
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
  for (const auto& section : sections) md << section.markdown;
  std::cout << "log-report: " << out_dir << "/report.md\n" << table.str() << ate_table.str();
  return damaged ? 3 : 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
