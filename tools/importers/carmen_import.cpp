// CARMEN text logs -> LASER_SCAN, ODOMETRY and POSE_CARMEN.
//
// Lines understood (fields separated by spaces; every line ends with "timestamp host
// logger_timestamp", timestamp in seconds):
//   FLASER n r1..rn x y theta odom_x odom_y odom_theta timestamp host logger_timestamp
//   ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy
//       remission_mode n r1..rn m rem1..remm laser_pose_x laser_pose_y laser_pose_theta
//       robot_pose_x robot_pose_y robot_pose_theta laser_tv laser_rv forward_safety_dist
//       side_safety_dist turn_axis timestamp host logger_timestamp
//   ODOM x y theta tv rv accel timestamp host logger_timestamp
// '#' starts a comment line. Other message kinds (PARAM, SYNC, TRUEPOS, RAWLASER*, NMEA...)
// are skipped and counted; PARAM robot_frontlaser_offset is read (FLASER laser mounting).

#include <algorithm>
#include <cmath>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "import_util.hpp"
#include "importers.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::importers {
namespace {

using internal::ParseDouble;
using internal::ParseInt64;
using internal::Quote;

constexpr size_t kMaxLineBytes = size_t{4} << 20;  // a 100000-beam line with remissions fits
constexpr int64_t kMaxReadings = 100000;           // per scan line
constexpr char kScanSensorFlaser[] = "carmen_front_laser";
constexpr char kScanSensorRobotLaser[] = "carmen_robot_laser";
constexpr char kOdometrySensor[] = "carmen_odometry";
constexpr char kPoseFrame[] = "map";
// Lines (besides comments) without a CARMEN message before the first one that make a file "not a
// CARMEN log" instead of one error per line.
constexpr int64_t kLinesToRecognise = 5;
constexpr char kCarmenShape[] =
    " (a CARMEN log is text, one message per line: 'FLASER 181 ...', 'ROBOTLASER1 ...', 'ODOM x y theta ...')";

enum class Kind { kScan, kOdom };

struct Record {
  Kind kind = Kind::kOdom;
  int64_t line = 0;
  double timestamp_s = 0;  // as logged [s]; <= 0: none
  bool used = true;
  nav::Pose2 robot_pose;  // odometry pose: ODOM x y theta, FLASER odom_*, ROBOTLASER1 robot_pose
  bool has_velocity = false;
  double tv_mps = 0;
  double rv_radps = 0;
  // Scans only.
  const char* sensor_name = "";
  nav::Pose2 logged_pose;      // robot pose the log assigns to the scan (POSE_CARMEN)
  nav::Pose2 sensor_on_robot;  // laser mounting
  float angle_min_rad = 0;
  float angle_increment_rad = 0;
  float range_max_m = 0;
  std::vector<float> ranges_m;
  std::vector<float> intensities;
};

// Reads numbered fields of one line, remembering the first problem.
class Fields {
 public:
  Fields(const char* kind, const std::vector<std::string_view>& tokens) : kind_(kind), tokens_(tokens) {}

  double Number(size_t index, const std::string& what) {
    if (!error_.empty()) return 0;
    const auto v = ParseDouble(tokens_[index]);
    if (!v) {
      error_ = std::string(kind_) + " " + what + " (field " + std::to_string(index + 1) +
               ") is not a number: " + Quote(tokens_[index]);
      return 0;
    }
    return *v;
  }
  std::optional<int64_t> Count(size_t index, const std::string& what, int64_t max) {
    if (!error_.empty()) return std::nullopt;
    const auto v = ParseInt64(tokens_[index]);
    if (!v) {
      error_ = std::string(kind_) + " " + what + " (field " + std::to_string(index + 1) +
               ") is not an integer: " + Quote(tokens_[index]);
      return std::nullopt;
    }
    if (*v < 0 || *v > max) {
      error_ = std::string(kind_) + " " + what + " " + std::to_string(*v) + " is outside 0.." + std::to_string(max);
      return std::nullopt;
    }
    return v;
  }
  void Fail(const std::string& reason) {
    if (error_.empty()) error_ = reason;
  }
  const std::string& error() const { return error_; }

