// MRPT rawlogs -> LASER_SCAN and ODOMETRY, read with MRPT's own deserialization.
//
// Both rawlog formats are understood, plain or gzip-compressed:
//  - action / sensory-frame pairs: CActionCollection (odometry increments,
//    CActionRobotMovement2D) alternating with CSensoryFrame (observations);
//  - observations only: CObservationOdometry (cumulative) and CObservation2DRangeScan.
// A serialized CRawlog object is understood too. Other classes are skipped and counted.
//
// The bytes are read through zlib by a small mrpt::io::CStream (not CFileGZInputStream):
// it reports truncated or corrupt gzip data (CFileGZInputStream reads a gzip file cut at an
// object boundary, or missing its trailer, as complete) and gives exact byte offsets.
//
// MRPT's deserializers trust the counts they read (CObservation2DRangeScan resizes three
// vectors to the beam count before reading them, and its aligned allocator does not check
// for failure), so corrupt data can exhaust memory or crash. The reading therefore runs in
// a child process with a limited address space that sends the converted messages back
// through a pipe; if it dies, the import ends with an error at the offset being read.

#include <mrpt/core/Clock.h>
#include <mrpt/io/CStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "import_util.hpp"
#include "importers.hpp"
#include "mrpt_time.hpp"
#include "snapnav/glue/codec.hpp"
#include "snapnav/laser_scan_t.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/odometry_t.hpp"

namespace snapnav::importers {
namespace {

constexpr char kDefaultLaserName[] = "laser";
constexpr char kOdometrySensor[] = "mrpt_odometry";

// A file read through zlib (gzip or plain), as an MRPT stream; counts decompressed bytes.
class ZlibCStream : public mrpt::io::CStream {
 public:
  explicit ZlibCStream(const std::string& path) : path_(path), file_(path) {}

  bool is_open() const { return file_.is_open(); }
  bool compressed() const { return file_.compressed(); }
  uint64_t content_hint() const { return static_cast<uint64_t>(file_.content_bytes_hint()); }
  // Why the file cannot be opened, or why its data ended early (truncated or corrupt gzip).
  const std::string& error() const { return file_.error(); }

  size_t Read(void* buffer, size_t count) override {
    const std::streamsize n = file_.rdbuf()->sgetn(static_cast<char*>(buffer), static_cast<std::streamsize>(count));
    position_ += static_cast<uint64_t>(n);
    return static_cast<size_t>(n);
  }
  size_t Write(const void*, size_t) override { throw std::runtime_error("ZlibCStream is read-only"); }
  uint64_t Seek(int64_t, TSeekOrigin) override { throw std::runtime_error("ZlibCStream cannot seek"); }
  uint64_t getTotalBytesCount() const override { return content_hint(); }
  uint64_t getPosition() const override { return position_; }
  std::string getStreamDescription() const override { return "file '" + path_ + "'"; }

 private:
  std::string path_;
  internal::ZlibInputFile file_;
  uint64_t position_ = 0;
};

// MRPT exception texts carry nested "Message:" lines and call stacks; keep the innermost
// message and the chain of classes being read.
std::string MrptReason(const std::string& what) {
  std::vector<std::string> messages, classes;
  std::istringstream in(what);
  std::string line;
  const std::string typed = "Exception while parsing typed object '";
  while (std::getline(in, line)) {
    const auto pos = line.find("Message:");
    if (pos == std::string::npos) continue;
    std::string m = line.substr(pos + 8);
    m.erase(0, m.find_first_not_of(" \t"));
    if (m.rfind(typed, 0) == 0) {
      const auto end = m.find('\'', typed.size());
      const std::string name = m.substr(typed.size(), end == std::string::npos ? 0 : end - typed.size());
      if (!name.empty() && name.find(' ') == std::string::npos) classes.push_back(name);
      continue;
    }
    messages.push_back(m);
  }
  std::string reason = messages.empty() ? what.substr(0, what.find('\n')) : messages.back();
  // MRPT's hint does not apply: gzip input is decompressed already.
  if (const auto hint = reason.find(" (Perhaps it's a gz-compressed stream?"); hint != std::string::npos) {
    reason.erase(hint);
  }
  if (!classes.empty()) {
    reason += " (while reading ";
    for (size_t i = 0; i < classes.size(); ++i) reason += (i ? " > " : "") + classes[i];
    reason += ")";
  }
  return reason;
}

nav::Pose2 ToPose2(const mrpt::poses::CPose2D& p) { return {p.x(), p.y(), p.phi()}; }

class Converter {
 public:
  Converter(const RawlogOptions& options, internal::Emitter& emitter, ImportReport& report)
      : options_(options), emitter_(emitter), report_(report) {}

