#include "slam_log.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "importers.hpp"
#include "report_text.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/log_reader.hpp"
#include "snapnav/glue/strings.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/dead_reckoning.hpp"
#include "snapnav/nav/slam/cell_key.hpp"
#include "snapnav/nav/slam/point_grid_map.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::eval {
namespace {

using glue::EndsWith;

using Clock = std::chrono::steady_clock;

// The ranges of a scan as a key: scans of the same reading are byte-identical floats.
std::string RangesKey(const laser_scan_t& s) {
  return std::string(reinterpret_cast<const char*>(s.ranges_m.data()), s.ranges_m.size() * sizeof(float));
}

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

}  // namespace

bool UsableScan(const laser_scan_t& s) {
  // As the laser-slam process checks a scan (processes/laser_slam).
  return !s.ranges_m.empty() && std::isfinite(s.angle_min_rad) && std::isfinite(s.angle_increment_rad) &&
         s.angle_increment_rad != 0 && s.range_min_m >= 0 && s.range_max_m > s.range_min_m && s.range_max_m <= 10000 &&
         std::abs(s.sensor_x_m) <= 10000 && std::abs(s.sensor_y_m) <= 10000 && std::abs(s.sensor_theta_rad) <= 100;
}

SlamLog LoadSlamLog(const std::string& path, bool progress) {
  glue::LogReader file(path);  // throws naming the file when it cannot be opened
  SlamLog log;
  log.path = path;
  glue::LogEvent e;
  while (file.Next(&e)) {
    ++log.events;
    std::string error;
    if (e.channel == channels::kOdometry) {
      const auto m = glue::Decode<odometry_t>(e.data.data(), e.data.size(), &error);
      if (!m || !glue::OdometryProblem(*m, false).empty()) { ++log.rejected; continue; }
      SlamStep step;
      step.utime = m->utime;
      step.odometry_delta = glue::OdometryDelta(*m);
      log.steps.push_back(std::move(step));
      ++log.odometry;
    } else if (e.channel == channels::kLaserScan) {
      const auto s = glue::Decode<laser_scan_t>(e.data.data(), e.data.size(), &error);
      if (!s || !UsableScan(*s)) {
        ++log.rejected;
        continue;
      }
      SlamStep step;
      step.is_scan = true;
      step.utime = s->utime;
      step.points = nav::ScanToPoints(s->ranges_m, s->angle_min_rad, s->angle_increment_rad, s->range_min_m,
                                      s->range_max_m, nav::Pose2{s->sensor_x_m, s->sensor_y_m, s->sensor_theta_rad});
      step.ranges_key = RangesKey(*s);
      step.range_max_m = s->range_max_m;
      if (log.beams == 0) log.beams = static_cast<int>(s->ranges_m.size());
      log.steps.push_back(std::move(step));
      ++log.scans;
      if (progress && log.scans % 500 == 0) std::cerr << "eval-slam: read " << log.scans << " scans\r" << std::flush;
    }
  }
  log.damaged_places = static_cast<int>(file.damage().size());
  log.damaged_bytes = file.damaged_bytes();
  for (const auto& d : file.damage()) log.damage.push_back(glue::DescribeLogDamage(path, d, file.file_size()));
  for (const auto& d : log.damage) std::cerr << "eval-slam: warning: " << d << "\n";
  if (log.scans == 0) throw std::runtime_error(path + " holds no " + std::string(channels::kLaserScan) + " messages");
  if (progress) {
    std::cerr << "eval-slam: " << path << ": " << log.scans << " scans of " << log.beams << " beams, " << log.odometry
              << " odometry, " << log.rejected << " undecodable or invalid, " << log.events << " events"
              << (log.damaged_places > 0 ? ", " + std::to_string(log.damaged_bytes) + " damaged bytes skipped" : "")
              << "\n";
  }
  return log;
}

