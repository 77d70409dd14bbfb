// Node test: the ratslam process on memq:// — panoramas (and a raw frame) and odometry in,
// POSE_RATSLAM and EXPERIENCE_MAP out; malformed input is counted by reason, never a crash; the
// config is read with every key required.
#include "ratslam_node.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "../support/config_errors.hpp"
#include "snapnav/experience_map_t.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::processes {
namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kShipped = std::string(SNAPNAV_CONFIG_DIR) + "/ratslam.ini";

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// `text` with `key` in [section] set to `value` (removed when value is null). Fails the test
// when the key is not there.
std::string Edit(const std::string& text, const std::string& section, const std::string& key, const char* value) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, current;
  bool found = false;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line[first] == '[') current = line.substr(first + 1, line.find(']') - first - 1);
    if (current == section && line.rfind(key + " ", 0) == 0) {
      found = true;
      if (value) out << key << " = " << value << "\n";
      continue;
    }
    out << line << "\n";
  }
  EXPECT_TRUE(found) << "[" << section << "] " << key;
  return out.str();
}

RatSlamConfig Config(const std::string& prefix, const std::string& text) {
  return RatSlamConfig::FromIni(glue::IniFile::Parse(text, "test.ini"), prefix);
}

// Panorama input (grey 720x120 of the shipped [panorama]), poses per frame, a map every 0.5 s.
std::string PanoramaConfigText() {
  std::string t = ReadText(kShipped);
  t = Edit(t, "node", "input", "panorama");
  t = Edit(t, "node", "experience_map_interval_s", "0.5");
  t = Edit(t, "node", "stats_interval_s", "0");
  // OpenRatSLAM's injection and smaller cells: the test's odometry drifts 64 degrees a lap.
  t = Edit(t, "ratslam", "pc_vt_inject_energy", "0.15");
  t = Edit(t, "ratslam", "pc_cell_x_size_m", "0.25");
  return t;
}

