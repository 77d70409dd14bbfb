// Fuzzing of every process node on memq:// (seeded, under ctest). On every subscribed channel
// each node gets messages that decode but carry NaN, infinities, absurd magnitudes, absurd
// times, wrong sizes and counts, and random byte mutations of a valid message. For every one:
// no crash; nothing the node publishes holds a NaN or an infinity; a non-finite value in a field
// the node uses is counted (the bus's per-channel rejected / handler-error counts, with the
// reason); and after all of them a valid message is still processed. Nodes whose first odometry
// message fixes the start pose get every mutation of that first message on a fresh node too.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "../placecells/test_lab.hpp"
#include "dead_reckoning_node.hpp"
#include "fused_slam_node.hpp"
#include "fuzz_samples.hpp"
#include "homing_node.hpp"
#include "landmarks_node.hpp"
#include "laser_slam_node.hpp"
#include "navigator_node.hpp"
#include "placecells_node.hpp"
#include "ratslam_node.hpp"
#include "snapnav/glue/codec.hpp"

namespace snapnav::fuzz {
namespace {

namespace fs = std::filesystem;
using namespace processes;

constexpr int64_t kStart = 1700000000000000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------- mutations of one message
template <class T>
struct Mutation {
  std::string name;   // "odometry_t.delta_x_m = NaN"
  std::string field;  // "delta_x_m"
  bool non_finite = false;
  bool keeps_time = false;  // sets utime itself
  std::function<void(T&)> apply;
};

template <class T, class Ref>
void Real(std::vector<Mutation<T>>* out, const std::string& field, Ref ref) {
  using V = std::remove_reference_t<decltype(ref(std::declval<T&>()))>;
  const double huge = std::is_same_v<V, float> ? 3e38 : 1e300;
  const std::vector<std::tuple<const char*, double, bool>> values = {
      {"NaN", kNaN, true}, {"+Inf", kInf, true}, {"-Inf", -kInf, true}, {"huge", huge, false}, {"-huge", -huge, false}};
  for (const auto& [label, v, nf] : values) {
    out->push_back({field + " = " + label, field, nf, false, [ref, v = v](T& m) { ref(m) = static_cast<V>(v); }});
  }
}

template <class T, class Ref>
void Int(std::vector<Mutation<T>>* out, const std::string& field, Ref ref) {
  using V = std::remove_reference_t<decltype(ref(std::declval<T&>()))>;
  for (const int64_t v : {int64_t{-1}, int64_t{0}, int64_t{std::numeric_limits<V>::max()},
                          int64_t{std::numeric_limits<V>::min()}}) {
    out->push_back({field + " = " + std::to_string(v), field, false, false, [ref, v](T& m) { ref(m) = static_cast<V>(v); }});
  }
}

template <class T>
void Times(std::vector<Mutation<T>>* out) {
  for (const int64_t v : {int64_t{-1}, int64_t{0}, std::numeric_limits<int64_t>::max(),
                          std::numeric_limits<int64_t>::min(), kStart - 3600000000, kStart * 10 /* year 2508 */}) {
    out->push_back({"utime = " + std::to_string(v), "utime", false, true, [v](T& m) { m.utime = v; }});
  }
}

#define REAL(T, f) Real<T>(&v, #f, [](T& m) -> auto& { return m.f; })
#define INT(T, f) Int<T>(&v, #f, [](T& m) -> auto& { return m.f; })

std::vector<Mutation<odometry_t>> OdometryMutations() {
  std::vector<Mutation<odometry_t>> v;
  Times(&v);
  REAL(odometry_t, x_m);
  REAL(odometry_t, y_m);
  REAL(odometry_t, theta_rad);
  REAL(odometry_t, delta_x_m);
  REAL(odometry_t, delta_y_m);
  REAL(odometry_t, delta_theta_rad);
  REAL(odometry_t, delta_t_s);
  REAL(odometry_t, linear_velocity_mps);
  REAL(odometry_t, angular_velocity_radps);
  return v;
}

std::vector<Mutation<laser_scan_t>> ScanMutations() {
  std::vector<Mutation<laser_scan_t>> v;
  Times(&v);
  REAL(laser_scan_t, sensor_x_m);
  REAL(laser_scan_t, sensor_y_m);
  REAL(laser_scan_t, sensor_theta_rad);
  REAL(laser_scan_t, angle_min_rad);
  REAL(laser_scan_t, angle_increment_rad);
  REAL(laser_scan_t, time_increment_s);
  REAL(laser_scan_t, range_min_m);
  REAL(laser_scan_t, range_max_m);
  REAL(laser_scan_t, ranges_m[0]);
  for (const double r : {kNaN, kInf, -kInf, -1.0, 1e30}) {
    v.push_back({"every range = " + std::to_string(r), "ranges_m", !std::isfinite(r), false,
                 [r](laser_scan_t& m) { std::fill(m.ranges_m.begin(), m.ranges_m.end(), static_cast<float>(r)); }});
  }
  v.push_back({"no beams", "nranges", false, false, [](laser_scan_t& m) {
                 m.nranges = 0;
                 m.ranges_m.clear();
               }});
  v.push_back({"200000 beams", "nranges", false, false, [](laser_scan_t& m) {
                 m.nranges = 200000;
                 m.ranges_m.assign(200000, 1.0f);
               }});
  v.push_back({"intensities of another count, NaN", "intensities", false, false, [](laser_scan_t& m) {
                 m.nintensities = 3;
                 m.intensities = {static_cast<float>(kNaN), 1, 2};
               }});
  return v;
}

std::vector<Mutation<pose_t>> PoseMutations() {
  std::vector<Mutation<pose_t>> v;
  Times(&v);
  REAL(pose_t, x_m);
  REAL(pose_t, y_m);
  REAL(pose_t, theta_rad);
  for (int i : {0, 1, 4, 8}) {
    Real<pose_t>(&v, "covariance[" + std::to_string(i) + "]", [i](pose_t& m) -> auto& { return m.covariance[i]; });
  }
  v.push_back({"negative variances", "covariance", false, false, [](pose_t& m) {
                 m.covariance[0] = m.covariance[4] = m.covariance[8] = -1;
               }});
  return v;
}

std::vector<Mutation<pose_correction_t>> PoseCorrectionMutations() {
  std::vector<Mutation<pose_correction_t>> v;
  Times(&v);
  Real<pose_correction_t>(&v, "x_m", [](pose_correction_t& m) -> auto& { return m.x_m[1]; });
  Real<pose_correction_t>(&v, "y_m", [](pose_correction_t& m) -> auto& { return m.y_m[0]; });
  Real<pose_correction_t>(&v, "theta_rad", [](pose_correction_t& m) -> auto& { return m.theta_rad[1]; });
  v.push_back({"ranges out of order", "from_utime", true, false, [](pose_correction_t& m) {
                 std::swap(m.from_utime[0], m.from_utime[1]);
               }});
  v.push_back({"no ranges", "ranges", false, false, [](pose_correction_t& m) {
                 m.ranges = 0;
                 m.from_utime.clear();
                 m.x_m.clear();
                 m.y_m.clear();
                 m.theta_rad.clear();
               }});
  return v;
}

std::vector<Mutation<homing_vector_t>> HomingVectorMutations() {
  std::vector<Mutation<homing_vector_t>> v;
  Times(&v);
  INT(homing_vector_t, method);
  REAL(homing_vector_t, direction_rad);
  REAL(homing_vector_t, magnitude);
  REAL(homing_vector_t, compass_rotation_rad);
  INT(homing_vector_t, nlandmarks_used);
  return v;
}

std::vector<Mutation<waypoint_route_t>> RouteMutations() {
  std::vector<Mutation<waypoint_route_t>> v;
  Times(&v);
  REAL(waypoint_route_t, tolerance_m);
  REAL(waypoint_route_t, x_m[0]);
  REAL(waypoint_route_t, y_m[1]);
  v.push_back({"no waypoints", "nwaypoints", false, false, [](waypoint_route_t& m) {
                 m.nwaypoints = 0;
                 m.x_m.clear();
                 m.y_m.clear();
               }});
  v.push_back({"100000 waypoints", "nwaypoints", false, false, [](waypoint_route_t& m) {
                 m.nwaypoints = 100000;
                 m.x_m.assign(100000, 2.0);
                 m.y_m.assign(100000, 2.0);
               }});
  v.push_back({"negative tolerance", "tolerance_m", false, false, [](waypoint_route_t& m) { m.tolerance_m = -1; }});
  return v;
}

std::vector<Mutation<landmark_set_t>> LandmarkSetMutations() {
  std::vector<Mutation<landmark_set_t>> v;
  Times(&v);
  INT(landmark_set_t, method);
  INT(landmark_set_t, panorama_width_px);
  INT(landmark_set_t, panorama_height_px);
  REAL(landmark_set_t, bearings_rad[0]);
  REAL(landmark_set_t, rows_px[0]);
  REAL(landmark_set_t, strengths[0]);
  REAL(landmark_set_t, scales_px[0]);
  REAL(landmark_set_t, descriptors[0][0]);
  v.push_back({"descriptors of another length", "descriptor_length", false, false, [](landmark_set_t& m) {
                 m.descriptor_length = 5;
                 for (auto& d : m.descriptors) d.assign(5, 0.5f);
               }});
  v.push_back({"no landmarks", "nlandmarks", false, false, [](landmark_set_t& m) {
                 m.nlandmarks = 0;
                 m.bearings_rad.clear();
                 m.rows_px.clear();
                 m.strengths.clear();
                 m.scales_px.clear();
                 m.descriptors.clear();
               }});
  return v;
}

// A PNG whose header claims `w` x `h` pixels (a decompression bomb when large).
std::vector<uint8_t> PngClaiming(int w, int h) {
  std::vector<uint8_t> png;
  cv::imencode(".png", cv::Mat(8, 8, CV_8UC1, cv::Scalar(100)), png);
  auto put = [&](size_t at, uint32_t x) {
    for (int k = 0; k < 4; ++k) png[at + k] = static_cast<uint8_t>(x >> (24 - 8 * k));
  };
  put(16, static_cast<uint32_t>(w));
  put(20, static_cast<uint32_t>(h));
  uint32_t crc = 0xffffffffu;  // CRC-32 of the IHDR chunk type and data, so libpng accepts it
  for (size_t i = 12; i < 29; ++i) {
    crc ^= png[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  put(29, ~crc);
  return png;
}

std::vector<Mutation<omni_frame_t>> FrameMutations() {
  std::vector<Mutation<omni_frame_t>> v;
  Times(&v);
  INT(omni_frame_t, kind);
  INT(omni_frame_t, width);
  INT(omni_frame_t, height);
  INT(omni_frame_t, row_stride);
  INT(omni_frame_t, encoding);
  REAL(omni_frame_t, mirror_center_x_px);
  REAL(omni_frame_t, mirror_center_y_px);
  REAL(omni_frame_t, mirror_inner_radius_px);
  REAL(omni_frame_t, mirror_outer_radius_px);
  REAL(omni_frame_t, mirror_elevation_inner_rad);
  REAL(omni_frame_t, mirror_elevation_outer_rad);
  REAL(omni_frame_t, bearing_col0_rad);
  REAL(omni_frame_t, elevation_top_rad);
  REAL(omni_frame_t, elevation_bottom_rad);
  v.push_back({"width 2^30 (row stride overflows)", "width", false, false, [](omni_frame_t& m) {
                 m.width = 1 << 30;
               }});
  v.push_back({"width 715827883 (3 x width overflows int)", "width", false, false, [](omni_frame_t& m) {
                 m.width = 715827883;
                 m.row_stride = 16;
               }});
  v.push_back({"data shorter than its size", "data", false, false, [](omni_frame_t& m) {
                 m.data.resize(m.data.size() / 2);
                 m.data_size = static_cast<int32_t>(m.data.size());
               }});
  v.push_back({"JPEG of garbage", "data", false, false, [](omni_frame_t& m) {
                 m.encoding = omni_frame_t::JPEG;
                 m.row_stride = 0;
                 m.data.assign(1000, 0x5a);
                 m.data_size = 1000;
               }});
  v.push_back({"PNG claiming 30000x30000 pixels", "data", false, false, [](omni_frame_t& m) {
                 m.encoding = omni_frame_t::PNG;
                 m.row_stride = 0;
                 m.data = PngClaiming(30000, 30000);
                 m.data_size = static_cast<int32_t>(m.data.size());
               }});
  v.push_back({"30000x30000 frame, PNG saying so", "data", false, false, [](omni_frame_t& m) {
                 m.encoding = omni_frame_t::PNG;
                 m.row_stride = 0;
                 m.width = m.height = 30000;
                 m.data = PngClaiming(30000, 30000);
                 m.data_size = static_cast<int32_t>(m.data.size());
               }});
  v.push_back({"PNG of another size than the frame's", "data", false, false, [](omni_frame_t& m) {
                 m.encoding = omni_frame_t::PNG;
                 m.row_stride = 0;
                 std::vector<uint8_t> png;
                 cv::imencode(".png", cv::Mat(8, 8, CV_8UC1, cv::Scalar(100)), png);
                 m.data = png;
                 m.data_size = static_cast<int32_t>(m.data.size());
               }});
  return v;
}

// ---------------------------------------------------------------- the harness
class Harness {
 public:
  explicit Harness(std::set<std::string> outputs) : outputs_(std::move(outputs)) {
    bus.SubscribeRaw(".*", [this](const void* d, size_t n) {
      if (outputs_.count(bus.current().channel)) {
        published_.emplace_back(bus.current().channel, std::string(static_cast<const char*>(d), n));
      }
    });
  }
  template <class M>
  void Send(const std::string& channel, const M& m) {
    SendRaw(channel, glue::Encode(m));
  }
  void SendRaw(const std::string& channel, const std::string& bytes) {
    bus.PublishRaw(channel, bytes.data(), bytes.size());
    Drain();
  }
  // What was published since the last call.
  std::vector<std::pair<std::string, std::string>> Take() { return std::exchange(published_, {}); }
  int64_t Clock() { return clock_ += 1000000; }  // one second of message time per message

  glue::Bus bus{"memq://"};

 private:
  void Drain() {
    while (bus.HandleOnce(0)) {
    }
  }
  std::set<std::string> outputs_;
  std::vector<std::pair<std::string, std::string>> published_;
  int64_t clock_ = kStart + 10000000;
};

struct FuzzTally {
  int sent = 0, counted = 0, outputs = 0;
  std::map<std::string, int> accepted_non_finite;  // fields whose NaN/Inf was taken silently (unused fields)
};

// Sends every mutation of `good` on `channel`; `must_count` are the fields whose non-finite
// values the node uses (so must count). `before` runs before each mutated message (e.g. a pose
// a frame needs).
template <class M>
FuzzTally FuzzChannel(Harness& h, const std::string& node, const std::string& channel, const M& good,
                      const std::vector<Mutation<M>>& mutations, const std::set<std::string>& must_count,
                      const std::function<void(int64_t)>& before = nullptr) {
  FuzzTally t;
  for (const auto& mu : mutations) {
    M m = good;
    const int64_t now = h.Clock();
    m.utime = now;
    if (before) before(now);
    h.Take();
    mu.apply(m);
    const uint64_t errors = h.bus.total_errors();
    h.Send(channel, m);
    ++t.sent;
    const bool counted = h.bus.total_errors() > errors;
    t.counted += counted;
    for (const auto& [ch, payload] : h.Take()) {
      ++t.outputs;
      const std::string problem = OutputProblem(ch, payload);
      EXPECT_TRUE(problem.empty()) << node << ": " << channel << ": " << M::getTypeName() << "." << mu.name << " -> "
                                   << problem;
    }
    if (mu.non_finite && !counted) {
      if (must_count.count(mu.field)) {
        ADD_FAILURE() << node << ": " << channel << ": " << M::getTypeName() << "." << mu.name
                      << " was taken silently (not counted)";
      } else {
        ++t.accepted_non_finite[mu.field];
      }
    }
  }
  // Random byte mutations of the valid message: rejected or taken, never a crash or a NaN out.
  std::mt19937_64 rng(std::hash<std::string>()(node + channel));
  for (int trial = 0; trial < 150; ++trial) {
    M m = good;
    m.utime = h.Clock();
    if (before) before(m.utime);
    std::string bytes = glue::Encode(m);
    for (int e = 0; e < 3; ++e) {
      const size_t at = 16 + rng() % std::min<size_t>(bytes.size() - 16, 512);  // the header, not the pixels
      bytes[at] = static_cast<char>(bytes[at] ^ (1 << (rng() % 8)));
    }
    h.Take();
    h.SendRaw(channel, bytes);
    for (const auto& [ch, payload] : h.Take()) {
      const std::string problem = OutputProblem(ch, payload);
      EXPECT_TRUE(problem.empty()) << node << ": " << channel << ": byte mutation " << trial << " -> " << problem;
    }
  }
  std::cerr << node << " on " << channel << ": " << t.sent << " bad messages, " << t.counted << " counted, "
            << t.outputs << " outputs (all finite)";
  for (const auto& [field, n] : t.accepted_non_finite) std::cerr << "; " << field << " non-finite ignored (unused)";
  std::cerr << "\n";
  return t;
}

// After the fuzzing, a valid message still gives an output on `channel`.
void ExpectStillWorks(Harness& h, const std::string& node, const std::function<void(int64_t)>& send_valid,
                      const std::string& channel) {
  h.Take();
  send_valid(h.Clock());
  int got = 0;
  for (const auto& [ch, payload] : h.Take()) {
    if (ch != channel) continue;
    ++got;
    EXPECT_EQ(OutputProblem(ch, payload), "") << node;
  }
  EXPECT_GT(got, 0) << node << ": a valid message after the bad ones gave nothing on " << channel;
}

void PrintCounts(Harness& h, const std::string& node) {
  std::cerr << node << ": what the bus counted and why:\n";
  h.bus.ReportStats(std::cerr);
}

glue::IniFile Config(const std::string& file, std::initializer_list<std::array<const char*, 3>> sets) {
  glue::IniFile ini = glue::IniFile::Load(std::string(SNAPNAV_CONFIG_DIR) + "/" + file);
  for (const auto& s : sets) ini.Set(s[0], s[1], s[2], "test");
  return ini;
}

omni_frame_t ValidFrame(int64_t utime) {
  return processes::test::Indoor13::Get().RawFrame(nav::Pose2{3.5, 3.0, 0.2}, utime);
}

const std::set<std::string> kMirror = {"mirror_center_x_px",     "mirror_center_y_px",        "mirror_inner_radius_px",
                                       "mirror_outer_radius_px", "mirror_elevation_inner_rad", "mirror_elevation_outer_rad"};

odometry_t Odometry(int64_t utime) {
  odometry_t o = SampleOdometry();
  o.utime = utime;
  return o;
}

// The first odometry message fixes the start pose: every mutation of it on a fresh node (made by
// `make` on the harness's bus), then `valid` (messages that give an output on `channel`) must still
// work, and nothing published may be non-finite. A non-finite cumulative pose must be counted.
void FuzzFirstOdometry(const std::string& node, const std::set<std::string>& outputs,
                       const std::string& odometry_channel, const std::string& channel,
                       const std::function<std::shared_ptr<void>(glue::Bus&)>& make,
                       const std::function<void(Harness&, int64_t)>& valid) {
  int counted = 0;
  for (const auto& mu : OdometryMutations()) {
    Harness h(outputs);
    const auto held = make(h.bus);
    odometry_t m = Odometry(h.Clock());
    mu.apply(m);
    h.Send(odometry_channel, m);
    for (const auto& [ch, p] : h.Take()) EXPECT_EQ(OutputProblem(ch, p), "") << node << ": first odometry " << mu.name;
    const bool was_counted = h.bus.total_errors() > 0;
    counted += was_counted;
    if (mu.non_finite && (mu.field == "x_m" || mu.field == "y_m" || mu.field == "theta_rad")) {
      EXPECT_TRUE(was_counted) << node << ": first odometry " << mu.name << " taken silently";
    }
    valid(h, h.Clock());
    int got = 0;
    for (const auto& [ch, p] : h.Take()) {
      EXPECT_EQ(OutputProblem(ch, p), "") << node << ": after first odometry " << mu.name;
      got += ch == channel;
    }
    EXPECT_GT(got, 0) << node << ": nothing on " << channel << " after first odometry " << mu.name;
  }
  std::cerr << node << ": first odometry message: " << OdometryMutations().size() << " mutations, " << counted
            << " counted, valid messages afterwards processed\n";
}

// ---------------------------------------------------------------- the nodes
TEST(FuzzNodes, DeadReckoning) {
  const auto config = DeadReckoningConfig::FromIni(Config("dead_reckoning.ini", {}), "");
  // The first message fixes the start pose: fuzz it on a fresh node each time.
  for (const auto& mu : OdometryMutations()) {
    Harness h({config.pose_channel});
    DeadReckoningNode node(h.bus, config);
    odometry_t m = Odometry(h.Clock());
    mu.apply(m);
    h.Send(config.odometry_channel, m);
    for (const auto& [ch, p] : h.Take()) EXPECT_EQ(OutputProblem(ch, p), "") << "first odometry " << mu.name;
    if (mu.non_finite && (mu.field == "x_m" || mu.field == "y_m" || mu.field == "theta_rad")) {
      EXPECT_GT(h.bus.total_errors(), 0u) << "first odometry " << mu.name << " taken silently";
    }
    h.Send(config.odometry_channel, Odometry(h.Clock()));
    EXPECT_GT(node.published(), 0) << "after first odometry " << mu.name;
  }
  Harness h({config.pose_channel});
  DeadReckoningNode node(h.bus, config);
  h.Send(config.odometry_channel, Odometry(h.Clock()));
  FuzzChannel(h, "dead-reckoning", config.odometry_channel, SampleOdometry(), OdometryMutations(),
              {"delta_x_m", "delta_y_m", "delta_theta_rad"});
  ExpectStillWorks(h, "dead-reckoning", [&](int64_t t) { h.Send(config.odometry_channel, Odometry(t)); },
                   config.pose_channel);
  PrintCounts(h, "dead-reckoning");
}

TEST(FuzzNodes, LaserSlam) {
  const auto config = LaserSlamConfig::FromIni(Config("laser_slam.ini", {{"laser_slam", "map_every_n_scans", "1"}}), "");
  Harness h({config.pose_channel, config.map_channel});
  LaserSlamNode node(h.bus, config);
  auto scan = [](int64_t t) {
    laser_scan_t s = SampleLaserScan(181);
    s.utime = t;
    return s;
  };
  h.Send(config.odometry_channel, Odometry(h.Clock()));
  h.Send(config.scan_channel, scan(h.Clock()));
  FuzzChannel(h, "laser-slam", config.odometry_channel, SampleOdometry(), OdometryMutations(),
              {"delta_x_m", "delta_y_m", "delta_theta_rad"});
  FuzzChannel(h, "laser-slam", config.scan_channel, SampleLaserScan(181), ScanMutations(),
              {"sensor_x_m", "sensor_y_m", "sensor_theta_rad", "angle_min_rad", "angle_increment_rad", "range_min_m",
               "range_max_m"});
  ExpectStillWorks(h, "laser-slam", [&](int64_t t) { h.Send(config.scan_channel, scan(t)); }, config.pose_channel);
  PrintCounts(h, "laser-slam");
  node.Report(std::cerr);
}

TEST(FuzzNodes, LaserSlamFirstOdometry) {
  const auto config = LaserSlamConfig::FromIni(Config("laser_slam.ini", {{"laser_slam", "map_every_n_scans", "1"}}), "");
  FuzzFirstOdometry(
      "laser-slam", {config.pose_channel, config.map_channel}, config.odometry_channel, config.pose_channel,
      [&](glue::Bus& bus) { return std::make_shared<LaserSlamNode>(bus, config); },
      [&](Harness& h, int64_t t) {
        laser_scan_t s = SampleLaserScan(181);
        s.utime = t;
        h.Send(config.scan_channel, s);
        h.Send(config.odometry_channel, Odometry(t + 1000));
        s.utime = t + 2000;
        h.Send(config.scan_channel, s);
      });
}

TEST(FuzzNodes, Landmarks) {
  const auto config = LandmarksConfig::FromIni(Config("landmarks.ini", {}), "");
  Harness h({config.landmarks_channel});
  LandmarksNode node(h.bus, config);
  FuzzChannel(h, "landmarks", config.omni_channel, ValidFrame(0), FrameMutations(), kMirror);
  ExpectStillWorks(h, "landmarks", [&](int64_t t) { h.Send(config.omni_channel, ValidFrame(t)); },
                   config.landmarks_channel);
  PrintCounts(h, "landmarks");
  node.Report(std::cerr);
}

TEST(FuzzNodes, HomingOnFrames) {
  const auto config = HomingConfig::FromIni(Config("homing.ini", {{"homing", "home", "first"}}), "");
  Harness h({config.homing_vector_channel});
  HomingNode node(h.bus, config);
  h.Send(config.omni_channel, ValidFrame(h.Clock()));  // the home
  FuzzChannel(h, "homing", config.omni_channel, ValidFrame(0), FrameMutations(), kMirror);
  FuzzChannel(h, "homing", config.home_snapshot_channel, ValidFrame(0), FrameMutations(), kMirror);
  ExpectStillWorks(h, "homing", [&](int64_t t) { h.Send(config.omni_channel, ValidFrame(t)); },
                   config.homing_vector_channel);
  PrintCounts(h, "homing");
  node.Report(std::cerr);
}

TEST(FuzzNodes, HomingOnLandmarks) {
  // A real SURF set of the valid frame, from the landmarks node.
  landmark_set_t good;
  {
    const auto lconfig = LandmarksConfig::FromIni(Config("landmarks.ini", {}), "");
    Harness lh({lconfig.landmarks_channel});
    LandmarksNode lnode(lh.bus, lconfig);
    lh.Send(lconfig.omni_channel, ValidFrame(kStart));
    const auto out = lh.Take();
    ASSERT_EQ(out.size(), 1u);
    std::string error;
    good = glue::Decode<landmark_set_t>(out[0].second.data(), out[0].second.size(), &error).value();
    ASSERT_GT(good.nlandmarks, 10);
  }
  const auto config =
      HomingConfig::FromIni(Config("homing.ini", {{"homing", "home", "first"}, {"homing", "input", "landmarks"}}), "");
  Harness h({config.homing_vector_channel});
  HomingNode node(h.bus, config);
  h.Send(config.landmarks_channel, good);  // the home set
  const std::set<std::string> used = {"bearings_rad[0]", "rows_px[0]", "strengths[0]", "scales_px[0]",
                                      "descriptors[0][0]"};
  FuzzChannel(h, "homing (landmarks)", config.landmarks_channel, good, LandmarkSetMutations(), used);
  ExpectStillWorks(h, "homing (landmarks)", [&](int64_t t) {
    landmark_set_t s = good;
    s.utime = t;
    h.Send(config.landmarks_channel, s);
  }, config.homing_vector_channel);
  FuzzChannel(h, "homing (landmarks)", config.home_landmarks_channel, good, LandmarkSetMutations(), used);
  h.Send(config.home_landmarks_channel, good);
  ExpectStillWorks(h, "homing (landmarks)", [&](int64_t t) {
    landmark_set_t s = good;
    s.utime = t;
    h.Send(config.landmarks_channel, s);
  }, config.homing_vector_channel);
  PrintCounts(h, "homing (landmarks)");
  node.Report(std::cerr);
}

class FuzzPlaceCells : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snapnav_fuzz_placecells_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(FuzzPlaceCells, ExploreAndLocalize) {
  const std::string memory = (dir_ / "fuzz.placecells").string();
  const auto config = PlaceCellsConfig::FromIni(
      Config("placecells.ini", {{"placecells", "mode", "explore"}, {"placecells", "memory_file", memory.c_str()},
                                {"placecells", "stats_interval_s", "0"}}),
      "");
  std::ostringstream log;
  {
    Harness h({config.match_channel, config.pose_channel});
    PlaceCellsNode node(h.bus, config, log);
    auto truth = [&](int64_t t) {
      pose_t p = SamplePose();
      p.utime = t;
      h.Send(config.explore_pose_channel, p);
    };
    FuzzChannel(h, "placecells (explore)", config.omni_channel, ValidFrame(0), FrameMutations(), kMirror, truth);
    FuzzChannel(h, "placecells (explore)", config.odometry_channel, SampleOdometry(), OdometryMutations(),
                {"x_m", "y_m", "theta_rad"});
    FuzzChannel(h, "placecells (explore)", config.explore_pose_channel, SamplePose(), PoseMutations(),
                {"x_m", "y_m", "theta_rad"});
    FuzzChannel(h, "placecells (explore)", config.explore_correction_channel, SamplePoseCorrection(),
                PoseCorrectionMutations(), {"x_m", "y_m", "theta_rad", "from_utime"});
    ExpectStillWorks(h, "placecells (explore)", [&](int64_t t) {
      truth(t);
      h.Send(config.omni_channel, ValidFrame(t));
    }, config.match_channel);
    PrintCounts(h, "placecells (explore)");
    node.Save();
    node.Report(std::cerr);
    ASSERT_GT(node.memory().size(), 0);
  }
  auto localize = config;
  localize.mode = PlaceCellsMode::kLocalize;
  Harness h({localize.match_channel, localize.pose_channel});
  PlaceCellsNode node(h.bus, localize, log);
  FuzzChannel(h, "placecells (localize)", localize.omni_channel, ValidFrame(0), FrameMutations(), kMirror);
  FuzzChannel(h, "placecells (localize)", localize.odometry_channel, SampleOdometry(), OdometryMutations(),
              {"x_m", "y_m", "theta_rad"});
  ExpectStillWorks(h, "placecells (localize)", [&](int64_t t) { h.Send(localize.omni_channel, ValidFrame(t)); },
                   localize.match_channel);
  PrintCounts(h, "placecells (localize)");
  node.Report(std::cerr);
}

TEST(FuzzNodes, RatSlam) {
  // Poses on frames and odometry, the experience map on every message: every path publishes.
  const auto config = RatSlamConfig::FromIni(
      Config("ratslam.ini", {{"node", "pose_on", "both"}, {"node", "experience_map_interval_s", "0.001"}}), "");
  std::ostringstream log;
  const std::set<std::string> outputs = {config.pose_channel, config.experience_map_channel};
  FuzzFirstOdometry(
      "ratslam", outputs, config.odometry_channel, config.pose_channel,
      [&](glue::Bus& bus) { return std::make_shared<RatSlamNode>(bus, config, log); },
      [&](Harness& h, int64_t t) {
        h.Send(config.odometry_channel, Odometry(t));
        h.Send(config.omni_channel, ValidFrame(t + 1000));
      });
  Harness h(outputs);
  RatSlamNode node(h.bus, config, log);
  h.Send(config.odometry_channel, Odometry(h.Clock()));
  h.Send(config.omni_channel, ValidFrame(h.Clock()));
  FuzzChannel(h, "ratslam", config.omni_channel, ValidFrame(0), FrameMutations(), kMirror);
  FuzzChannel(h, "ratslam", config.odometry_channel, SampleOdometry(), OdometryMutations(),
              {"delta_x_m", "delta_y_m", "delta_theta_rad", "delta_t_s"});
  ExpectStillWorks(h, "ratslam", [&](int64_t t) { h.Send(config.omni_channel, ValidFrame(t)); }, config.pose_channel);
  ExpectStillWorks(h, "ratslam", [&](int64_t t) { h.Send(config.odometry_channel, Odometry(t)); },
                   config.experience_map_channel);
  PrintCounts(h, "ratslam");
  node.Report(std::cerr);
  EXPECT_EQ(node.internal_errors(), 0);
}

TEST(FuzzNodes, FusedSlam) {
  // The map and a status after every scan: every output path publishes.
  const auto ini = [](const char* start) {
    return Config("fused_slam.ini", {{"fused_slam", "map_every_n_scans", "1"},
                                     {"fused_slam", "status_every_n_scans", "1"},
                                     {"fused_slam", "start", start}});
  };
  const auto config = FusedSlamConfig::FromIni(ini("odometry"), "");
  const std::set<std::string> outputs = {config.pose_channel, config.map_channel, config.status_channel};
  auto scan = [](int64_t t) {
    laser_scan_t s = SampleLaserScan(181);
    s.utime = t;
    return s;
  };
  auto visual = [](int64_t t) {
    pose_t p = SamplePose();  // near the sample odometry's cumulative pose (1, 2)
    p.x_m = 1.0;
    p.y_m = 2.0;
    p.theta_rad = 0.3;
    p.utime = t;
    return p;
  };
  FuzzFirstOdometry(
      "fused-slam", outputs, config.odometry_channel, config.pose_channel,
      [&](glue::Bus& bus) { return std::make_shared<FusedSlamNode>(bus, config); },
      [&](Harness& h, int64_t t) {
        h.Send(config.odometry_channel, Odometry(t));
        h.Send(config.scan_channel, scan(t + 1000));
        h.Send(config.visual_channel, visual(t + 2000));
      });
  {
    Harness h(outputs);
    FusedSlamNode node(h.bus, config);
    h.Send(config.odometry_channel, Odometry(h.Clock()));
    h.Send(config.scan_channel, scan(h.Clock()));
    auto odometry_before = [&](int64_t t) { h.Send(config.odometry_channel, Odometry(t - 1000)); };
    FuzzChannel(h, "fused-slam", config.odometry_channel, SampleOdometry(), OdometryMutations(),
                {"delta_x_m", "delta_y_m", "delta_theta_rad"});
    FuzzChannel(h, "fused-slam", config.scan_channel, SampleLaserScan(181), ScanMutations(),
                {"sensor_x_m", "sensor_y_m", "sensor_theta_rad", "angle_min_rad", "angle_increment_rad", "range_min_m",
                 "range_max_m"},
                odometry_before);
    FuzzChannel(h, "fused-slam", config.visual_channel, visual(0), PoseMutations(),
                {"x_m", "y_m", "theta_rad", "covariance[0]", "covariance[1]", "covariance[4]", "covariance[8]"},
                odometry_before);
    ExpectStillWorks(h, "fused-slam", [&](int64_t t) {
      odometry_before(t);
      h.Send(config.scan_channel, scan(t));
    }, config.pose_channel);
    ExpectStillWorks(h, "fused-slam", [&](int64_t t) {
      odometry_before(t);
      h.Send(config.visual_channel, visual(t));
    }, config.status_channel);
    PrintCounts(h, "fused-slam");
    node.Report(std::cerr);
    EXPECT_EQ(node.internal_errors(), 0);
  }
  // start = visual: the first visual measurement starts the filter; fuzz it on fresh nodes.
  const auto vconfig = FusedSlamConfig::FromIni(ini("visual"), "");
  for (const auto& mu : PoseMutations()) {
    Harness h(outputs);
    FusedSlamNode node(h.bus, vconfig);
    h.Send(vconfig.odometry_channel, Odometry(h.Clock()));
    pose_t first = visual(h.Clock());
    mu.apply(first);
    h.Send(vconfig.visual_channel, first);
    const int64_t t = h.Clock();
    h.Send(vconfig.odometry_channel, Odometry(t));
    h.Send(vconfig.visual_channel, visual(t));
    h.Send(vconfig.scan_channel, scan(t + 1000));
    int poses = 0;
    for (const auto& [ch, p] : h.Take()) {
      EXPECT_EQ(OutputProblem(ch, p), "") << "fused-slam (start = visual): first visual " << mu.name;
      poses += ch == vconfig.pose_channel;
    }
    EXPECT_GT(poses, 0) << "fused-slam (start = visual): nothing after first visual " << mu.name;
    EXPECT_EQ(node.internal_errors(), 0) << "first visual " << mu.name;
  }
}

TEST(FuzzNodes, Navigator) {
  const auto config = NavigatorConfig::FromIni(Config("navigator.ini", {}), "");
  Harness h({config.drive_command_channel, config.status_channel});
  NavigatorNode node(h.bus, config);
  auto fix = [&](int64_t t) {
    pose_t p = SamplePose();
    p.utime = t;
    h.Send(config.pose_channel, p);
  };
  h.Send(config.odometry_channel, Odometry(h.Clock()));
  fix(h.Clock());
  FuzzChannel(h, "navigator", config.odometry_channel, SampleOdometry(), OdometryMutations(),
              {"delta_x_m", "delta_y_m", "delta_theta_rad"});
  FuzzChannel(h, "navigator", config.pose_channel, SamplePose(), PoseMutations(),
              {"x_m", "y_m", "theta_rad", "covariance[0]", "covariance[1]", "covariance[4]", "covariance[8]"});
  FuzzChannel(h, "navigator", config.homing_vector_channel, SampleHomingVector(), HomingVectorMutations(),
              {"direction_rad", "magnitude"});
  FuzzChannel(h, "navigator", config.route_channel, SampleRoute(), RouteMutations(), {"tolerance_m", "x_m[0]", "y_m[1]"});
  h.Send(config.route_channel, SampleRoute());
  fix(h.Clock());
  ExpectStillWorks(h, "navigator", [&](int64_t t) { h.Send(config.odometry_channel, Odometry(t)); },
                   config.drive_command_channel);
  PrintCounts(h, "navigator");
  node.Report(std::cerr);
}

}  // namespace
}  // namespace snapnav::fuzz