  void Action(const mrpt::obs::CActionCollection& actions) {
    ++entries_;
    Flush();  // two actions in a row: the first one's time cannot come from a sensory frame
    const auto movement = actions.getBestMovementEstimation();
    for (const auto& a : actions) {
      if (a.get() != movement.get()) ++report_.skipped[a->GetRuntimeClass()->className];
    }
    if (!movement) return;
    PendingAction p;
    p.delta = ToPose2(movement->poseChange->getMeanVal());
    p.utime = MrptTimeToUtime(movement->timestamp);
    p.has_velocity = movement->hasVelocities;
    p.v_mps = movement->velocityLocal.vx;
    p.w_radps = movement->velocityLocal.omega;
    pending_ = p;
    saw_increments_ = true;
  }

  void SensoryFrame(const mrpt::obs::CSensoryFrame& frame) {
    ++entries_;
    if (pending_) {
      // The increment ends where this frame was taken: without its own time, it gets the frame's.
      std::optional<int64_t> frame_utime;
      for (const auto& o : frame) {
        if (const auto u = MrptTimeToUtime(o->timestamp); u && (!frame_utime || *u < *frame_utime)) frame_utime = u;
      }
      if (!pending_->utime) pending_->utime = frame_utime;
      Flush();
    }
    for (const auto& o : frame) ObservationInside(o);
  }

  void Observation(const mrpt::obs::CObservation::Ptr& obs) {
    ++entries_;
    Flush();
    ObservationInside(obs);
  }

  void Finish() {
    Flush();
    if (synthesized_ > 0) {
      report_.synthesized_utimes += synthesized_;
      char rate[32];
      std::snprintf(rate, sizeof rate, "%g", options_.rate_hz);
      report_.notes.push_back(std::to_string(synthesized_) + (synthesized_ == 1 ? " message has" : " messages have") +
                              " no timestamp in the rawlog; each got the previous message's time + 1/" + rate + " s");
    }
    if (saw_increments_ && saw_absolute_) {
      report_.notes.push_back(
          "the rawlog has both odometry increments (CActionRobotMovement2D) and cumulative odometry "
          "(CObservationOdometry); both were written to the odometry channel");
    }
  }

  int64_t entries() const { return entries_; }
  int64_t scans() const { return scans_; }

 private:
  struct PendingAction {
    nav::Pose2 delta;
    std::optional<int64_t> utime;
    bool has_velocity = false;
    double v_mps = 0;
    double w_radps = 0;
  };

  int64_t Utime(std::optional<int64_t> utime) {
    if (!utime) {
      ++synthesized_;
      const int64_t period = std::llround(1e6 / options_.rate_hz);
      utime = any_time_ ? last_utime_ + period : kSynthesizedStartUtime;
    }
    any_time_ = true;
    last_utime_ = *utime;
    return *utime;
  }

  void Flush() {
    if (!pending_) return;
    const PendingAction p = *pending_;
    pending_.reset();
    const int64_t utime = Utime(p.utime);
    increment_pose_ = increment_pose_.Compose(p.delta);
    WriteOdometry(increment_pose_, p.delta, utime, p.has_velocity, p.v_mps, p.w_radps);
  }