// A textured 720x120 panorama, different for each seed.
cv::Mat Place(uint64_t seed) {
  cv::Mat noise(12, 72, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat pano;
  cv::resize(noise, pano, cv::Size(720, 120), 0, 0, cv::INTER_CUBIC);
  return pano;
}

// The panorama after a counter-clockwise turn of `columns` columns (they move up).
cv::Mat Turned(const cv::Mat& pano, int columns) {
  cv::Mat out(pano.size(), pano.type());
  for (int c = 0; c < pano.cols; ++c) pano.col(c).copyTo(out.col(((c + columns) % pano.cols + pano.cols) % pano.cols));
  return out;
}

omni_frame_t PanoramaFrame(const cv::Mat& image, int64_t utime, const nav::PanoramaModel& model) {
  omni_frame_t f = glue::ImageToFrame(image, omni_frame_t::GRAY8);
  f.utime = utime;
  f.sensor_name = "test";
  f.kind = omni_frame_t::PANORAMA;
  glue::SetPanorama(model, &f);
  return f;
}

odometry_t Odo(int64_t utime, const nav::Pose2& cumulative, const nav::Pose2& delta, double dt_s) {
  return glue::ToOdometryMsg(utime, "test", cumulative, delta, dt_s);
}

void Drain(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

// Two laps of a 4 x 4 m square at 0.4 m/s, odometry drifting 4 degrees per metre, a view per
// 0.25 m of route (place panoramas turned with the true heading): poses per frame with the frame's
// utime from the start pose on, experience maps, and a loop closure on the second lap.
TEST(RatSlamNode, FramesAndOdometryGivePosesAndAnExperienceMapThatClosesTheLoop) {
  glue::Bus bus("memq://");
  const RatSlamConfig config = Config("RS1_", PanoramaConfigText());
  std::ostringstream log;
  RatSlamNode node(bus, config, log);
  std::vector<pose_t> poses;
  std::vector<experience_map_t> maps;
  bus.Subscribe<pose_t>("RS1_POSE_RATSLAM", [&](const pose_t& p) { poses.push_back(p); });
  bus.Subscribe<experience_map_t>("RS1_EXPERIENCE_MAP", [&](const experience_map_t& m) { maps.push_back(m); });

  std::vector<cv::Mat> places;
  for (int i = 0; i < 64; ++i) places.push_back(Place(100 + static_cast<uint64_t>(i)));
  const nav::Pose2 start{1, 2, 0.5};  // the odometry frame's start: the map frame starts here
  nav::Pose2 truth{0, 0, 0}, odometry = start;
  const double dt = 0.02, speed = 0.4, drift = 4 * kPi / 180;
  int64_t utime = 1'700'000'000'000'000;
  bus.Publish("RS1_ODOMETRY", Odo(utime, odometry, {}, 0));  // the first message fixes the start
  int step = 0;
  double travelled = 0;
  std::vector<int64_t> frame_utimes;
  for (int lap = 0; lap < 2; ++lap) {
    for (int side = 0; side < 4; ++side) {
      for (int i = 0; i < 500; ++i, ++step) {  // 4 m
        utime += 20'000;
        const nav::Pose2 measured{speed * dt, 0, drift * speed * dt};
        truth = truth.Compose({speed * dt, 0, 0});
        odometry = odometry.Compose(measured);
        travelled += speed * dt;
        bus.Publish("RS1_ODOMETRY", Odo(utime, odometry, measured, dt));
        if (step % 5 == 0) {
          const int place = static_cast<int>(std::lround(std::fmod(travelled, 16.0) / 0.25)) % 64;
          const int columns = static_cast<int>(std::lround(truth.theta_rad / (2 * kPi) * 720));
          bus.Publish("RS1_OMNI_PANORAMA",
                      PanoramaFrame(Turned(places[static_cast<size_t>(place)], columns), utime, config.panorama));
          frame_utimes.push_back(utime);
        }
        Drain(bus);
      }
      for (int i = 0; i < 25; ++i) {
        utime += 20'000;
        const nav::Pose2 turn{0, 0, kPi / 2 / 25};
        truth = truth.Compose(turn);
        odometry = odometry.Compose(turn);
        bus.Publish("RS1_ODOMETRY", Odo(utime, odometry, turn, dt));
      }
      Drain(bus);
    }
  }
  ASSERT_EQ(poses.size(), frame_utimes.size()) << "one pose per frame (pose_on = frame)";
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(poses[i].utime, frame_utimes[i]);
    EXPECT_EQ(poses[i].estimator, "ratslam");
    EXPECT_EQ(poses[i].frame, "map");
  }
  // The map frame is the odometry frame: the first pose is where the odometry was.
  EXPECT_NEAR(poses.front().x_m, start.x_m, 0.05);
  EXPECT_NEAR(poses.front().y_m, start.y_m, 0.05);
  // The truth in the odometry frame, against RatSLAM's final pose and the odometry's.
  const nav::Pose2 truth_odom = start.Compose(truth);
  const double ratslam_error = std::hypot(poses.back().x_m - truth_odom.x_m, poses.back().y_m - truth_odom.y_m);
  const double odometry_error = std::hypot(odometry.x_m - truth_odom.x_m, odometry.y_m - truth_odom.y_m);
  EXPECT_LT(ratslam_error, 0.5 * odometry_error) << ratslam_error << " m vs odometry " << odometry_error << " m";

  ASSERT_GE(maps.size(), 40u) << "a map every 0.5 s of message time over about 45 s";
  const experience_map_t& m = maps.back();
  EXPECT_EQ(m.estimator, "ratslam");
  EXPECT_EQ(m.nexperiences, static_cast<int32_t>(node.slam()->experience_map().experiences().size()));
  EXPECT_EQ(m.nlinks, static_cast<int32_t>(m.link_from.size()));
  EXPECT_EQ(m.templates, node.slam()->templates());
  EXPECT_GT(m.loop_closures, 0);
  int flagged = 0;
  for (int i = 0; i < m.nlinks; ++i) {
    ASSERT_GE(m.link_from[i], 0);
    ASSERT_LT(m.link_to[i], m.nexperiences);
    flagged += m.link_loop_closure[i];
  }
  EXPECT_EQ(flagged, m.loop_closures);
  EXPECT_EQ(node.rejected_total(), 0);
  EXPECT_EQ(node.internal_errors(), 0);
  EXPECT_EQ(node.processed(), static_cast<int64_t>(frame_utimes.size()));
}

TEST(RatSlamNode, MalformedInputIsCountedByReasonAndNeverCrashes) {
  glue::Bus bus("memq://");
  const RatSlamConfig config = Config("RS2_", PanoramaConfigText());
  std::ostringstream log;
  RatSlamNode node(bus, config, log);
  std::vector<pose_t> poses;
  bus.Subscribe<pose_t>("RS2_POSE_RATSLAM", [&](const pose_t& p) { poses.push_back(p); });
  const double nan = std::numeric_limits<double>::quiet_NaN();
  int64_t t = 1'000'000;
  // A first odometry message that is not finite fixes nothing.
  bus.Publish("RS2_ODOMETRY", Odo(t, {nan, 0, 0}, {}, 0));
  bus.Publish("RS2_ODOMETRY", Odo(t += 20'000, {0, 0, 0}, {}, 0));  // the start
  bus.Publish("RS2_ODOMETRY", Odo(t += 20'000, {0.01, 0, 0}, {0.01, nan, 0}, 0.02));
  odometry_t bad_dt = Odo(t += 20'000, {0.02, 0, 0}, {0.01, 0, 0}, 0.02);
  bad_dt.delta_t_s = -1;
  bus.Publish("RS2_ODOMETRY", bad_dt);
  // Frames: wrong size, wrong geometry, unknown kind, unknown encoding, no pixels, garbage.
  omni_frame_t small = PanoramaFrame(cv::Mat(60, 360, CV_8UC1, cv::Scalar(9)), t, config.panorama);
  small.bearing_col0_rad = 0;
  bus.Publish("RS2_OMNI_PANORAMA", small);
  omni_frame_t geometry = PanoramaFrame(Place(1), t, config.panorama);
  geometry.elevation_top_rad = 1.2f;
  bus.Publish("RS2_OMNI_PANORAMA", geometry);
  omni_frame_t kind = PanoramaFrame(Place(1), t, config.panorama);
  kind.kind = 7;
  bus.Publish("RS2_OMNI_PANORAMA", kind);
  omni_frame_t encoding = PanoramaFrame(Place(1), t, config.panorama);
  encoding.encoding = 9;
  bus.Publish("RS2_OMNI_PANORAMA", encoding);
  omni_frame_t empty = PanoramaFrame(Place(1), t, config.panorama);
  empty.data.clear();
  empty.data_size = 0;
  bus.Publish("RS2_OMNI_PANORAMA", empty);
  const std::string garbage = "not an lcm message";
  bus.PublishRaw("RS2_OMNI_PANORAMA", garbage.data(), garbage.size());
  bus.PublishRaw("RS2_ODOMETRY", garbage.data(), garbage.size());
  // And good ones still work.
  bus.Publish("RS2_OMNI_PANORAMA", PanoramaFrame(Place(2), t += 20'000, config.panorama));
  bus.Publish("RS2_ODOMETRY", Odo(t += 20'000, {0.03, 0, 0}, {0.01, 0, 0}, 0.02));
  Drain(bus);

  EXPECT_EQ(node.rejected("non-finite odometry"), 2);
  EXPECT_EQ(node.rejected("bad odometry time"), 1);
  EXPECT_EQ(node.rejected("wrong size"), 1);
  EXPECT_EQ(node.rejected("wrong geometry"), 1);
  EXPECT_EQ(node.rejected("unknown kind"), 1);
  EXPECT_EQ(node.rejected("unknown encoding"), 1);
  EXPECT_EQ(node.rejected("empty image"), 1);
  EXPECT_EQ(node.rejected_total(), 8);
  EXPECT_EQ(node.internal_errors(), 0);
  EXPECT_EQ(node.processed(), 1);
  ASSERT_EQ(poses.size(), 1u);
  // Rejections and undecodable payloads are counted on their channels by the bus.
  EXPECT_EQ(bus.stats().at("RS2_OMNI_PANORAMA").decode_errors, 6u);
  EXPECT_EQ(bus.stats().at("RS2_ODOMETRY").decode_errors, 4u);
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("rejected (wrong size): 1"), std::string::npos) << report.str();
}

TEST(RatSlamNode, RawFramesAreUnwrappedAndAFrameBeforeOdometryStartsAtTheOrigin) {
  glue::Bus bus("memq://");
  std::string text = ReadText(kShipped);
  text = Edit(text, "node", "pose_on", "both");
  const RatSlamConfig config = Config("RS3_", text);
  std::ostringstream log;
  RatSlamNode node(bus, config, log);
  std::vector<pose_t> poses;
  bus.Subscribe<pose_t>("RS3_POSE_RATSLAM", [&](const pose_t& p) { poses.push_back(p); });
  // A grey 640x480 catadioptric image of noise, with the calibration of [mirror].
  cv::Mat raw(480, 640, CV_8UC1);
  cv::RNG(5).fill(raw, cv::RNG::UNIFORM, 0, 256);
  omni_frame_t f = glue::ImageToFrame(raw, omni_frame_t::GRAY8);
  f.utime = 5'000'000;
  f.kind = omni_frame_t::RAW_OMNI;
  glue::SetMirror(config.mirror, &f);
  bus.Publish("RS3_OMNI_FRAME", f);
  Drain(bus);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].utime, 5'000'000);
  EXPECT_EQ(poses[0].x_m, 0);  // no odometry yet: the origin
  ASSERT_NE(node.slam(), nullptr);
  EXPECT_EQ(node.slam()->templates(), 1);
  // pose_on = both: odometry publishes too (the first message only fixes... nothing: RatSLAM
  // already started at the origin, so its increment is used from the second on).
  bus.Publish("RS3_ODOMETRY", Odo(5'020'000, {0, 0, 0}, {}, 0));
  bus.Publish("RS3_ODOMETRY", Odo(5'040'000, {0.1, 0, 0}, {0.1, 0, 0}, 0.02));
  Drain(bus);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].utime, 5'040'000);
  EXPECT_NEAR(poses[1].x_m, 0.1, 1e-9);
}

TEST(RatSlamConfig, ShippedConfigHasTheLibnavDefaults) {
  const RatSlamConfig c = RatSlamConfig::FromIni(glue::IniFile::Load(kShipped), "");
  std::ostringstream shipped, defaults;
  glue::PrintRatSlamOptions(shipped, c.options);
  glue::PrintRatSlamOptions(defaults, nav::RatSlamOptions{});
  EXPECT_EQ(shipped.str(), defaults.str());
  EXPECT_EQ(c.input_channel(), "OMNI_FRAME");
  EXPECT_EQ(c.pose_channel, "POSE_RATSLAM");
  EXPECT_EQ(c.experience_map_channel, "EXPERIENCE_MAP");
  // The effective configuration reads back as the same configuration.
  std::ostringstream printed;
  c.Print(printed);
  const RatSlamConfig again = RatSlamConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  std::ostringstream printed_again;
  again.Print(printed_again);
  EXPECT_EQ(printed.str(), printed_again.str());
}

TEST(RatSlamConfig, MissingUnknownAndInvalidKeysAreErrorsNamingThem) {
  const std::string text = ReadText(kShipped);
  try {
    Config("", Edit(text, "ratslam", "vt_match_threshold", nullptr));
    FAIL() << "missing key accepted";
  } catch (const glue::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vt_match_threshold"), std::string::npos) << e.what();
  }
  try {
    Config("", text + "[ratslam]\npc_cell_x_size = 1.0\n");  // OpenRatSLAM's name without the unit
    FAIL() << "unknown key accepted";
  } catch (const glue::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("pc_cell_x_size"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Config("", Edit(text, "ratslam", "pc_w_e_dim", "6")), glue::ConfigError);
  EXPECT_THROW(Config("", Edit(text, "ratslam", "pc_dim_xy", "many")), glue::ConfigError);
  EXPECT_THROW(Config("", Edit(text, "node", "pose_on", "always")), glue::ConfigError);
  EXPECT_THROW(Config("", Edit(text, "node", "input", "jpeg")), glue::ConfigError);
  EXPECT_THROW(Config("", Edit(text, "node", "experience_map_interval_s", "-1")), glue::ConfigError);
  EXPECT_THROW(Config("", Edit(text, "panorama", "width_px", "0")), glue::ConfigError);
  const RatSlamConfig prefixed = Config("P_", text);
  EXPECT_EQ(prefixed.odometry_channel, "P_ODOMETRY");
}

// Every number of the shipped ratslam.ini made negative or NaN: each error names the file, the line and
// the key.
TEST(RatSlamConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(
      test_support::ExpectBadNumbersNamed(kShipped, [](const glue::IniFile& ini) { RatSlamConfig::FromIni(ini, ""); }),
      0);
}

}  // namespace
}  // namespace snapnav::processes