std::optional<nav::Pose2> Reference::Find(const std::string& ranges_key, int64_t utime, int64_t max_dt_us) const {
  if (!by_ranges.empty()) {
    const auto it = by_ranges.find(ranges_key);
    if (it == by_ranges.end()) return std::nullopt;
    return it->second;
  }
  if (const auto i = nav::NearestInTime(by_time, utime, max_dt_us)) return by_time[*i].pose;
  return std::nullopt;
}

namespace {


// Poses by time, one per line: a CSV `utime,x,y,theta` (a header line starting with `utime`, `#`
// comments), or MRPT's ground truth of its simulated datasets (`*.rawlog.GT.txt`, as in
// /usr/share/mrpt/datasets/graphslam-engine-demos: `timestamp x y phi`, Unix seconds, whitespace,
// `%` or `#` comments). Further columns are ignored. Sorted by time.
void ReadTimedPoses(const std::string& path, bool mrpt, Reference* ref) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open reference " + path);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#' || (mrpt && line[first] == '%') ||
        (!mrpt && line.compare(first, 5, "utime") == 0)) {
      continue;
    }
    if (!mrpt) std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    double t = 0;
    nav::StampedPose p;
    const bool ok = static_cast<bool>(s >> t >> p.pose.x_m >> p.pose.y_m >> p.pose.theta_rad) && std::isfinite(t) &&
                    t >= 0 && t < (mrpt ? 1e10 : 1e17) && std::isfinite(p.pose.x_m) && std::isfinite(p.pose.y_m) &&
                    std::isfinite(p.pose.theta_rad);
    if (!ok) {
      throw std::runtime_error(path + ":" + std::to_string(n) +
                               (mrpt ? ": expected 'timestamp x y phi' (MRPT ground truth: Unix seconds, metres, radians)"
                                     : ": expected utime,x,y,theta"));
    }
    p.utime = mrpt ? std::llround(t * 1e6) : std::llround(t);
    ref->by_time.push_back(p);
  }
  std::sort(ref->by_time.begin(), ref->by_time.end(), [](auto& a, auto& b) { return a.utime < b.utime; });
  if (ref->by_time.empty()) throw std::runtime_error("reference " + path + " holds no poses");
}

}  // namespace

namespace {

std::vector<float> RangesOfKey(const std::string& key) {
  std::vector<float> r(key.size() / sizeof(float));
  std::memcpy(r.data(), key.data(), r.size() * sizeof(float));
  return r;
}

// Whether two readings of the same scan agree (AlignReference).
bool SameReading(const std::vector<float>& a, float a_max, const std::vector<float>& b, float b_max) {
  if (a.size() != b.size() || a.empty()) return false;
  constexpr float kTolerance = 0.001f;
  const float cap = std::min(a_max, b_max) - kTolerance;
  size_t compared = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const bool a_far = a[i] >= cap, b_far = b[i] >= cap;
    if (a_far != b_far) return false;
    if (a_far) continue;
    if (std::abs(a[i] - b[i]) > kTolerance) return false;
    ++compared;
  }
  return compared >= std::max<size_t>(5, a.size() / 10);
}

}  // namespace

void AlignReference(const SlamLog& log, Reference* reference) {
  reference->paired_exactly = reference->paired_by_overlap = 0;
  if (reference->scans.empty()) return;
  std::vector<const SlamStep*> scans;
  for (const SlamStep& s : log.steps) {
    if (!s.is_scan) continue;
    scans.push_back(&s);
    if (reference->by_ranges.count(s.ranges_key)) ++reference->paired_exactly;
  }
  const size_t reference_scans = reference->by_ranges.size();
  if (static_cast<size_t>(reference->paired_exactly) >= std::min(reference_scans, scans.size())) return;
  std::vector<std::vector<float>> ranges;
  ranges.reserve(scans.size());
  for (const SlamStep* s : scans) ranges.push_back(RangesOfKey(s->ranges_key));
  std::map<std::string, nav::Pose2> added;
  size_t next = 0;
  for (const Reference::Scan& r : reference->scans) {
    for (size_t k = next; k < scans.size(); ++k) {
      if (!SameReading(ranges[k], scans[k]->range_max_m, r.ranges_m, r.range_max_m)) continue;
      if (!reference->by_ranges.count(scans[k]->ranges_key) && added.emplace(scans[k]->ranges_key, r.pose).second) {
        ++reference->paired_by_overlap;
      }
      next = k + 1;
      break;
    }
  }
  reference->by_ranges.insert(added.begin(), added.end());
}