  void ObservationInside(const mrpt::obs::CObservation::Ptr& obs) {
    if (!obs) {
      ++report_.skipped["empty observation"];
      return;
    }
    if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(obs.get())) {
      WriteScan(*scan);
    } else if (const auto* odo = dynamic_cast<const mrpt::obs::CObservationOdometry*>(obs.get())) {
      saw_absolute_ = true;
      const nav::Pose2 pose = ToPose2(odo->odometry);
      const nav::Pose2 delta = have_absolute_ ? absolute_pose_.Between(pose) : nav::Pose2{};
      have_absolute_ = true;
      absolute_pose_ = pose;
      WriteOdometry(pose, delta, Utime(MrptTimeToUtime(odo->timestamp)), odo->hasVelocities, odo->velocityLocal.vx,
                    odo->velocityLocal.omega);
    } else {
      ++report_.skipped[obs->GetRuntimeClass()->className];
    }
  }

  void WriteScan(const mrpt::obs::CObservation2DRangeScan& in) {
    const size_t n = in.getScanSize();
    if (n == 0) {
      ++report_.skipped["CObservation2DRangeScan with no beams"];
      return;
    }
    laser_scan_t scan{};
    scan.utime = Utime(MrptTimeToUtime(in.timestamp));
    scan.sensor_name = in.sensorLabel.empty() ? kDefaultLaserName : in.sensorLabel;
    scan.sensor_x_m = static_cast<float>(in.sensorPose.x());
    scan.sensor_y_m = static_cast<float>(in.sensorPose.y());
    scan.sensor_theta_rad = static_cast<float>(in.sensorPose.yaw());
    // MRPT: beam i at -aperture/2 + i * aperture/(n-1), counter-clockwise if rightToLeft.
    // A clockwise scan is stored reversed, so the increment is always positive.
    scan.angle_min_rad = -in.aperture / 2;
    scan.angle_increment_rad = n > 1 ? in.aperture / static_cast<float>(n - 1) : 0.0f;
    scan.time_increment_s = 0;
    scan.range_min_m = 0;
    scan.range_max_m = in.maxRange;
    scan.nranges = static_cast<int32_t>(n);
    scan.ranges_m.resize(n);
    const bool intensity = in.hasIntensity();
    scan.nintensities = intensity ? static_cast<int32_t>(n) : 0;
    if (intensity) scan.intensities.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const size_t k = in.rightToLeft ? i : n - 1 - i;
      const float r = in.getScanRange(k);
      const bool valid = in.getScanRangeValidity(k) && std::isfinite(r) && r >= 0;
      scan.ranges_m[i] = valid ? r : in.maxRange;
      if (intensity) scan.intensities[i] = static_cast<float>(in.getScanIntensity(k));
    }
    emitter_.Emit(options_.channels.laser_scan, scan);
    ++scans_;
  }

  void WriteOdometry(const nav::Pose2& pose, const nav::Pose2& delta, int64_t utime, bool has_velocity, double v_mps,
                     double w_radps) {
    odometry_t odo{};
    odo.utime = utime;
    odo.sensor_name = kOdometrySensor;
    odo.x_m = pose.x_m;
    odo.y_m = pose.y_m;
    odo.theta_rad = pose.theta_rad;
    odo.delta_x_m = delta.x_m;
    odo.delta_y_m = delta.y_m;
    odo.delta_theta_rad = delta.theta_rad;
    const double dt = have_odometry_ ? static_cast<double>(utime - last_odometry_utime_) * 1e-6 : 0.0;
    odo.delta_t_s = dt;
    if (has_velocity) {
      odo.linear_velocity_mps = v_mps;
      odo.angular_velocity_radps = w_radps;
    } else {
      odo.linear_velocity_mps = dt > 0 ? delta.x_m / dt : 0.0;
      odo.angular_velocity_radps = dt > 0 ? delta.theta_rad / dt : 0.0;
    }
    emitter_.Emit(options_.channels.odometry, odo);
    have_odometry_ = true;
    last_odometry_utime_ = utime;
  }

