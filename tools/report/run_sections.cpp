#include "run_sections.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "report_text.hpp"
#include "stats.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::report {
namespace {

namespace fs = std::filesystem;
using eval::Fixed;
using eval::Median;
constexpr double kDeg = M_PI / 180;
constexpr int64_t kTruthToleranceUs = 30000;  // sim: ground truth at 50 Hz, on the frames' steps


std::string Lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string StateName(int8_t s) {
  switch (s) {
    case navigator_status_t::IDLE: return "idle";
    case navigator_status_t::WAITING_FOR_POSE: return "waiting for a pose";
    case navigator_status_t::TURNING: return "turning";
    case navigator_status_t::DRIVING: return "driving";
    case navigator_status_t::HOMING: return "homing";
    case navigator_status_t::FINISHED: return "finished";
  }
  return "state " + std::to_string(s);
}

// World (x, y) -> pixel of a map covering lo..hi.
struct MapFrame {
  Eigen::Vector2d lo, hi;
  double scale = 1;
  int margin = 40;
  cv::Point Px(double x, double y) const {
    return {margin + static_cast<int>((x - lo.x()) * scale), margin + static_cast<int>((hi.y() - y) * scale)};
  }
  cv::Mat Blank() const {
    return cv::Mat(static_cast<int>((hi.y() - lo.y()) * scale) + 2 * margin,
                   static_cast<int>((hi.x() - lo.x()) * scale) + 2 * margin, CV_8UC3, cv::Scalar(255, 255, 255));
  }
};

// The series with a gap (NaN) wherever the time jumps by more than max_dt_s (e.g. a process that
// was down), so the chart does not bridge it.
plot::Series WithGaps(const std::string& name, const std::vector<double>& t, const std::vector<double>& y, double max_dt_s) {
  plot::Series s{name, {}, {}};
  for (size_t i = 0; i < t.size(); ++i) {
    if (i > 0 && t[i] - t[i - 1] > max_dt_s) {
      s.x.push_back(0.5 * (t[i] + t[i - 1]));
      s.y.push_back(NAN);
    }
    s.x.push_back(t[i]);
    s.y.push_back(y[i]);
  }
  return s;
}

}  // namespace

HomingErrors EvaluateHoming(const std::vector<homing_vector_t>& vectors, const std::vector<nav::StampedPose>& truth,
                            const Eigen::Vector2d& home, int64_t t0_us, double min_distance_m) {
  HomingErrors h;
  double sum = 0;
  int in45 = 0, in90 = 0;
  for (const auto& v : vectors) {
    ++h.vectors;
    if (!v.valid || !std::isfinite(v.direction_rad)) continue;
    ++h.valid;
    const auto j = nav::NearestInTime(truth, v.utime, kTruthToleranceUs);
    if (!j) continue;
    const nav::Pose2& p = truth[*j].pose;
    const Eigen::Vector2d to_home = home - Eigen::Vector2d(p.x_m, p.y_m);
    if (to_home.norm() < min_distance_m) continue;
    const double true_dir = std::atan2(to_home.y(), to_home.x()) - p.theta_rad;
    const double err = std::abs(nav::WrapAngle(v.direction_rad - true_dir)) / kDeg;
    ++h.evaluated;
    sum += err;
    h.max_deg = std::max(h.max_deg, err);
    in45 += err <= 45;
    in90 += err <= 90;
    h.t_s.push_back((v.utime - t0_us) * 1e-6);
    h.error_deg.push_back(err);
  }
  if (h.evaluated > 0) {
    h.mean_deg = sum / h.evaluated;
    h.median_deg = Median(h.error_deg);
    h.within_45 = static_cast<double>(in45) / h.evaluated;
    h.within_90 = static_cast<double>(in90) / h.evaluated;
  }
  return h;
}

PlaceCellErrors EvaluatePlaceCells(const std::vector<place_cell_match_t>& matches,
                                   const std::vector<nav::StampedPose>& truth, int64_t t0_us) {
  PlaceCellErrors e;
  double sum = 0;
  for (const auto& m : matches) {
    ++e.matches;
    if (m.cell_id < 0) {
      ++e.unmatched;
      continue;
    }
    const auto j = nav::NearestInTime(truth, m.utime, kTruthToleranceUs);
    if (!j) continue;
    const double err = std::hypot(m.x_m - truth[*j].pose.x_m, m.y_m - truth[*j].pose.y_m);
    ++e.evaluated;
    sum += err;
    e.max_m = std::max(e.max_m, err);
    e.t_s.push_back((m.utime - t0_us) * 1e-6);
    e.error_m.push_back(err);
  }
  if (e.evaluated > 0) {
    e.mean_m = sum / e.evaluated;
    e.median_m = Median(e.error_m);
  }
  return e;
}