 private:
  const char* kind_;
  const std::vector<std::string_view>& tokens_;
  std::string error_;
};

bool IsMessageKind(std::string_view word) {
  if (word.empty() || word.front() < 'A' || word.front() > 'Z') return false;
  return std::all_of(word.begin(), word.end(),
                     [](char c) { return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_'; });
}

// Judges the start of a file, line by line until its first CARMEN message: binary data, an
// endless line or only lines of something else there mean the file is no CARMEN log at all.
class StartJudge {
 public:
  // The reason the file is not a CARMEN log, "" while it may be one. `line_start`: the line's first
  // byte in the (decompressed) input.
  std::string Judge(internal::LineReader::Status status, const internal::LineReader& reader, int64_t line_start) {
    if (recognised_) return "";
    const std::string at_line = "line " + std::to_string(reader.line_number());
    if (status == internal::LineReader::Status::kTooLong) {
      return at_line + " is longer than " + std::to_string(kMaxLineBytes) + " bytes, before any CARMEN message";
    }
    const std::string& line = reader.line();
    for (size_t i = 0; i < line.size(); ++i) {
      const auto c = static_cast<unsigned char>(line[i]);
      if ((c < 0x20 && c != '\t' && c != '\r' && c != '\v' && c != '\f') || c == 0x7f) {
        static const char hex[] = "0123456789abcdef";
        return "byte " + std::to_string(line_start + static_cast<int64_t>(i)) + " (" + at_line +
               ") is binary data (0x" + hex[c >> 4] + hex[c & 15] + "), before any CARMEN message";
      }
    }
    internal::Tokenize(line, &tokens_);
    if (tokens_.empty() || tokens_[0].front() == '#') return "";
    if (IsMessageKind(tokens_[0])) {
      recognised_ = true;
      return "";
    }
    if (first_other_.empty()) first_other_ = at_line + " starts with " + Quote(tokens_[0]);
    if (++other_lines_ < kLinesToRecognise) return "";
    return "none of its first " + std::to_string(kLinesToRecognise) +
           " lines (besides comments) is a CARMEN message (" + first_other_ + ")";
  }

 private:
  bool recognised_ = false;
  int64_t other_lines_ = 0;
  std::string first_other_;
  std::vector<std::string_view> tokens_;
};

class Parser {
 public:
  Parser(const std::string& name, const CarmenOptions& options, ImportReport& report)
      : name_(name), options_(options), report_(report) {}

  // Returns false if the line was malformed (already reported).
  bool ParseLine(std::string_view line, int64_t number) {
    internal::Tokenize(line, &tokens_);
    if (tokens_.empty()) return true;
    if (tokens_[0].front() == '#') {
      ++report_.comment_lines;
      return true;
    }
    const std::string_view kind = tokens_[0];
    std::string error;
    if (kind == "FLASER") {
      error = ParseFlaser(number);
    } else if (kind == "ROBOTLASER1") {
      error = ParseRobotLaser(number);
    } else if (kind == "ODOM") {
      error = ParseOdom(number);
    } else if (IsMessageKind(kind)) {
      if (kind == "PARAM" && tokens_.size() >= 3 && tokens_[1] == "robot_frontlaser_offset") {
        if (const auto v = ParseDouble(tokens_[2])) front_laser_offset_m_ = *v;
      }
      ++report_.skipped[std::string(kind)];
      return true;
    } else {
      error = "not a CARMEN message: first word " + Quote(kind);
    }
    if (!error.empty()) {
      Fail(number, error);
      return false;
    }
    return true;
  }

  void Fail(int64_t line, const std::string& reason) {
    report_.AddError(name_ + ":" + std::to_string(line) + ": " + reason);
  }

  std::vector<Record>& records() { return records_; }
  int64_t negative_readings() const { return negative_readings_; }
  int64_t dropped_remissions() const { return dropped_remissions_; }

 private:
  // Fills ranges, mapping "no return" and negative readings to range_max_m.
  void ReadRanges(Fields& f, size_t first, int64_t n, float range_max_m, std::vector<float>* out) {
    out->resize(static_cast<size_t>(n));
    for (int64_t i = 0; i < n && f.error().empty(); ++i) {
      double r = f.Number(first + static_cast<size_t>(i), "reading " + std::to_string(i + 1));
      if (r < 0) {
        ++negative_readings_;
        r = range_max_m;
      }
      if (r >= kCarmenNoReturnThresholdM || r >= range_max_m) r = range_max_m;
      (*out)[static_cast<size_t>(i)] = static_cast<float>(r);
    }
  }

  // The trailing "timestamp host logger_timestamp" starting at `index`.
  double Timestamp(Fields& f, size_t index) {
    const double t = f.Number(index, "timestamp");
    f.Number(index + 2, "logger_timestamp");
    return t;
  }

  std::string ParseFlaser(int64_t line) {
    Fields f("FLASER", tokens_);
    if (tokens_.size() < 2) return "FLASER without a reading count";
    const auto n = f.Count(1, "reading count", kMaxReadings);
    if (!n) return f.error();
    if (*n == 0) return "FLASER with 0 readings";
    const size_t expected = static_cast<size_t>(*n) + 11;
    if (tokens_.size() != expected) {
      return "FLASER declares " + std::to_string(*n) + " readings, so the line needs " + std::to_string(expected) +
             " fields, but it has " + std::to_string(tokens_.size()) +
             (tokens_.size() < expected ? " (truncated?)" : "");
    }
    Record r;
    r.kind = Kind::kScan;
    r.line = line;
    r.sensor_name = kScanSensorFlaser;
    r.range_max_m = static_cast<float>(options_.flaser_max_range_m);
    ReadRanges(f, 2, *n, r.range_max_m, &r.ranges_m);
    const size_t p = 2 + static_cast<size_t>(*n);
    const nav::Pose2 laser_pose{f.Number(p, "x"), f.Number(p + 1, "y"), f.Number(p + 2, "theta")};
    r.robot_pose = {f.Number(p + 3, "odom_x"), f.Number(p + 4, "odom_y"), f.Number(p + 5, "odom_theta")};
    r.timestamp_s = Timestamp(f, p + 6);
    if (!f.error().empty()) return f.error();
    // CARMEN writes the laser's pose: the robot pose moved forward by the front laser offset.
    r.sensor_on_robot = {front_laser_offset_m_, 0.0, 0.0};
    r.logged_pose = laser_pose.Compose(r.sensor_on_robot.Inverse());
    const double fov_rad = options_.flaser_fov_deg * M_PI / 180.0;
    r.angle_min_rad = static_cast<float>(-fov_rad / 2);
    // 181 or 361 beams cover both ends of the field of view; 180 or 360 start at its right
    // end and stop one step short of the left (CARMEN's and GMapping's convention).
    const int64_t steps = (*n % 2 == 1) ? *n - 1 : *n;
    r.angle_increment_rad = steps > 0 ? static_cast<float>(fov_rad / static_cast<double>(steps)) : 0.0f;
    records_.push_back(std::move(r));
    return "";
  }

  std::string ParseRobotLaser(int64_t line) {
    Fields f("ROBOTLASER1", tokens_);
    if (tokens_.size() < 10) {
      return "ROBOTLASER1 needs at least 10 fields before the readings, it has " + std::to_string(tokens_.size());
    }
    const auto n = f.Count(8, "reading count", kMaxReadings);
    if (!n) return f.error();
    if (*n == 0) return "ROBOTLASER1 with 0 readings";
    const size_t m_index = 9 + static_cast<size_t>(*n);
    if (tokens_.size() <= m_index) {
      return "ROBOTLASER1 declares " + std::to_string(*n) + " readings, but the line has only " +
             std::to_string(tokens_.size()) + " fields (truncated?)";
    }
    const auto m = f.Count(m_index, "remission count", kMaxReadings);
    if (!m) return f.error();
    const size_t expected = static_cast<size_t>(*n + *m) + 24;
    if (tokens_.size() != expected) {
      return "ROBOTLASER1 declares " + std::to_string(*n) + " readings and " + std::to_string(*m) +
             " remissions, so the line needs " + std::to_string(expected) + " fields, but it has " +
             std::to_string(tokens_.size()) + (tokens_.size() < expected ? " (truncated?)" : "");
    }
    Record r;
    r.kind = Kind::kScan;
    r.line = line;
    r.sensor_name = kScanSensorRobotLaser;
    f.Count(1, "laser_type", 1000);
    const double start_angle = f.Number(2, "start_angle");
    const double fov = f.Number(3, "field_of_view");
    double resolution = f.Number(4, "angular_resolution");
    const double max_range = f.Number(5, "maximum_range");
    f.Number(6, "accuracy");
    f.Number(7, "remission_mode");
    if (!f.error().empty()) return f.error();
    if (!(max_range > 0)) return "ROBOTLASER1 maximum_range " + std::to_string(max_range) + " is not positive";
    if (*n > 1 && resolution == 0) {
      if (fov == 0) return "ROBOTLASER1 has neither angular_resolution nor field_of_view";
      resolution = fov / static_cast<double>(*n - 1);
    }
    r.range_max_m = static_cast<float>(max_range);
    ReadRanges(f, 9, *n, r.range_max_m, &r.ranges_m);
    if (*m == *n) {
      r.intensities.resize(static_cast<size_t>(*m));
      for (int64_t i = 0; i < *m; ++i) {
        r.intensities[static_cast<size_t>(i)] =
            static_cast<float>(f.Number(m_index + 1 + static_cast<size_t>(i), "remission " + std::to_string(i + 1)));
      }
    } else {
      for (int64_t i = 0; i < *m; ++i) f.Number(m_index + 1 + static_cast<size_t>(i), "remission");
      if (*m > 0) ++dropped_remissions_;
    }
    const size_t p = m_index + 1 + static_cast<size_t>(*m);
    const nav::Pose2 laser_pose{f.Number(p, "laser_pose_x"), f.Number(p + 1, "laser_pose_y"),
                                f.Number(p + 2, "laser_pose_theta")};
    r.robot_pose = {f.Number(p + 3, "robot_pose_x"), f.Number(p + 4, "robot_pose_y"),
                    f.Number(p + 5, "robot_pose_theta")};
    r.tv_mps = f.Number(p + 6, "laser_tv");
    r.rv_radps = f.Number(p + 7, "laser_rv");
    r.has_velocity = true;
    f.Number(p + 8, "forward_safety_dist");
    f.Number(p + 9, "side_safety_dist");
    f.Number(p + 10, "turn_axis");
    r.timestamp_s = Timestamp(f, p + 11);
    if (!f.error().empty()) return f.error();
    r.logged_pose = r.robot_pose;
    r.sensor_on_robot = r.robot_pose.Between(laser_pose);
    if (resolution < 0) {  // clockwise scan: store it counter-clockwise
      std::reverse(r.ranges_m.begin(), r.ranges_m.end());
      std::reverse(r.intensities.begin(), r.intensities.end());
      r.angle_min_rad = static_cast<float>(start_angle + resolution * static_cast<double>(*n - 1));
      r.angle_increment_rad = static_cast<float>(-resolution);
    } else {
      r.angle_min_rad = static_cast<float>(start_angle);
      r.angle_increment_rad = static_cast<float>(resolution);
    }
    records_.push_back(std::move(r));
    return "";
  }

  std::string ParseOdom(int64_t line) {
    if (tokens_.size() != 10) {
      return "ODOM needs 10 fields (ODOM x y theta tv rv accel timestamp host logger_timestamp), it has " +
             std::to_string(tokens_.size());
    }
    Fields f("ODOM", tokens_);
    Record r;
    r.kind = Kind::kOdom;
    r.line = line;
    r.robot_pose = {f.Number(1, "x"), f.Number(2, "y"), f.Number(3, "theta")};
    r.tv_mps = f.Number(4, "tv");
    r.rv_radps = f.Number(5, "rv");
    r.has_velocity = true;
    f.Number(6, "accel");
    r.timestamp_s = Timestamp(f, 7);
    if (!f.error().empty()) return f.error();
    records_.push_back(std::move(r));
    return "";
  }

  const std::string& name_;
  const CarmenOptions& options_;
  ImportReport& report_;
  std::vector<std::string_view> tokens_;
  std::vector<Record> records_;
  double front_laser_offset_m_ = 0.0;
  int64_t negative_readings_ = 0;
  int64_t dropped_remissions_ = 0;
};

std::string Seconds(double t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", t);
  return buf;
}

// Why the logged timestamps cannot be used as message times, or nullopt if they can:
// every scan and every odometry message needs a positive time after its predecessor's.
std::optional<std::string> TimestampProblem(const std::vector<Record>& records, bool odometry_from_odom) {
  struct Stream {
    const char* what;
    bool any = false;
    double t = 0;
    int64_t line = 0;
  };
  Stream scans{"scan"}, odoms{"ODOM"};
  for (const auto& r : records) {
    if (!r.used) continue;
    Stream* streams[2] = {nullptr, nullptr};
    if (r.kind == Kind::kScan) streams[0] = &scans;
    if (r.kind == Kind::kOdom && odometry_from_odom) streams[1] = &odoms;
    for (Stream* s : streams) {
      if (s == nullptr) continue;
      if (!(r.timestamp_s > 0)) {
        return "line " + std::to_string(r.line) + ": " + s->what + " timestamp " + Seconds(r.timestamp_s) +
               " is not positive";
      }
      if (s->any && r.timestamp_s <= s->t) {
        return "line " + std::to_string(r.line) + ": " + s->what + " timestamp " + Seconds(r.timestamp_s) +
               " is not after line " + std::to_string(s->line) + "'s (" + Seconds(s->t) + ")";
      }
      s->any = true;
      s->t = r.timestamp_s;
      s->line = r.line;
    }
  }
  return std::nullopt;
}

class Writer {
 public:
  Writer(const CarmenOptions& options, internal::Emitter& emitter) : options_(options), emitter_(emitter) {}

  void Scan(const Record& r, int64_t utime) {
    laser_scan_t scan{};
    scan.utime = utime;
    scan.sensor_name = r.sensor_name;
    scan.sensor_x_m = static_cast<float>(r.sensor_on_robot.x_m);
    scan.sensor_y_m = static_cast<float>(r.sensor_on_robot.y_m);
    scan.sensor_theta_rad = static_cast<float>(r.sensor_on_robot.theta_rad);
    scan.angle_min_rad = r.angle_min_rad;
    scan.angle_increment_rad = r.angle_increment_rad;
    scan.time_increment_s = 0;
    scan.range_min_m = 0;
    scan.range_max_m = r.range_max_m;
    scan.nranges = static_cast<int32_t>(r.ranges_m.size());
    scan.ranges_m = r.ranges_m;
    scan.nintensities = static_cast<int32_t>(r.intensities.size());
    scan.intensities = r.intensities;
    emitter_.Emit(options_.channels.laser_scan, scan);
    emitter_.Emit(options_.channels.pose_carmen,
                  glue::ToPoseMsg(utime, kCarmenEstimator, kPoseFrame, r.logged_pose, Eigen::Matrix3d::Zero()));
  }

  void Odometry(const Record& r, int64_t utime) {
    odometry_t odo{};
    odo.utime = utime;
    odo.sensor_name = kOdometrySensor;
    odo.x_m = r.robot_pose.x_m;
    odo.y_m = r.robot_pose.y_m;
    odo.theta_rad = r.robot_pose.theta_rad;
    nav::Pose2 delta;
    double dt = 0;
    if (have_previous_) {
      delta = previous_pose_.Between(r.robot_pose);
      dt = static_cast<double>(utime - previous_utime_) * 1e-6;
    }
    odo.delta_x_m = delta.x_m;
    odo.delta_y_m = delta.y_m;
    odo.delta_theta_rad = delta.theta_rad;
    odo.delta_t_s = dt;
    if (r.has_velocity) {
      odo.linear_velocity_mps = r.tv_mps;
      odo.angular_velocity_radps = r.rv_radps;
    } else {
      odo.linear_velocity_mps = dt > 0 ? delta.x_m / dt : 0.0;
      odo.angular_velocity_radps = dt > 0 ? delta.theta_rad / dt : 0.0;
    }
    emitter_.Emit(options_.channels.odometry, odo);
    have_previous_ = true;
    previous_pose_ = r.robot_pose;
    previous_utime_ = utime;
  }

 private:
  const CarmenOptions& options_;
  internal::Emitter& emitter_;
  bool have_previous_ = false;
  nav::Pose2 previous_pose_;
  int64_t previous_utime_ = 0;
};

void WriteRecords(std::vector<Record>& records, const CarmenOptions& options, Sink& sink, ImportReport& report) {
  const auto flaser =
      std::count_if(records.begin(), records.end(), [](const Record& r) { return r.sensor_name == kScanSensorFlaser; });
  const auto robot_laser = std::count_if(records.begin(), records.end(),
                                         [](const Record& r) { return r.sensor_name == kScanSensorRobotLaser; });
  if (flaser > 0 && robot_laser > 0) {
    report.notes.push_back("the log has both FLASER and ROBOTLASER1 lines (" + std::to_string(flaser) + " and " +
                           std::to_string(robot_laser) + "); both were written, with sensor_name " + kScanSensorFlaser +
                           " and " + kScanSensorRobotLaser);
  }
  // Odometry: from ODOM lines if the log has them, else from each scan's odometry pose.
  const bool odometry_from_odom =
      std::any_of(records.begin(), records.end(), [](const Record& r) { return r.kind == Kind::kOdom; });
  if (odometry_from_odom) {
    const bool any_timed = std::any_of(records.begin(), records.end(),
                                       [](const Record& r) { return r.kind == Kind::kOdom && r.timestamp_s > 0; });
    int64_t untimed = 0;
    for (auto& r : records) {
      if (any_timed && r.kind == Kind::kOdom && !(r.timestamp_s > 0)) {
        r.used = false;
        ++untimed;
      }
    }
    if (untimed > 0) {
      report.skipped["ODOM with timestamp 0"] += untimed;
      report.notes.push_back(std::to_string(untimed) +
                             " ODOM lines with timestamp 0 skipped: they are not odometry readings (GMapping "
                             "writes the corrected pose that way after each scan)");
    }
    report.notes.push_back("odometry from the ODOM lines (the scans' odometry poses are not used)");
  } else {
    report.notes.push_back("odometry from the odometry pose of each scan line (the log has no ODOM lines)");
  }

  bool synthesize = options.time_source == TimeSource::kSynthesize;
  const auto problem = TimestampProblem(records, odometry_from_odom);
  int64_t t0 = kSynthesizedStartUtime;
  for (const auto& r : records) {
    if (r.used && r.timestamp_s > 0) {
      if (const auto u = internal::SecondsToUtime(r.timestamp_s)) {
        t0 = *u;
        break;
      }
    }
  }
  if (problem && options.time_source == TimeSource::kAuto) synthesize = true;
  if (synthesize) {
    report.notes.push_back(
        "times synthesized: one message line every " + Seconds(1.0 / options.rate_hz) + " s from " +
        internal::FormatUtime(t0) + " s" +
        (problem ? ", because the logged timestamps are unusable (" + *problem + ")" : std::string(", as asked")));
  } else if (problem) {
    report.notes.push_back("logged timestamps kept as asked, although " + *problem);
  }

  internal::Emitter emitter(sink, report);
  Writer writer(options, emitter);
  int64_t index = 0;
  for (const auto& r : records) {
    if (!r.used) continue;
    int64_t utime = 0;
    if (synthesize) {
      utime = t0 + static_cast<int64_t>(std::llround(static_cast<double>(index) * 1e6 / options.rate_hz));
    } else {
      utime = internal::SecondsToUtime(r.timestamp_s).value_or(0);
    }
    ++index;
    if (r.kind == Kind::kOdom) {
      writer.Odometry(r, utime);
    } else {
      if (!odometry_from_odom) writer.Odometry(r, utime);
      writer.Scan(r, utime);
    }
  }
  if (synthesize) {
    for (const auto& [name, stats] : report.channels) report.synthesized_utimes += stats.count;
  }
}

}  // namespace

void CarmenOptions::Validate() const {
  if (!(flaser_fov_deg > 0 && flaser_fov_deg <= 360)) {
    throw std::invalid_argument("CARMEN FLASER field of view must be in (0, 360] deg");
  }
  if (!(flaser_max_range_m > 0)) throw std::invalid_argument("CARMEN FLASER max range must be positive");
  if (!(rate_hz > 0 && rate_hz <= 1e6)) throw std::invalid_argument("synthesized rate must be in (0, 1e6] Hz");
}

ImportReport ImportCarmen(std::istream& in, const std::string& name, Sink& sink, const CarmenOptions& options) {
  options.Validate();
  ImportReport report;
  report.input = name;
  Parser parser(name, options, report);
  internal::LineReader reader(in, kMaxLineBytes);
  StartJudge judge;
  int64_t next_progress = options.progress_every_bytes;
  int64_t lines = 0;
  for (;;) {
    const int64_t line_start = reader.bytes_read();
    const auto status = reader.Next();
    if (status == internal::LineReader::Status::kEnd) break;
    ++lines;
    if (const std::string not_carmen = judge.Judge(status, reader, line_start); !not_carmen.empty()) {
      // One error for the file instead of one per line of it (nothing was imported yet).
      report.errors.clear();
      report.error_count = 0;
      report.AddError(name + " is not a CARMEN log: " + not_carmen + kCarmenShape);
      return report;
    }
    if (status == internal::LineReader::Status::kTooLong) {
      parser.Fail(reader.line_number(), "line longer than " + std::to_string(kMaxLineBytes) + " bytes; skipped");
      continue;
    }
    const bool ok = parser.ParseLine(reader.line(), reader.line_number());
    if (!reader.had_newline() && ok && !reader.line().empty()) {
      report.notes.push_back("the last line (" + std::to_string(reader.line_number()) +
                             ") has no newline at its end; it was complete and imported");
    }
    if (options.progress && reader.bytes_read() >= next_progress) {
      options.progress({reader.bytes_read(), options.total_bytes, "bytes"});
      next_progress = reader.bytes_read() + options.progress_every_bytes;
    }
  }
  if (in.bad()) report.AddError(name + ": read error after line " + std::to_string(reader.line_number()));
  if (parser.negative_readings() > 0) {
    report.notes.push_back(std::to_string(parser.negative_readings()) + " negative readings written as no return");
  }
  if (parser.dropped_remissions() > 0) {
    report.notes.push_back(std::to_string(parser.dropped_remissions()) +
                           " ROBOTLASER1 lines had a remission count different from the reading count; their "
                           "remissions were dropped");
  }
  auto& records = parser.records();
  if (records.empty()) {
    report.AddError(name + ": " + (lines == 0 ? std::string("empty file") : "no FLASER, ROBOTLASER1 or ODOM line") +
                    ": nothing to import (is this a CARMEN log?)");
    return report;
  }
  WriteRecords(records, options, sink, report);
  return report;
}

ImportReport ImportCarmenFile(const std::string& path, Sink& sink, const CarmenOptions& options) {
  internal::ZlibInputFile file(path);
  if (!file.is_open()) {
    options.Validate();
    ImportReport report;
    report.input = path;
    report.AddError(path + ": " + file.error());
    return report;
  }
  CarmenOptions with_size = options;
  if (with_size.total_bytes == 0) with_size.total_bytes = file.content_bytes_hint();
  ImportReport report = ImportCarmen(file, path, sink, with_size);
  if (!file.error().empty()) {
    report.AddError(path + ": " + file.error() + " after " + std::to_string(file.compressed_offset()) + " of " +
                    std::to_string(file.file_bytes()) + " bytes; the lines before were imported");
  }
  if (file.compressed()) report.notes.push_back("input is gzip-compressed");
  return report;
}

}  // namespace snapnav::importers