  const RawlogOptions& options_;
  internal::Emitter& emitter_;
  ImportReport& report_;
  std::optional<PendingAction> pending_;
  nav::Pose2 increment_pose_;  // integral of the increments
  nav::Pose2 absolute_pose_;   // last CObservationOdometry
  bool have_absolute_ = false;
  bool saw_increments_ = false;
  bool saw_absolute_ = false;
  bool have_odometry_ = false;
  int64_t last_odometry_utime_ = 0;
  bool any_time_ = false;
  int64_t last_utime_ = 0;
  int64_t synthesized_ = 0;
  int64_t entries_ = 0;
  int64_t scans_ = 0;
};

// What the reader reports, in order. In a child process these become frames on a pipe.
class ReaderEvents {
 public:
  virtual ~ReaderEvents() = default;
  // About to read the object at `offset` (decompressed bytes); `objects` were read before it.
  virtual void ObjectStart(uint64_t offset, int64_t objects) = 0;
  virtual void Message(const std::string& channel, int64_t utime, const std::string& payload) = 0;
  virtual void Progress(int64_t done, int64_t total) = 0;
  // The end: what was skipped, notes, errors and the synthesized-time count.
  virtual void Done(const ImportReport& report) = 0;
};

class EventsSink : public Sink {
 public:
  explicit EventsSink(ReaderEvents& events) : events_(events) {}
  void Write(const std::string& channel, int64_t utime, const std::string& payload) override {
    events_.Message(channel, utime, payload);
  }

 private:
  ReaderEvents& events_;
};

// Reads the rawlog with MRPT and converts it; everything goes to `events`.
void RunReader(const std::string& path, const RawlogOptions& options, ReaderEvents& events) {
  ImportReport report;  // channel figures are kept by the receiving side
  report.input = path;
  ZlibCStream stream(path);
  if (!stream.is_open()) {
    report.AddError(path + ": " + stream.error());
    events.Done(report);
    return;
  }
  const std::string where = stream.compressed() ? " of the decompressed data" : "";
  if (stream.compressed()) report.notes.push_back("input is gzip-compressed; byte offsets count decompressed bytes");
  auto archive = mrpt::serialization::archiveFrom(stream);
  EventsSink sink(events);
  internal::Emitter emitter(sink, report);
  Converter converter(options, emitter, report);
  int64_t objects = 0;
  for (;;) {
    const uint64_t start = stream.getPosition();
    events.ObjectStart(start, objects);
    mrpt::serialization::CSerializable::Ptr object;
    std::string failure;
    bool clean_end = false;
    bool eof = false;
    try {
      object = archive.ReadObject();
    } catch (const mrpt::serialization::CExceptionEOF& e) {
      eof = true;
      if (stream.getPosition() == start) {
        clean_end = true;
      } else {
        failure = MrptReason(e.what());
      }
    } catch (const std::exception& e) {
      failure = MrptReason(e.what());
    }
    if (clean_end) {
      if (!stream.error().empty()) {
        report.AddError(path + ": byte offset " + std::to_string(start) + where + ": " + stream.error() + "; the " +
                        std::to_string(objects) + " objects before it were imported");
      }
      break;
    }
    if (!failure.empty()) {
      const bool ended = eof || !stream.error().empty() || failure.find("EOF") != std::string::npos;
      std::string detail = failure;
      if (!stream.error().empty()) detail += "; " + stream.error();
      if (failure.find("which is not registered") != std::string::npos) {
        // MRPT stores no object sizes, so an object of an unknown class cannot be skipped.
        report.AddError(path + ": byte offset " + std::to_string(start) + where +
                        ": an object of a class unknown to the MRPT libraries log-import links (mrpt-obs) cannot "
                        "be skipped: " +
                        failure + "; the " + std::to_string(objects) + " objects before it were imported");
      } else if (objects == 0) {
        report.AddError(path + ": not an MRPT rawlog" +
                        (ended ? std::string(" (or truncated inside its first object)") : std::string()) +
                        ": no MRPT object can be read at byte offset 0: " + detail);
      } else {
        report.AddError(
            path + ": byte offset " + std::to_string(start) + where + ": " +
            (ended ? "truncated: the data ends inside the object that starts there: " : "corrupt object: ") + detail +
            "; the " + std::to_string(objects) + " objects before it were imported");
      }
      break;
    }
    ++objects;
    if (objects % options.progress_every_objects == 0) {
      events.Progress(static_cast<int64_t>(stream.getPosition()), static_cast<int64_t>(stream.content_hint()));
    }
    if (!object) {
      ++report.skipped["null object"];
    } else if (const auto actions = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(object)) {
      converter.Action(*actions);
    } else if (const auto frame = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(object)) {
      converter.SensoryFrame(*frame);
    } else if (const auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(object)) {
      converter.Observation(obs);
    } else if (const auto rawlog = std::dynamic_pointer_cast<mrpt::obs::CRawlog>(object)) {
      for (size_t i = 0; i < rawlog->size(); ++i) {
        switch (rawlog->getType(i)) {
          case mrpt::obs::CRawlog::etActionCollection:
            converter.Action(*rawlog->getAsAction(i));
            break;
          case mrpt::obs::CRawlog::etSensoryFrame:
            converter.SensoryFrame(*rawlog->getAsObservations(i));
            break;
          case mrpt::obs::CRawlog::etObservation:
            converter.Observation(rawlog->getAsObservation(i));
            break;
          default:
            ++report.skipped["CRawlog entry of another type"];
        }
      }
    } else {
      ++report.skipped[object->GetRuntimeClass()->className];
    }
  }
  converter.Finish();
  if (converter.entries() == 0 && report.error_count == 0) {
    report.AddError(path + ": " +
                    (objects == 0 ? std::string("empty file")
                                  : std::to_string(objects) + " MRPT objects but no rawlog entry (action, sensory "
                                                              "frame or observation)") +
                    ": not an MRPT rawlog");
  }
  report.notes.push_back(std::to_string(objects) + " MRPT objects read, " + std::to_string(converter.entries()) +
                         " rawlog entries");
  events.Done(report);
}