Reference LoadReference(const std::string& path, const SlamLog* log) {
  Reference ref;
  ref.path = path;
  if (EndsWith(path, ".txt") || EndsWith(path, ".csv")) {
    const bool mrpt = EndsWith(path, ".txt");
    ReadTimedPoses(path, mrpt, &ref);
    if (mrpt) std::cerr << "eval-slam: reference " << path << ": " << ref.by_time.size() << " poses (MRPT ground truth)\n";
    return ref;
  }
  VectorSink sink;
  importers::CarmenOptions options;
  options.time_source = importers::TimeSource::kLog;
  importers::ImportCarmenFile(path, sink, options);
  // Each FLASER line gives a scan and its pose, next to each other in the output (the
  // corrected log's times are truncated, so times do not tell lines apart).
  std::optional<std::string> pending_scan;
  float pending_range_max_m = 0;
  std::optional<nav::Pose2> pending_pose;
  for (const auto& e : sink.events) {
    if (e.channel == channels::kLaserScan) {
      laser_scan_t s;
      if (s.decode(e.payload.data(), 0, static_cast<int>(e.payload.size())) <= 0) continue;
      if (pending_pose) {
        ref.by_ranges.emplace(RangesKey(s), *pending_pose);
        ref.scans.push_back({s.ranges_m, s.range_max_m, *pending_pose});
        pending_pose.reset();
      } else {
        pending_scan = RangesKey(s);
        pending_range_max_m = s.range_max_m;
      }
    } else if (e.channel == importers::kPoseCarmen) {
      pose_t p;
      if (p.decode(e.payload.data(), 0, static_cast<int>(e.payload.size())) <= 0) continue;
      if (pending_scan) {
        ref.by_ranges.emplace(*pending_scan, glue::FromPoseMsg(p));
        ref.scans.push_back({RangesOfKey(*pending_scan), pending_range_max_m, glue::FromPoseMsg(p)});
        pending_scan.reset();
      } else {
        pending_pose = glue::FromPoseMsg(p);
      }
    }
  }
  std::cerr << "eval-slam: reference " << path << ": " << ref.by_ranges.size() << " scans with poses\n";
  if (ref.by_ranges.empty()) throw std::runtime_error("reference " + path + " holds no scans with poses");
  if (log) {
    const size_t reference_scans = ref.by_ranges.size();
    AlignReference(*log, &ref);
    const int paired = ref.paired_exactly + ref.paired_by_overlap;
    std::cerr << "eval-slam: " << paired << " of the log's " << log->scans << " scans paired with the reference's "
              << reference_scans << " (" << ref.paired_exactly << " by identical ranges, " << ref.paired_by_overlap
              << " by their readings below the lower maximum range)\n";
    if (2 * static_cast<size_t>(paired) < std::min<size_t>(reference_scans, static_cast<size_t>(log->scans))) {
      std::cerr << "eval-slam: warning: fewer than half of the scans pair with the reference " << path
                << ": is it the reference of this log? Its figures are over " << paired << " scans only\n";
    }
  }
  return ref;
}