Section HomingSection(const std::string& channel, const std::vector<homing_vector_t>& vectors,
                      const std::vector<nav::StampedPose>& truth, const std::optional<Eigen::Vector2d>& home,
                      int64_t t0_us, const std::string& out_dir) {
  Section s;
  const std::string key = Lower(channel);
  int valid = 0;
  for (const auto& v : vectors) valid += v.valid;
  std::ostringstream md;
  md << "\n## Homing: " << channel << "\n\n" << vectors.size() << " vectors, " << valid << " valid";
  s.json[key + "_vectors"] = vectors.size();
  s.json[key + "_valid"] = valid;
  if (!home || truth.empty()) {
    md << " (no " << (home ? "ground truth" : "home position (--home X,Y)") << ": directions not judged).\n";
    s.markdown = md.str();
    return s;
  }
  const HomingErrors h = EvaluateHoming(vectors, truth, *home, t0_us);
  md << "; home (" << Fixed(home->x()) << ", " << Fixed(home->y()) << ") m. Against the true direction home ("
     << h.evaluated << " vectors further than 0.1 m from home):\n\n"
     << "| mean angular error (deg) | median (deg) | max (deg) | within 45 deg | within 90 deg |\n|---|---|---|---|---|\n| "
     << Fixed(h.mean_deg, 1) << " | " << Fixed(h.median_deg, 1) << " | " << Fixed(h.max_deg, 1) << " | "
     << Fixed(100 * h.within_45, 0) << " % | " << Fixed(100 * h.within_90, 0) << " % |\n";
  s.json[key + "_evaluated"] = h.evaluated;
  s.json[key + "_mean_error_deg"] = results::Rounded(h.mean_deg, 2);
  s.json[key + "_median_error_deg"] = results::Rounded(h.median_deg, 2);
  s.json[key + "_within_90_fraction"] = results::Rounded(h.within_90, 3);
  if (h.evaluated == 0) {
    s.markdown = md.str();
    return s;
  }
  const std::string chart = key + "_error.png";
  plot::Axes axes;
  axes.title = "Homing error against the true direction home (" + channel + ")";
  axes.x_label = "time (s)";
  axes.y_label = "angular error (deg)";
  axes.y_min = 0;
  axes.y_max = 180;
  plot::SavePng(plot::LineChart(axes, {WithGaps("|direction - true direction|", h.t_s, h.error_deg, 1.0)}),
                (fs::path(out_dir) / chart).string());

  // The map: the true path, the home, and every n-th vector drawn at the true pose.
  MapFrame f;
  f.lo = *home;
  f.hi = *home;
  for (const auto& p : truth) {
    f.lo = f.lo.cwiseMin(Eigen::Vector2d(p.pose.x_m, p.pose.y_m));
    f.hi = f.hi.cwiseMax(Eigen::Vector2d(p.pose.x_m, p.pose.y_m));
  }
  f.lo -= Eigen::Vector2d::Constant(0.4);
  f.hi += Eigen::Vector2d::Constant(0.4);
  f.scale = 700.0 / std::max(f.hi.x() - f.lo.x(), f.hi.y() - f.lo.y());
  cv::Mat img = f.Blank();
  std::vector<cv::Point> path;
  for (const auto& p : truth) path.push_back(f.Px(p.pose.x_m, p.pose.y_m));
  cv::polylines(img, path, false, cv::Scalar(160, 160, 160), 1, cv::LINE_AA);
  const size_t step = std::max<size_t>(1, vectors.size() / 80);
  for (size_t i = 0; i < vectors.size(); i += step) {
    const auto& v = vectors[i];
    if (!v.valid) continue;
    const auto j = nav::NearestInTime(truth, v.utime, kTruthToleranceUs);
    if (!j) continue;
    const nav::Pose2& p = truth[*j].pose;
    const Eigen::Vector2d to_home = *home - Eigen::Vector2d(p.x_m, p.y_m);
    if (to_home.norm() < 0.1) continue;
    const double err =
        std::abs(nav::WrapAngle(v.direction_rad - (std::atan2(to_home.y(), to_home.x()) - p.theta_rad))) / kDeg;
    const double a = p.theta_rad + v.direction_rad;
    const cv::Scalar colour = err <= 45 ? cv::Scalar(0, 150, 0) : err <= 90 ? cv::Scalar(0, 140, 255) : cv::Scalar(0, 0, 220);
    cv::arrowedLine(img, f.Px(p.x_m, p.y_m), f.Px(p.x_m + 0.25 * std::cos(a), p.y_m + 0.25 * std::sin(a)), colour, 2,
                    cv::LINE_AA, 0, 0.3);
  }
  cv::drawMarker(img, f.Px(home->x(), home->y()), cv::Scalar(0, 0, 0), cv::MARKER_STAR, 18, 2);
  cv::putText(img, "home", f.Px(home->x(), home->y()) + cv::Point(10, -8), cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1,
              cv::LINE_AA);
  cv::putText(img, "homing vectors at the true pose: green <= 45 deg, orange <= 90 deg, red > 90 deg error",
              {10, img.rows - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.42, {0, 0, 0}, 1, cv::LINE_AA);
  cv::line(img, {10, 15}, {10 + static_cast<int>(f.scale), 15}, cv::Scalar(0, 0, 0), 2);
  cv::putText(img, "1 m", {14 + static_cast<int>(f.scale), 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0));
  const std::string map = key + "_map.png";
  plot::SavePng(img, (fs::path(out_dir) / map).string());
  md << "\n![homing error](" << chart << ")\n\n![homing vectors](" << map << ")\n";
  s.markdown = md.str();
  return s;
}

Section PlaceCellSection(const std::string& channel, const std::vector<place_cell_match_t>& matches,
                         const std::vector<nav::StampedPose>& truth, int64_t t0_us, const std::string& out_dir) {
  Section s;
  const std::string key = Lower(channel);
  const PlaceCellErrors e = EvaluatePlaceCells(matches, truth, t0_us);
  std::ostringstream md;
  md << "\n## Place cells: " << channel << "\n\n"
     << e.matches << " matches, " << e.unmatched << " views matched no cell";
  s.json[key + "_matches"] = e.matches;
  s.json[key + "_unmatched"] = e.unmatched;
  if (e.evaluated == 0) {
    md << (truth.empty() ? " (no ground truth)" : "") << ".\n";
    s.markdown = md.str();
    return s;
  }
  md << ". Distance from the matched cell to the true position (" << e.evaluated << " views):\n\n"
     << "| mean (m) | median (m) | max (m) |\n|---|---|---|\n| " << Fixed(e.mean_m, 3) << " | " << Fixed(e.median_m, 3)
     << " | " << Fixed(e.max_m, 3) << " |\n";
  s.json[key + "_mean_cell_error_m"] = results::Rounded(e.mean_m, 4);
  s.json[key + "_median_cell_error_m"] = results::Rounded(e.median_m, 4);
  s.json[key + "_max_cell_error_m"] = results::Rounded(e.max_m, 4);
  const std::string chart = key + "_error.png";
  plot::Axes axes;
  axes.title = "Matched place cell against the true position (" + channel + ")";
  axes.x_label = "time (s)";
  axes.y_label = "distance (m)";
  axes.y_from_zero = true;
  plot::SavePng(plot::LineChart(axes, {WithGaps("matched cell - true position", e.t_s, e.error_m, 2.0)}),
                (fs::path(out_dir) / chart).string());
  md << "\n![place-cell error](" << chart << ")\n";
  s.markdown = md.str();
  return s;
}

Section NavigatorSection(const std::string& channel, const std::vector<navigator_status_t>& statuses,
                         const std::vector<nav::StampedPose>& truth, int64_t t0_us, const std::string& out_dir) {
  Section s;
  const std::string key = Lower(channel);
  std::ostringstream md;
  md << "\n## Navigator: " << channel << "\n\n";
  if (statuses.empty()) {
    md << "No status.\n";
    s.markdown = md.str();
    return s;
  }
  const navigator_status_t& last = statuses.back();
  md << "Route '" << last.route_name << "' (" << last.nwaypoints << " waypoints): " << last.arrivals
     << " waypoints reached, " << last.laps << " laps completed, final state " << StateName(last.state) << "; place-cell fixes "
     << last.fixes_accepted << " accepted, " << last.fixes_rejected << " rejected, " << last.tracker_resets
     << " tracker resets.\n";
  s.json[key + "_arrivals"] = last.arrivals;
  s.json[key + "_laps"] = last.laps;
  s.json[key + "_fixes_accepted"] = last.fixes_accepted;
  s.json[key + "_fixes_rejected"] = last.fixes_rejected;
  // Arrivals (the count going up) and the tracked position against the truth.
  std::vector<double> t, dist, err;
  double err_sum = 0, err_max = 0;
  int err_n = 0, prev_arrivals = 0, prev_waypoint = -1;
  std::ostringstream arrivals;
  for (const auto& st : statuses) {
    const double ts = (st.utime - t0_us) * 1e-6;
    if (st.arrivals > prev_arrivals) {  // the waypoint it headed for before this status
      arrivals << (arrivals.tellp() > 0 ? ", " : "") << prev_waypoint << " at " << Fixed(ts, 1) << " s";
      prev_arrivals = st.arrivals;
    }
    prev_waypoint = st.waypoint_index;
    if (st.state == navigator_status_t::IDLE || st.state == navigator_status_t::WAITING_FOR_POSE) continue;
    t.push_back(ts);
    dist.push_back(st.distance_to_waypoint_m);
    double e = NAN;
    if (const auto j = nav::NearestInTime(truth, st.utime, kTruthToleranceUs)) {
      e = std::hypot(st.x_m - truth[*j].pose.x_m, st.y_m - truth[*j].pose.y_m);
      err_sum += e;
      err_max = std::max(err_max, e);
      ++err_n;
    }
    err.push_back(e);
  }
  if (arrivals.tellp() > 0) md << "\nWaypoints reached (index, time since the start of the log): " << arrivals.str() << ".\n";
  if (err_n > 0) {
    md << "\nTracked position against the true position: mean " << Fixed(err_sum / err_n, 3) << " m, max "
       << Fixed(err_max, 3) << " m (" << err_n << " statuses).\n";
    s.json[key + "_mean_tracking_error_m"] = results::Rounded(err_sum / err_n, 4);
    s.json[key + "_max_tracking_error_m"] = results::Rounded(err_max, 4);
  }
  if (!t.empty()) {
    const std::string chart = key + ".png";
    plot::Axes axes;
    axes.title = "Navigator progress (" + channel + ")";
    axes.x_label = "time (s)";
    axes.y_label = "m";
    axes.y_from_zero = true;
    std::vector<plot::Series> series{{"distance to the waypoint (tracked)", t, dist}};
    if (err_n > 0) series.push_back({"tracked position - true position", t, err});
    plot::SavePng(plot::LineChart(axes, series), (fs::path(out_dir) / chart).string());
    md << "\n![navigator](" << chart << ")\n";
  }
  s.markdown = md.str();
  return s;
}

std::vector<Delivery> CompareDelivery(const std::vector<ProcessLog>& logs, const std::map<std::string, int64_t>& recorded) {
  std::map<std::string, Delivery> by_channel;
  for (const auto& log : logs) {
    const auto totals = log.Totals();
    for (const auto& [ch, c] : totals) {
      Delivery& d = by_channel[ch];
      d.channel = ch;
      if (c.published > 0) {  // a run that reported published on it; a run that did not may have too
        d.publishers.push_back(log.name);
        d.published += c.published;
        d.exact = d.exact && log.complete();
      }
      if (c.received > 0) d.received.emplace_back(log.name, c.received);
    }
  }
  std::vector<Delivery> out;
  for (auto& [ch, d] : by_channel) {
    if (d.publishers.empty()) continue;
    const auto it = recorded.find(ch);
    d.recorded = it == recorded.end() ? 0 : static_cast<uint64_t>(it->second);
    out.push_back(std::move(d));
  }
  return out;
}

Section DeliverySection(const std::vector<ProcessLog>& logs, const std::map<std::string, int64_t>& recorded) {
  Section s;
  std::ostringstream md;
  md << "\n## Delivery: published by the processes, recorded in the log\n\n"
     << "Counts each process printed at its end (its bus statistics, in the launcher's process logs) against the "
        "messages in the log. A run killed by a signal prints no counts: its channels' published counts are lower "
        "bounds (marked >=).\n\n"
     << "| channel | publisher | published | recorded | lost | received by |\n|---|---|---|---|---|---|\n";
  // (A subscriber that ran once and received fewer than were published shows "(N missed)".)
  uint64_t lost_total = 0, missed_total = 0;
  int exact_channels = 0;
  std::map<std::string, const ProcessLog*> by_name;
  for (const auto& log : logs) by_name[log.name] = &log;
  for (const auto& d : CompareDelivery(logs, recorded)) {
    std::string pubs, recv;
    for (const auto& p : d.publishers) pubs += (pubs.empty() ? "" : ", ") + p;
    for (const auto& [name, n] : d.received) {
      recv += (recv.empty() ? "" : ", ") + name + " " + std::to_string(n);
      // A subscriber that ran once, start to end, should have every message of an exact channel.
      const ProcessLog* log = by_name.at(name);
      if (d.exact && log->runs.size() == 1 && log->complete() && n < d.published) {
        missed_total += d.published - n;
        recv += " (" + std::to_string(d.published - n) + " missed)";
      }
    }
    std::string lost;
    if (d.exact) {
      ++exact_channels;
      const uint64_t l = d.published > d.recorded ? d.published - d.recorded : 0;
      lost_total += l;
      lost = std::to_string(l);
      if (d.recorded > d.published) lost += " (" + std::to_string(d.recorded - d.published) + " more recorded)";
      s.json["delivery_" + Lower(d.channel) + "_published"] = d.published;
      s.json["delivery_" + Lower(d.channel) + "_recorded"] = d.recorded;
    } else {
      lost = "unknown";
    }
    md << "| " << d.channel << " | " << pubs << " | " << (d.exact ? "" : ">= ") << d.published << " | " << d.recorded
       << " | " << lost << " | " << (recv.empty() ? "-" : recv) << " |\n";
  }
  s.json["delivery_exact_channels"] = exact_channels;
  s.json["delivery_lost_total"] = lost_total;
  s.json["delivery_missed_by_subscribers_total"] = missed_total;
  // The runs of each process and the launcher's words about them.
  md << "\n| process | runs | runs that reported counts | launcher |\n|---|---|---|---|\n";
  int restarts = 0;
  for (const auto& log : logs) {
    int reported = 0;
    for (const auto& r : log.runs) reported += r.reported;
    restarts += std::max<int>(0, static_cast<int>(log.runs.size()) - 1);
    std::string notes;
    for (const auto& l : log.launcher_lines) {
      if (l.find("ended (") != std::string::npos || l.find("FAILED") != std::string::npos ||
          l.find("restarted") != std::string::npos || l.find("not a clean stop") != std::string::npos) {
        notes += (notes.empty() ? "" : "; ") + l;
      }
    }
    md << "| " << log.name << " | " << log.runs.size() << " | " << reported << " | " << (notes.empty() ? "-" : notes)
       << " |\n";
    s.json["process_" + Lower(log.name) + "_runs"] = log.runs.size();
  }
  s.json["process_restarts_total"] = restarts;
  s.markdown = md.str();
  return s;
}

std::string DeliveryCsv(const std::vector<ProcessLog>& logs, const std::map<std::string, int64_t>& recorded) {
  std::ostringstream csv;
  csv << "process,runs,reported_runs,channel,published,received,rejected,handler_errors,recorded\n";
  for (const auto& log : logs) {
    int reported = 0;
    for (const auto& r : log.runs) reported += r.reported;
    for (const auto& [ch, c] : log.Totals()) {
      const auto it = recorded.find(ch);
      csv << log.name << "," << log.runs.size() << "," << reported << "," << ch << "," << c.published << ","
          << c.received << "," << c.rejected << "," << c.handler_errors << "," << (it == recorded.end() ? 0 : it->second)
          << "\n";
    }
  }
  return csv.str();
}

AteWindows EvaluateAteWindows(const std::vector<nav::StampedPose>& estimate, const std::vector<nav::StampedPose>& truth,
                              int64_t t0_us, double window_s) {
  if (!(window_s > 0)) throw std::invalid_argument("ATE window must be positive");
  AteWindows w;
  std::map<int64_t, std::pair<double, int>> bins;  // window index -> (sum of squared errors, poses)
  for (const auto& e : estimate) {
    const auto j = nav::NearestInTime(truth, e.utime, kTruthToleranceUs);
    if (!j) continue;
    const double err = std::hypot(e.pose.x_m - truth[*j].pose.x_m, e.pose.y_m - truth[*j].pose.y_m);
    auto& b = bins[static_cast<int64_t>(std::floor((e.utime - t0_us) * 1e-6 / window_s))];
    b.first += err * err;
    ++b.second;
  }
  for (const auto& [k, b] : bins) {
    w.start_s.push_back(k * window_s);
    w.rmse_m.push_back(std::sqrt(b.first / b.second));
    w.poses.push_back(b.second);
  }
  const size_t n = w.rmse_m.size();
  if (n == 0) return w;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < n; ++i) {
    const double x = (w.start_s[i] + window_s / 2) / 3600.0, y = w.rmse_m[i];
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    w.max_m = std::max(w.max_m, y);
  }
  w.mean_m = sy / n;
  const double den = n * sxx - sx * sx;
  w.trend_m_per_h = n >= 2 && den > 0 ? (n * sxy - sx * sy) / den : 0;
  const size_t third = std::max<size_t>(1, n / 3);
  double first = 0, last = 0;
  for (size_t i = 0; i < third; ++i) {
    first += w.rmse_m[i];
    last += w.rmse_m[n - 1 - i];
  }
  w.growth_m = (last - first) / third;
  return w;
}