// The receiving side: writes the messages into the sink (keeping the channel figures) and
// merges the reader's report.
class Collector : public ReaderEvents {
 public:
  Collector(Sink& sink, ImportReport& report, const RawlogOptions& options)
      : emitter_(sink, report), report_(report), options_(options) {}

  void ObjectStart(uint64_t offset, int64_t objects) override {
    offset_ = offset;
    objects_ = objects;
  }
  void Message(const std::string& channel, int64_t utime, const std::string& payload) override {
    const auto fingerprint = glue::PayloadFingerprint(payload.data(), payload.size());
    std::string error;
    if (fingerprint && *fingerprint == static_cast<uint64_t>(laser_scan_t::getHash())) {
      if (auto msg = glue::Decode<laser_scan_t>(payload.data(), payload.size(), &error)) {
        emitter_.Emit(channel, *msg);
        return;
      }
    } else if (fingerprint && *fingerprint == static_cast<uint64_t>(odometry_t::getHash())) {
      if (auto msg = glue::Decode<odometry_t>(payload.data(), payload.size(), &error)) {
        emitter_.Emit(channel, *msg);
        return;
      }
    }
    throw std::logic_error("rawlog reader sent an undecodable message on " + channel + " at " + std::to_string(utime) +
                           ": " + error);
  }
  void Progress(int64_t done, int64_t total) override {
    if (options_.progress) options_.progress({done, total, "bytes"});
  }
  void Done(const ImportReport& reader) override {
    for (const auto& [kind, count] : reader.skipped) report_.skipped[kind] += count;
    for (const auto& note : reader.notes) report_.notes.push_back(note);
    for (const auto& error : reader.errors) report_.AddError(error);
    report_.error_count += reader.error_count - static_cast<int64_t>(reader.errors.size());
    report_.synthesized_utimes += reader.synthesized_utimes;
    done_ = true;
  }

  bool done() const { return done_; }
  uint64_t offset() const { return offset_; }
  int64_t objects() const { return objects_; }