SlamRun RunSlam(const SlamLog& log, const nav::LaserSlamOptions& options) {
  nav::LaserSlam slam(options);
  nav::DeadReckoning dr({});
  SlamRun run;
  run.slam.reserve(log.scans);
  for (const SlamStep& step : log.steps) {
    if (!step.is_scan) {
      slam.Predict(step.odometry_delta, step.utime);
      dr.AddOdometry(step.odometry_delta);
      continue;
    }
    const auto t0 = Clock::now();
    const nav::LaserSlamUpdate u = slam.Update(step.points, step.utime);
    run.update_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    run.updates.push_back(u);
    run.utime.push_back(step.utime);
    run.ranges_key.push_back(step.ranges_key);
    // The pose of the scan (where it was matched: its utime less scan_latency_s), as a reference
    // aligned on the scans holds it; pose() is that pose carried on by the odometry since.
    run.slam.push_back(slam.scan_pose());
    run.dead_reckoning.push_back(dr.pose());
  }
  run.map = slam.map().points();
  return run;
}

namespace {
OdometryFigure FigureOf(const nav::OdometryCalibration& c) {
  OdometryFigure f;
  f.measured = c.observations() > 0;
  f.drift_deg_per_m = c.drift_rad_per_m() / nav::kRadPerDeg;
  f.turn_scale = c.turn_scale();
  f.distance_scale = c.distance_scale();
  f.stretches = c.observations();
  return f;
}
}  // namespace

OdometryFigure SlamOdometryCalibration(const SlamRun& run) {
  OdometryFigure f;
  if (run.updates.empty()) return f;
  const nav::LaserSlamUpdate& u = run.updates.back();
  f.measured = u.odometry_calibration_stretches > 0;
  f.drift_deg_per_m = u.odometry_drift_rad_per_m / nav::kRadPerDeg;
  f.turn_scale = u.odometry_turn_scale;
  f.distance_scale = u.odometry_distance_scale;
  f.stretches = u.odometry_calibration_stretches;
  return f;
}

OdometryFigure ReferenceOdometryCalibration(const SlamRun& run, const Reference& reference,
                                            const nav::LaserSlamOptions& options) {
  nav::OdometryCalibration calibration(options.odometry_calibration);
  std::optional<size_t> start;
  std::optional<nav::Pose2> start_reference;
  double path = 0, turn = 0;
  for (size_t i = 0; i < run.dead_reckoning.size() && i < run.utime.size(); ++i) {
    if (start && i > 0) {
      const nav::Pose2 step = run.dead_reckoning[i - 1].Between(run.dead_reckoning[i]);
      path += std::copysign(std::hypot(step.x_m, step.y_m), step.x_m);
      turn += step.theta_rad;
    }
    const auto truth = reference.Find(run.ranges_key[i], run.utime[i]);
    if (!truth) continue;
    if (start && calibration.LongEnough(path, turn)) {
      calibration.Observe(run.dead_reckoning[*start].Between(run.dead_reckoning[i]), path, turn,
                          start_reference->Between(*truth), nav::MotionHeadingVariance(options.motion, path, turn));
    } else if (start) {
      continue;  // the stretch goes on
    }
    start = i;
    start_reference = *truth;
    path = turn = 0;
  }
  return FigureOf(calibration);
}

std::string DescribeOdometry(const OdometryFigure& f) {
  if (!f.measured) return "no stretch of good matches to measure it";
  char text[160];
  std::snprintf(text, sizeof text, "heading drift %+.2f deg/m, turns %+.1f %%, distance %+.1f %% (%d stretches)",
                f.drift_deg_per_m, 100 * f.turn_scale, 100 * f.distance_scale, f.stretches);
  return text;
}

std::vector<std::pair<nav::Pose2, nav::Pose2>> PairWithReference(const std::vector<nav::Pose2>& estimate,
                                                                 const SlamRun& run, const Reference& reference) {
  std::vector<std::pair<nav::Pose2, nav::Pose2>> pairs;
  for (size_t i = 0; i < estimate.size() && i < run.utime.size(); ++i) {
    if (const auto truth = reference.Find(run.ranges_key[i], run.utime[i])) pairs.push_back({estimate[i], *truth});
  }
  return pairs;
}