Section AteOverTimeSection(const std::map<std::string, std::vector<nav::StampedPose>>& estimates,
                           const std::vector<nav::StampedPose>& truth, int64_t t0_us, double window_s,
                           const std::string& out_dir) {
  Section s;
  std::ostringstream md, csv;
  md << "\n## Trajectory error over time (windows of " << Fixed(window_s, 0) << " s)\n\n"
     << "Each estimator's RMSE against the ground truth per window of message time (no alignment): a trend is "
        "the least-squares slope of the windows' RMSE, growth the mean of the last third of the windows minus "
        "the first third's. Dead reckoning has no correction: its error grows by design.\n\n"
     << "| estimator channel | windows | first window (m) | last window (m) | max (m) | mean (m) | trend (m per hour) "
        "| growth (m) |\n|---|---|---|---|---|---|---|---|\n";
  csv << "channel,window_start_s,window_end_s,poses,rmse_m\n";
  std::vector<plot::Series> series;
  for (const auto& [ch, traj] : estimates) {
    const AteWindows w = EvaluateAteWindows(traj, truth, t0_us, window_s);
    if (w.rmse_m.empty()) continue;
    const std::string key = Lower(ch);
    md << "| " << ch << " | " << w.rmse_m.size() << " | " << Fixed(w.rmse_m.front(), 3) << " | "
       << Fixed(w.rmse_m.back(), 3) << " | " << Fixed(w.max_m, 3) << " | " << Fixed(w.mean_m, 3) << " | "
       << Fixed(w.trend_m_per_h, 3) << " | " << Fixed(w.growth_m, 3) << " |\n";
    s.json[key + "_ate_windows"] = w.rmse_m.size();
    s.json[key + "_ate_window_first_m"] = results::Rounded(w.rmse_m.front(), 4);
    s.json[key + "_ate_window_last_m"] = results::Rounded(w.rmse_m.back(), 4);
    s.json[key + "_ate_window_max_m"] = results::Rounded(w.max_m, 4);
    s.json[key + "_ate_window_mean_m"] = results::Rounded(w.mean_m, 4);
    s.json[key + "_ate_trend_m_per_h"] = results::Rounded(w.trend_m_per_h, 4);
    s.json[key + "_ate_growth_m"] = results::Rounded(w.growth_m, 4);
    plot::Series line{ch, {}, w.rmse_m};
    for (size_t i = 0; i < w.rmse_m.size(); ++i) {
      line.x.push_back((w.start_s[i] + window_s / 2) / 60.0);
      csv << ch << "," << w.start_s[i] << "," << w.start_s[i] + window_s << "," << w.poses[i] << "," << w.rmse_m[i] << "\n";
    }
    series.push_back(std::move(line));
  }
  s.json["ate_window_s"] = results::Rounded(window_s, 1);
  std::ofstream(fs::path(out_dir) / "ate_windows.csv") << csv.str();
  if (!series.empty()) {
    plot::Axes axes;
    axes.title = "Position error per " + Fixed(window_s, 0) + " s window against the ground truth";
    axes.x_label = "time [min]";
    axes.y_label = "RMSE [m]";
    axes.y_from_zero = true;
    plot::SavePng(plot::LineChart(axes, series, {1000, 560}), (fs::path(out_dir) / "ate_over_time.png").string());
    md << "\n![error over time](ate_over_time.png)\n";
  }
  s.markdown = md.str();
  return s;
}

}  // namespace snapnav::report