 private:
  internal::Emitter emitter_;
  ImportReport& report_;
  const RawlogOptions& options_;
  bool done_ = false;
  uint64_t offset_ = 0;
  int64_t objects_ = 0;
};

// ---------------------------------------------------------------- the pipe
// Frames: a tag byte, then fixed-size integers (host byte order: both ends are this
// program) and strings as a 32-bit length and the bytes.
constexpr uint32_t kMaxFrameString = uint32_t{1} << 30;

class PipeWriter : public ReaderEvents {
 public:
  explicit PipeWriter(int fd) : fd_(fd) {}

  void ObjectStart(uint64_t offset, int64_t objects) override {
    Put('S');
    Put(offset);
    Put(objects);
    Flush();  // the receiver must know where the reader is before it may die
  }
  void Message(const std::string& channel, int64_t utime, const std::string& payload) override {
    Put('M');
    Put(channel);
    Put(utime);
    Put(payload);
  }
  void Progress(int64_t done, int64_t total) override {
    Put('P');
    Put(done);
    Put(total);
  }
  void Done(const ImportReport& report) override {
    Put('D');
    Put(report.synthesized_utimes);
    Put(report.error_count);
    Put(static_cast<uint32_t>(report.skipped.size()));
    for (const auto& [kind, count] : report.skipped) {
      Put(kind);
      Put(count);
    }
    Put(static_cast<uint32_t>(report.notes.size()));
    for (const auto& note : report.notes) Put(note);
    Put(static_cast<uint32_t>(report.errors.size()));
    for (const auto& error : report.errors) Put(error);
    Flush();
  }

  bool Flush() {
    size_t done = 0;
    while (done < buffer_.size()) {
      const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    buffer_.clear();
    return true;
  }

 private:
  void Put(char tag) { buffer_.push_back(tag); }
  template <class T>
  void Put(T value) {
    static_assert(std::is_integral_v<T>);
    buffer_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void Put(const std::string& text) {
    Put(static_cast<uint32_t>(text.size()));
    buffer_ += text;
  }

  int fd_;
  std::string buffer_;
};

class PipeReader {
 public:
  explicit PipeReader(int fd) : fd_(fd) {}

  // Delivers every complete frame to `events`; returns at the end of the pipe.
  void Run(ReaderEvents& events) {
    char tag = 0;
    while (Get(&tag)) {
      if (tag == 'S') {
        uint64_t offset = 0;
        int64_t objects = 0;
        if (!Get(&offset) || !Get(&objects)) return;
        events.ObjectStart(offset, objects);
      } else if (tag == 'M') {
        std::string channel, payload;
        int64_t utime = 0;
        if (!Get(&channel) || !Get(&utime) || !Get(&payload)) return;
        events.Message(channel, utime, payload);
      } else if (tag == 'P') {
        int64_t done = 0, total = 0;
        if (!Get(&done) || !Get(&total)) return;
        events.Progress(done, total);
      } else if (tag == 'D') {
        ImportReport report;
        uint32_t n = 0;
        if (!Get(&report.synthesized_utimes) || !Get(&report.error_count) || !Get(&n)) return;
        for (uint32_t i = 0; i < n; ++i) {
          std::string kind;
          int64_t count = 0;
          if (!Get(&kind) || !Get(&count)) return;
          report.skipped[kind] = count;
        }
        if (!Get(&n)) return;
        for (uint32_t i = 0; i < n; ++i) {
          std::string note;
          if (!Get(&note)) return;
          report.notes.push_back(std::move(note));
        }
        if (!Get(&n)) return;
        for (uint32_t i = 0; i < n; ++i) {
          std::string error;
          if (!Get(&error)) return;
          report.errors.push_back(std::move(error));
        }
        events.Done(report);
      } else {
        return;  // not a frame: the writer broke down
      }
    }
  }

 private:
  bool Fill(size_t need) {
    while (end_ - begin_ < need) {
      if (begin_ > 0) {
        buffer_.erase(0, begin_);
        end_ -= begin_;
        begin_ = 0;
      }
      buffer_.resize(std::max(buffer_.size(), end_ + std::max<size_t>(need, 1 << 16)));
      const ssize_t n = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      end_ += static_cast<size_t>(n);
    }
    return true;
  }
  bool Get(char* tag) {
    if (!Fill(1)) return false;
    *tag = buffer_[begin_++];
    return true;
  }
  template <class T>
  bool Get(T* value) {
    static_assert(std::is_integral_v<T>);
    if (!Fill(sizeof(T))) return false;
    std::memcpy(value, buffer_.data() + begin_, sizeof(T));
    begin_ += sizeof(T);
    return true;
  }
  bool Get(std::string* text) {
    uint32_t size = 0;
    if (!Get(&size) || size > kMaxFrameString || !Fill(size)) return false;
    text->assign(buffer_.data() + begin_, size);
    begin_ += size;
    return true;
  }

  int fd_;
  std::string buffer_;
  size_t begin_ = 0;
  size_t end_ = 0;
};

// Lets this process's address space grow by at most `extra` bytes from now on.
void LimitAddressSpace(size_t extra) {
  size_t pages = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    unsigned long total = 0;
    if (std::fscanf(f, "%lu", &total) == 1) pages = total;
    std::fclose(f);
  }
  const size_t current = pages * static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) != 0) return;
  const rlim_t wanted = static_cast<rlim_t>(current + extra);
  if (limit.rlim_max == RLIM_INFINITY || wanted < limit.rlim_max) limit.rlim_cur = wanted;
  ::setrlimit(RLIMIT_AS, &limit);
}