MapConsistency ComputeMapConsistency(const SlamLog& log, const std::vector<std::optional<nav::Pose2>>& poses,
                                     int min_separation_scans, double max_distance_m, int min_pairs) {
  // The scans' points in the world on a grid of kCell: a cell keeps the point of the earliest and
  // of the latest scan that hit it (a point of a scan at least min_separation_scans away, if there
  // is one, is one of these two). A query visits the cells ring by ring and stops once no nearer
  // cell is left: linear in the points, however often a place is seen again (a dense log that
  // drives a corridor twice has thousands of scans on each wall).
  constexpr double kCell = 0.05;
  constexpr size_t kQueryPoints = 90;  // a scan's points queried, evenly spaced over the scan
  struct Cell {
    int first_scan, last_scan;
    Eigen::Vector2d first, last;
  };
  const auto key = [](int64_t cx, int64_t cy) { return static_cast<int64_t>(nav::CellKey(cx, cy)); };
  const auto cell_of = [](double v) { return static_cast<int64_t>(std::floor(v / kCell)); };
  std::unordered_map<int64_t, Cell> grid;
  std::vector<std::vector<Eigen::Vector2d>> world;
  for (const SlamStep& step : log.steps) {
    if (!step.is_scan) continue;
    const int i = static_cast<int>(world.size());
    world.emplace_back();
    if (i >= static_cast<int>(poses.size()) || !poses[i]) continue;
    for (const Eigen::Vector2d& q : step.points) {
      const Eigen::Vector2d p = poses[i]->Transform(q);
      world.back().push_back(p);
      const auto [it, fresh] = grid.try_emplace(key(cell_of(p.x()), cell_of(p.y())), Cell{i, i, p, p});
      if (!fresh) {
        it->second.last_scan = i;  // scans come in order
        it->second.last = p;
      }
    }
  }
  const int rings = static_cast<int>(std::ceil(max_distance_m / kCell)) + 1;
  MapConsistency c;
  c.per_scan_m.assign(world.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<double> medians;
  for (size_t i = 0; i < world.size(); ++i) {
    std::vector<double> d;
    const size_t step = std::max<size_t>(1, (world[i].size() + kQueryPoints - 1) / kQueryPoints);
    for (size_t k = 0; k < world[i].size(); k += step) {
      const Eigen::Vector2d& p = world[i][k];
      const int64_t cx = cell_of(p.x()), cy = cell_of(p.y());
      double best = max_distance_m * max_distance_m;
      bool found = false;
      for (int r = 0; r <= rings; ++r) {
        // Every cell of ring r is at least (r - 1) cells from p.
        if (found && best <= std::pow(std::max(0, r - 1) * kCell, 2)) break;
        for (int64_t dx = -r; dx <= r; ++dx) {
          for (int64_t dy = -r; dy <= r; ++dy) {
            if (std::max(std::abs(dx), std::abs(dy)) != r) continue;
            const auto it = grid.find(key(cx + dx, cy + dy));
            if (it == grid.end()) continue;
            const Cell& cell = it->second;
            for (const auto& [scan, q] : {std::pair<int, Eigen::Vector2d>{cell.first_scan, cell.first},
                                          std::pair<int, Eigen::Vector2d>{cell.last_scan, cell.last}}) {
              if (std::abs(scan - static_cast<int>(i)) < min_separation_scans) continue;
              const double d2 = (q - p).squaredNorm();
              if (d2 <= best) {
                best = d2;
                found = true;
              }
            }
          }
        }
      }
      if (found) d.push_back(std::sqrt(best));
    }
    if (static_cast<int>(d.size()) < min_pairs) continue;
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    c.per_scan_m[i] = d[d.size() / 2];
    medians.push_back(c.per_scan_m[i]);
  }
  c.scans = static_cast<int>(medians.size());
  if (!medians.empty()) {
    double sum = 0;
    for (const double m : medians) sum += m;
    c.mean_m = sum / static_cast<double>(medians.size());
    std::nth_element(medians.begin(), medians.begin() + static_cast<std::ptrdiff_t>(medians.size() / 2), medians.end());
    c.median_m = medians[medians.size() / 2];
  }
  return c;
}

ReferenceCheck CheckReference(const SlamLog& log, const Reference& reference, const ReferenceCheckOptions& options) {
  if (options.window < 1 || !(options.near_m > 0) || !(options.max_turn_deg >= 1) || !(options.min_gain > 0)) {
    throw std::invalid_argument("reference check: window >= 1, near_m > 0, max_turn_deg >= 1 and min_gain > 0 needed");
  }
  struct Placed {
    const std::vector<Eigen::Vector2d>* points;
    nav::Pose2 pose;
    int scan;
  };
  std::vector<Placed> placed;
  int scan = -1;
  for (const SlamStep& step : log.steps) {
    if (!step.is_scan) continue;
    ++scan;
    if (step.points.empty()) continue;
    if (const auto pose = reference.Find(step.ranges_key, step.utime)) placed.push_back({&step.points, *pose, scan});
  }
  ReferenceCheck check;
  const int turns = static_cast<int>(std::floor(options.max_turn_deg));
  const auto window = static_cast<size_t>(options.window);
  std::vector<double> fits(static_cast<size_t>(2 * turns + 1));
  for (size_t k = window; k < placed.size(); ++k) {
    // The previous scans at their reference poses (every point: a cell of a fifth of near_m).
    nav::PointGridMap before(options.near_m / 5, options.near_m);
    for (size_t j = k - window; j < k; ++j) {
      for (const Eigen::Vector2d& p : *placed[j].points) before.Add(placed[j].pose.Transform(p));
    }
    const auto fit = [&](const nav::Pose2& pose) {
      size_t n = 0;
      for (const Eigen::Vector2d& p : *placed[k].points) n += before.NearestIndex(pose.Transform(p), options.near_m) >= 0;
      return static_cast<double>(n) / static_cast<double>(placed[k].points->size());
    };
    ReferenceSuspect s;
    s.scan = placed[k].scan;
    s.fit = s.turned_fit = fit(placed[k].pose);
    ++check.checked;
    if (s.fit > 1 - options.min_gain) continue;  // no heading can fit min_gain better
    // The best heading; where several fit equally, the middle of them.
    for (int d = -turns; d <= turns; ++d) {
      nav::Pose2 turned = placed[k].pose;
      turned.theta_rad += d * M_PI / 180;
      fits[static_cast<size_t>(d + turns)] = d == 0 ? s.fit : fit(turned);
    }
    s.turned_fit = *std::max_element(fits.begin(), fits.end());
    double sum = 0;
    int n = 0;
    for (int d = -turns; d <= turns; ++d) {
      if (fits[static_cast<size_t>(d + turns)] >= s.turned_fit - 1e-9) {
        sum += d;
        ++n;
      }
    }
    s.turn_deg = std::round(sum / n);
    if (s.turned_fit - s.fit >= options.min_gain) check.suspects.push_back(s);
  }
  return check;
}

std::string DescribeReferenceCheck(const ReferenceCheck& check) {
  std::ostringstream o;
  o << check.suspects.size() << " of " << check.checked << " reference poses disagree with their scans";
  for (size_t i = 0; i < check.suspects.size(); ++i) {
    const ReferenceSuspect& s = check.suspects[i];
    o << (i == 0 ? ": " : ", ") << "scan " << s.scan << " (fit " << Fixed(s.fit, 2) << " at the reference, "
      << Fixed(s.turned_fit, 2) << " turned " << (s.turn_deg > 0 ? "+" : "") << Fixed(s.turn_deg, 0)
      << " deg)";
  }
  return o.str();
}

void WriteReferenceCheckCsv(const std::string& path, const ReferenceCheck& check) {
  std::ofstream csv(path);
  if (!csv) throw std::runtime_error("cannot write " + path);
  csv << "scan,fit,turned_fit,turn_deg\n";
  for (const ReferenceSuspect& s : check.suspects) {
    csv << s.scan << "," << Fixed(s.fit, 4) << "," << Fixed(s.turned_fit, 4) << "," << s.turn_deg << "\n";
  }
}

}  // namespace snapnav::eval