std::string DescribeExit(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::strsignal(sig);
    return "was killed by signal " + std::to_string(sig) + " (" + (name ? name : "?") + ")";
  }
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "stopped";
}

bool IsGzipFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  return in.read(reinterpret_cast<char*>(magic), 2) && magic[0] == 0x1f && magic[1] == 0x8b;
}

}  // namespace

void RawlogOptions::Validate() const {
  if (!(rate_hz > 0 && rate_hz <= 1e6)) throw std::invalid_argument("synthesized rate must be in (0, 1e6] Hz");
  if (reader_memory_limit_bytes < (size_t{64} << 20)) {
    throw std::invalid_argument("rawlog reader memory limit must be at least 64 MiB");
  }
  if (progress_every_objects < 1) throw std::invalid_argument("progress_every_objects must be positive");
}

ImportReport ImportRawlog(const std::string& path, Sink& sink, const RawlogOptions& options) {
  options.Validate();
  ImportReport report;
  report.input = path;
  Collector collector(sink, report, options);
  if (!options.isolate_reader) {
    RunReader(path, options, collector);
    return report;
  }
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(std::string("cannot start the rawlog reader process: ") + std::strerror(err));
  }
  if (pid == 0) {  // the reader: never returns
    ::close(fds[0]);
    int code = 0;
    try {
      LimitAddressSpace(options.reader_memory_limit_bytes);
      PipeWriter writer(fds[1]);
      RunReader(path, options, writer);
      if (!writer.Flush()) code = 4;
    } catch (...) {
      code = 3;
    }
    ::_exit(code);
  }
  ::close(fds[1]);
  std::string receive_error;
  try {
    PipeReader(fds[0]).Run(collector);
  } catch (const std::exception& e) {
    receive_error = e.what();
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!receive_error.empty()) throw std::runtime_error(receive_error);
  if (!collector.done()) {
    const std::string where = IsGzipFile(path) ? " of the decompressed data" : "";
    report.AddError(path + ": byte offset " + std::to_string(collector.offset()) + where +
                    ": corrupt object: the MRPT reader process " + DescribeExit(status) +
                    " while reading the object that starts there (corrupt data, or more memory than its " +
                    std::to_string(options.reader_memory_limit_bytes) + "-byte limit); the " +
                    std::to_string(collector.objects()) + " objects before it were imported");
  }
  return report;
}

}  // namespace snapnav::importers
