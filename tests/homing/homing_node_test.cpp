// Node tests: the homing process on memq:// — frames rendered by the simulator go in,
// homing vectors come out; bad input is counted, never fatal.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "../support/config_errors.hpp"
#include "homing_node.hpp"
#include "landmarks_node.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/homing_vector_t.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::processes {
namespace {

const std::string kShippedConfig = std::string(SNAPNAV_CONFIG_DIR) + "/homing.ini";

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// `text` with the line of `key` in [section] replaced by `key = value` (or removed when
// `value` is null). Fails the test when the key is not there.
std::string Edit(const std::string& text, const std::string& section, const std::string& key, const char* value) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, current;
  bool found = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '[') current = line.substr(1, line.find(']') - 1);
    const auto eq = line.find('=');
    if (current == section && line[0] != '#' && line[0] != ';' && eq != std::string::npos &&
        line.substr(0, line.find_first_of(" \t=")) == key) {
      found = true;
      if (value) out << key << " = " << value << "\n";
      continue;
    }
    out << line << "\n";
  }
  EXPECT_TRUE(found) << "[" << section << "] " << key << " not in the shipped config";
  return out.str();
}

struct Override {
  const char* section;
  const char* key;
  const char* value;
};

HomingConfig Config(const std::string& prefix, std::initializer_list<Override> overrides,
                    const std::string& origin = "test.ini") {
  std::string text = ReadText(kShippedConfig);
  for (const auto& o : overrides) text = Edit(text, o.section, o.key, o.value);
  return HomingConfig::FromIni(glue::IniFile::Parse(text, origin), prefix);
}

// A 5 m x 4 m room with blurred random textures, as in hog_homing_test, and the camera of the
// shipped config (720x120 panorama over +-20 deg; mirror -40..20 deg).
class Lab {
 public:
  Lab() {
    scene_.name = "room";
    cv::RNG rng(11);
    for (int i = 0; i < 4; ++i) {
      cv::Mat tex(128, 128, CV_8UC3);
      rng.fill(tex, cv::RNG::UNIFORM, 0, 255);
      cv::GaussianBlur(tex, tex, {9, 9}, 3.0);
      scene_.textures.push_back(nav::sim::MakeTexture("t" + std::to_string(i), tex, 1.5, 1.5));
    }
    scene_.walls = {{{-2.5, -2}, {2.5, -2}, 2.6, 0, 0, 0},
                    {{2.5, -2}, {2.5, 2}, 2.6, 0, 1, 0},
                    {{2.5, 2}, {-2.5, 2}, 2.6, 0, 2, 0},
                    {{-2.5, 2}, {-2.5, -2}, 2.6, 0, 3, 0}};
    camera_.panorama.width_px = 720;
    camera_.panorama.height_px = 120;
    camera_.panorama.elevation_top_rad = 20 * M_PI / 180;
    camera_.panorama.elevation_bottom_rad = -20 * M_PI / 180;
    camera_.mirror.elevation_inner_rad = -40 * M_PI / 180;
    camera_.mirror.elevation_outer_rad = 20 * M_PI / 180;
    renderer_.emplace(scene_, camera_);
  }

  omni_frame_t Panorama(const nav::Pose2& pose, int64_t utime, int8_t encoding = omni_frame_t::GRAY8) {
    cv::Mat img;
    renderer_->RenderPanorama(pose, {}, &img);
    omni_frame_t f = glue::ImageToFrame(img, encoding);
    f.utime = utime;
    f.sensor_name = "test";
    f.kind = omni_frame_t::PANORAMA;
    glue::SetPanorama(camera_.panorama, &f);
    return f;
  }

  omni_frame_t Raw(const nav::Pose2& pose, int64_t utime, bool with_mirror = true) {
    cv::Mat img;
    renderer_->RenderOmni(pose, {}, &img);
    omni_frame_t f = glue::ImageToFrame(img, omni_frame_t::RGB8);
    f.utime = utime;
    f.sensor_name = "test";
    f.kind = omni_frame_t::RAW_OMNI;
    if (with_mirror) glue::SetMirror(camera_.mirror, &f);
    return f;
  }

  cv::Mat RawImage(const nav::Pose2& pose) {
    cv::Mat img;
    renderer_->RenderOmni(pose, {}, &img);
    return img;
  }

  const nav::sim::OmniCameraOptions& camera() const { return camera_; }

 private:
  nav::sim::Scene scene_;
  nav::sim::OmniCameraOptions camera_;
  std::optional<nav::sim::OmniRenderer> renderer_;
};

// Angle between the estimated direction and the true direction home of a robot at `pose`
// (home at the origin, heading 0).
double DirectionError(const homing_vector_t& v, const nav::Pose2& pose) {
  const double truth = nav::WrapAngle(std::atan2(-pose.y_m, -pose.x_m) - pose.theta_rad);
  return std::abs(nav::WrapAngle(v.direction_rad - truth));
}

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

constexpr double kSixtyDeg = M_PI / 3;

// home = first: the first frame becomes the home and gets no vector, so N frames give N - 1
// vectors, stamped with the utimes of frames 2..N.
TEST(HomingNode, PanoramaFramesWithHomeFirstGiveOneVectorPerLaterFrame) {
  Lab lab;
  glue::Bus bus("memq://");
  HomingNode node(bus, Config("H1_", {{"homing", "input", "panorama"}, {"homing", "home", "first"}}));
  std::vector<homing_vector_t> got;
  bus.Subscribe<homing_vector_t>("H1_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });

  const std::vector<nav::Pose2> poses = {{0, 0, 0}, {0.6, 0, 0.3}, {0, -0.6, -1.0}, {-0.5, 0.4, 2.0}, {0.3, 0.3, 0}};
  for (size_t i = 0; i < poses.size(); ++i) {
    bus.Publish("H1_OMNI_PANORAMA", lab.Panorama(poses[i], 1000000 + 100000 * static_cast<int64_t>(i),
                                                 i % 2 ? omni_frame_t::RGB8 : omni_frame_t::PNG));
  }
  HandleAll(bus);
  ASSERT_EQ(got.size(), poses.size() - 1);
  EXPECT_EQ(node.frames(), static_cast<int64_t>(poses.size()));
  EXPECT_EQ(node.homes_set(), 1);
  EXPECT_EQ(node.published(), static_cast<int64_t>(got.size()));
  EXPECT_EQ(node.rejected_total(), 0);
  for (size_t i = 0; i < got.size(); ++i) {
    const homing_vector_t& v = got[i];
    EXPECT_EQ(v.utime, 1000000 + 100000 * static_cast<int64_t>(i + 1));
    EXPECT_EQ(v.method, landmark_set_t::HOG);
    EXPECT_EQ(v.alv_variant, "hog");
  }
  // The frame 0.6 m in front of home, turned by 0.3 rad: home is behind it.
  ASSERT_TRUE(got[0].valid);
  EXPECT_GT(got[0].magnitude, 0);
  EXPECT_GE(got[0].nlandmarks_used, 1);
  EXPECT_LT(DirectionError(got[0], poses[1]), kSixtyDeg) << "direction " << got[0].direction_rad;
  EXPECT_NEAR(got[0].compass_rotation_rad, 0.3, 0.2);
  // The other displaced frames (any heading): most point home too.
  int good = 0;
  for (size_t i = 1; i < 4; ++i) good += got[i - 1].valid && DirectionError(got[i - 1], poses[i]) < kSixtyDeg;
  EXPECT_GE(good, 2);
}

// Raw catadioptric frames are unwrapped with their own calibration; the map is built once per
// calibration, not per frame.
TEST(HomingNode, RawFramesAreUnwrappedWithAMapBuiltOncePerCalibration) {
  Lab lab;
  glue::Bus bus("memq://");
  HomingNode node(bus, Config("H2_", {{"homing", "home", "first"}}));  // input = raw in the shipped config
  std::vector<homing_vector_t> got;
  bus.Subscribe<homing_vector_t>("H2_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });
  const nav::Pose2 away{0.6, 0, 0.3};
  bus.Publish("H2_OMNI_FRAME", lab.Raw({0, 0, 0}, 10));
  bus.Publish("H2_OMNI_FRAME", lab.Raw(away, 20));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].utime, 20);
  ASSERT_TRUE(got[0].valid);
  EXPECT_LT(DirectionError(got[0], away), kSixtyDeg) << "direction " << got[0].direction_rad;
  EXPECT_EQ(node.unwrapper_builds(), 1);

  // More frames of the same calibration reuse the map; another calibration builds a new one.
  for (int i = 0; i < 3; ++i) bus.Publish("H2_OMNI_FRAME", lab.Raw(away, 30 + i));
  HandleAll(bus);
  EXPECT_EQ(node.unwrapper_builds(), 1);
  omni_frame_t moved = lab.Raw(away, 40);
  moved.mirror_center_x_px += 1;
  bus.Publish("H2_OMNI_FRAME", moved);
  HandleAll(bus);
  EXPECT_EQ(node.unwrapper_builds(), 2);
  // A frame without a calibration (all mirror fields zero) is unwrapped with [mirror].
  bus.Publish("H2_OMNI_FRAME", lab.Raw(away, 50, /*with_mirror=*/false));
  HandleAll(bus);
  EXPECT_EQ(node.unwrapper_builds(), 3);
  ASSERT_EQ(got.size(), 6u);
  EXPECT_EQ(got.back().utime, 50);
  EXPECT_TRUE(got.back().valid);
  EXPECT_EQ(node.rejected_total(), 0);
}

// home = message: frames before the home are counted, not answered; a HOME_SNAPSHOT (here a
// raw frame, unwrapped like the input) becomes the home; a later one replaces it.
TEST(HomingNode, HomeSnapshotMessageSetsTheHome) {
  Lab lab;
  glue::Bus bus("memq://");
  HomingNode node(bus, Config("H3_", {{"homing", "input", "panorama"}}));  // home = message
  std::vector<homing_vector_t> got;
  bus.Subscribe<homing_vector_t>("H3_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });
  const nav::Pose2 away{0, 0.6, -0.5};
  bus.Publish("H3_OMNI_PANORAMA", lab.Panorama(away, 100));
  HandleAll(bus);
  EXPECT_FALSE(node.has_home());
  EXPECT_EQ(node.before_home(), 1);
  EXPECT_TRUE(got.empty());

  bus.Publish("H3_HOME_SNAPSHOT", lab.Raw({0, 0, 0}, 150));
  bus.Publish("H3_OMNI_PANORAMA", lab.Panorama(away, 200));
  HandleAll(bus);
  EXPECT_TRUE(node.has_home());
  EXPECT_EQ(node.homes_set(), 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].utime, 200);
  ASSERT_TRUE(got[0].valid);
  EXPECT_LT(DirectionError(got[0], away), kSixtyDeg) << "direction " << got[0].direction_rad;

  // A new home where the robot stands: the robot is home, home is elsewhere than before.
  bus.Publish("H3_HOME_SNAPSHOT", lab.Panorama(away, 250));
  bus.Publish("H3_OMNI_PANORAMA", lab.Panorama(away, 300));
  HandleAll(bus);
  EXPECT_EQ(node.homes_set(), 2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].utime, 300);  // the same view as home: little or no homing vector
  EXPECT_TRUE(!got[1].valid || got[1].magnitude < got[0].magnitude);
  EXPECT_EQ(node.rejected_total(), 0);
}

// Bad input is counted per reason; nothing is published for it and the node keeps working.
TEST(HomingNode, BadInputIsCountedAndSkipped) {
  Lab lab;
  glue::Bus bus("memq://");
  HomingNode node(bus, Config("H4_", {{"homing", "input", "panorama"}, {"homing", "home", "first"}}));
  int vectors = 0;
  bus.Subscribe<homing_vector_t>("H4_HOMING_VECTOR", [&](const homing_vector_t&) { ++vectors; });
  const std::string channel = "H4_OMNI_PANORAMA";

  bus.PublishRaw(channel, "garbage, not an omni frame", 26);  // does not decode
  bus.PublishRaw(channel, "", 0);                             // empty payload
  omni_frame_t f = lab.Panorama({0, 0, 0}, 1);
  f.encoding = 7;  // no such encoding
  bus.Publish(channel, f);
  f = lab.Panorama({0, 0, 0}, 2);
  f.encoding = omni_frame_t::JPEG;  // raw pixels claimed to be a JPEG file
  f.row_stride = 0;
  bus.Publish(channel, f);
  f = lab.Panorama({0, 0, 0}, 3);
  f.data.resize(f.data.size() / 2);  // truncated pixels
  f.data_size = static_cast<int32_t>(f.data.size());
  bus.Publish(channel, f);
  cv::Mat small(60, 360, CV_8UC1, cv::Scalar(128));
  f = glue::ImageToFrame(small, omni_frame_t::GRAY8);  // not the configured 720x120
  f.kind = omni_frame_t::PANORAMA;
  glue::SetPanorama(lab.camera().panorama, &f);
  bus.Publish(channel, f);
  f = lab.Panorama({0, 0, 0}, 4);
  f.elevation_top_rad = 0.6f;  // another panorama model
  bus.Publish(channel, f);
  f = lab.Panorama({0, 0, 0}, 5);
  f.kind = 9;
  bus.Publish(channel, f);
  f = omni_frame_t{};
  f.kind = omni_frame_t::PANORAMA;  // no pixels at all
  bus.Publish(channel, f);
  f = lab.Raw({0, 0, 0}, 6);
  f.mirror_outer_radius_px = 5;  // smaller than the inner radius: no useful ring
  bus.Publish(channel, f);
  bus.Publish(channel, f);  // the same bad calibration again: refused without a rebuild
  HandleAll(bus);
  EXPECT_EQ(vectors, 0);
  EXPECT_FALSE(node.has_home());
  EXPECT_EQ(node.frames(), 9);
  EXPECT_EQ(bus.stats().at(channel).received, 11u);
  EXPECT_EQ(bus.stats().at(channel).decode_errors, 11u);  // the bus's two and the node's nine
  EXPECT_EQ(node.rejected_total(), 9);
  const auto& r = node.rejected();
  EXPECT_EQ(r.count("unknown encoding") ? r.at("unknown encoding") : 0, 1);
  EXPECT_EQ(r.count("undecodable image") ? r.at("undecodable image") : 0, 2);
  EXPECT_EQ(r.count("wrong size") ? r.at("wrong size") : 0, 1);
  EXPECT_EQ(r.count("wrong geometry") ? r.at("wrong geometry") : 0, 1);
  EXPECT_EQ(r.count("unknown kind") ? r.at("unknown kind") : 0, 1);
  EXPECT_EQ(r.count("empty image") ? r.at("empty image") : 0, 1);
  EXPECT_EQ(r.count("bad mirror calibration") ? r.at("bad mirror calibration") : 0, 2);
  EXPECT_EQ(node.unwrapper_builds(), 0);
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("wrong size"), std::string::npos) << report.str();

  // Still working: a good home and a good frame give one vector.
  bus.Publish(channel, lab.Panorama({0, 0, 0}, 10));
  bus.Publish(channel, lab.Panorama({0.6, 0, 0}, 20));
  HandleAll(bus);
  EXPECT_EQ(vectors, 1);
  EXPECT_EQ(bus.stats().at(channel).handler_errors, 0u);
}

// home = image: the file is loaded at start (relative to the config's folder); a missing or
// unreadable file is an error that names it.
TEST(HomingNode, HomeImageFile) {
  Lab lab;
  const auto dir = std::filesystem::temp_directory_path() / ("homing_node_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string origin = (dir / "homing.ini").string();
  {
    glue::Bus bus("memq://");
    try {
      HomingNode node(
          bus, Config("H5_", {{"homing", "home", "image"}, {"homing", "home_image", "no_such_home.png"}}, origin));
      ADD_FAILURE() << "no error for a missing home image";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find((dir / "no_such_home.png").string()), std::string::npos) << e.what();
    }
    std::ofstream(dir / "not_an_image.png") << "hello";
    try {
      HomingNode node(
          bus, Config("H5_", {{"homing", "home", "image"}, {"homing", "home_image", "not_an_image.png"}}, origin));
      ADD_FAILURE() << "no error for a file that is not an image";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("not_an_image.png"), std::string::npos) << e.what();
    }
  }
  // A raw home image, unwrapped with [mirror] (the shipped calibration is the test camera's).
  ASSERT_TRUE(cv::imwrite((dir / "home_raw.png").string(), lab.RawImage({0, 0, 0})));
  glue::Bus bus("memq://");
  HomingNode node(
      bus,
      Config("H6_",
             {{"homing", "input", "panorama"}, {"homing", "home", "image"}, {"homing", "home_image", "home_raw.png"}},
             origin));
  EXPECT_TRUE(node.has_home());
  std::vector<homing_vector_t> got;
  bus.Subscribe<homing_vector_t>("H6_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });
  const nav::Pose2 away{-0.6, 0, 0};
  bus.Publish("H6_OMNI_PANORAMA", lab.Panorama(away, 5));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 1u);
  ASSERT_TRUE(got[0].valid);
  EXPECT_LT(DirectionError(got[0], away), kSixtyDeg) << "direction " << got[0].direction_rad;

  // A panorama home image must have the configured size.
  const cv::Mat small(60, 360, CV_8UC3, cv::Scalar(1, 2, 3));
  ASSERT_TRUE(cv::imwrite((dir / "small.png").string(), small));
  try {
    HomingNode bad(bus, Config("H7_",
                               {{"homing", "home", "image"},
                                {"homing", "home_image", "small.png"},
                                {"homing", "home_image_kind", "panorama"}},
                               origin));
    ADD_FAILURE() << "no error for a home panorama of the wrong size";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("360x60"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(HomingConfig, ShippedConfigLoadsAndPrintsBack) {
  const auto config = HomingConfig::FromIni(glue::IniFile::Load(kShippedConfig), "P_");
  EXPECT_EQ(config.omni_channel, "P_OMNI_FRAME");
  EXPECT_EQ(config.panorama_channel, "P_OMNI_PANORAMA");
  EXPECT_EQ(config.home_snapshot_channel, "P_HOME_SNAPSHOT");
  EXPECT_EQ(config.homing_vector_channel, "P_HOMING_VECTOR");
  EXPECT_EQ(config.panorama.width_px, 720);
  EXPECT_EQ(config.panorama.height_px, 120);
  EXPECT_NEAR(config.panorama.elevation_top_rad, 20 * M_PI / 180, 1e-12);
  EXPECT_EQ(config.homing.hog.cell_size_px, 20);
  EXPECT_EQ(config.homing.hog.bins, 36);
  EXPECT_EQ(config.homing.hog.range, nav::OrientationRange::kVertical);
  EXPECT_TRUE(config.homing.use_compass);
  EXPECT_EQ(config.homing.compass_hog.cell_size_px, 40);
  EXPECT_EQ(config.homing.alv.weight, nav::CellWeight::kLog);
  EXPECT_EQ(config.homing.alv.difference, nav::AlvDifference::kCurrentMinusHome);
  EXPECT_TRUE(config.home_image.empty());
  std::ostringstream printed;
  config.Print(printed);
  const auto again = HomingConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  std::ostringstream printed_again;
  again.Print(printed_again);
  EXPECT_EQ(printed.str(), printed_again.str());
}

TEST(HomingConfig, EveryShippedKeyIsRequired) {
  const std::string text = ReadText(kShippedConfig);
  const auto ini = glue::IniFile::Parse(text, "shipped");
  int keys = 0;
  for (const auto& section : ini.Sections()) {
    std::istringstream in(text);
    std::string line, current;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] == '[') current = line.substr(1, line.find(']') - 1);
      if (current != section || line.empty() || line[0] == '#' || line[0] == ';' || line[0] == '[') continue;
      const std::string key = line.substr(0, line.find_first_of(" \t="));
      try {
        HomingConfig::FromIni(glue::IniFile::Parse(Edit(text, section, key, nullptr), "test.ini"), "");
        ADD_FAILURE() << "no error without [" << section << "] " << key;
      } catch (const glue::ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
      }
      ++keys;
    }
  }
  EXPECT_EQ(keys, 75);
}

TEST(HomingConfig, BadValuesAndUnknownKeysAreErrors) {
  auto error = [](std::initializer_list<Override> o) -> std::string {
    try {
      Config("", o);
    } catch (const glue::ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error({{"homing", "input", "video"}}).find("input"), std::string::npos);
  EXPECT_NE(error({{"homing", "home", "last"}}).find("home"), std::string::npos);
  EXPECT_NE(error({{"hog", "range", "diagonal"}}).find("range"), std::string::npos);
  EXPECT_NE(error({{"alv", "weight", "sqrt"}}).find("weight"), std::string::npos);
  EXPECT_NE(error({{"hog", "band_top_px", "100"}}).find("[hog]"), std::string::npos);
  EXPECT_NE(error({{"compass", "cell_size_px", "200"}}).find("[compass]"), std::string::npos);
  EXPECT_NE(error({{"homing", "home", "image"}}).find("home_image"), std::string::npos);
  EXPECT_NE(error({{"homing", "home_image", "a.png"}}).find("home_image"), std::string::npos);
  EXPECT_NE(error({{"hog", "bins", "1"}}), "");
  EXPECT_NE(error({{"compass", "enabled", "maybe"}}).find("enabled"), std::string::npos);
  const std::string text = ReadText(kShippedConfig) + "[alv]\n";  // repeated section header is fine
  try {
    HomingConfig::FromIni(glue::IniFile::Parse(text + "treshold_frac = 0.3\n", "typo.ini"), "");
    ADD_FAILURE() << "no error for an unknown key";
  } catch (const glue::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("treshold_frac"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------ landmarks + homing on sets
const std::string kLandmarksConfig = std::string(SNAPNAV_CONFIG_DIR) + "/landmarks.ini";

LandmarksConfig LmConfig(const std::string& prefix, const std::string& method) {
  std::string text = Edit(ReadText(kLandmarksConfig), "landmarks", "input", "panorama");
  return LandmarksConfig::FromIni(glue::IniFile::Parse(text, "landmarks-test.ini"), prefix, method);
}

// The landmarks process turns each frame into a set on its method's channel; the homing process
// (input = landmarks, home = first) homes from the sets, with the method and landmark count.
// (The test room's walls are smooth blurred noise: SIFT finds a few keypoints, SURF none.)
TEST(LandmarkNodes, SiftSetsFlowIntoHomingVectors) {
  Lab lab;
  glue::Bus bus("memq://");
  LandmarksNode landmarks(bus, LmConfig("L1_", "sift"));
  HomingNode homing(bus, Config("L1_", {{"homing", "input", "landmarks"},
                                        {"homing", "home", "first"},
                                        {"channels", "landmarks", "LANDMARKS_SIFT"}}));
  std::vector<landmark_set_t> sets;
  std::vector<homing_vector_t> got;
  bus.Subscribe<landmark_set_t>("L1_LANDMARKS_SIFT", [&](const landmark_set_t& m) { sets.push_back(m); });
  bus.Subscribe<homing_vector_t>("L1_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });
  const std::vector<nav::Pose2> poses = {{0, 0, 0}, {0.6, 0, 0.0}, {0, -0.6, 0.5}, {-0.5, 0.4, -1.0}};
  for (size_t i = 0; i < poses.size(); ++i) bus.Publish("L1_OMNI_PANORAMA", lab.Panorama(poses[i], 100 + static_cast<int64_t>(i)));
  HandleAll(bus);
  ASSERT_EQ(sets.size(), poses.size());
  EXPECT_EQ(landmarks.published(), 4);
  EXPECT_EQ(landmarks.rejected_total(), 0);
  for (const auto& m : sets) {
    EXPECT_EQ(m.method, landmark_set_t::SIFT);
    EXPECT_GE(m.nlandmarks, 3);
    EXPECT_EQ(m.descriptor_length, 128);
  }
  ASSERT_EQ(got.size(), poses.size() - 1);
  EXPECT_EQ(homing.homes_set(), 1);
  int good = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].utime, 101 + static_cast<int64_t>(i));
    EXPECT_EQ(got[i].method, landmark_set_t::SIFT);
    EXPECT_EQ(got[i].alv_variant, "unit");
    if (got[i].valid) {
      EXPECT_GE(got[i].nlandmarks_used, 1);
      good += DirectionError(got[i], poses[i + 1]) < kSixtyDeg;
    }
  }
  EXPECT_GE(good, 2);
}

TEST(LandmarkNodes, EachMethodPublishesOnItsOwnChannel) {
  Lab lab;
  glue::Bus bus("memq://");
  LandmarksNode vline(bus, LmConfig("L2_", "vline"));
  LandmarksNode sift(bus, LmConfig("L2_", "sift"));
  std::map<std::string, landmark_set_t> last;
  for (const char* ch : {"L2_LANDMARKS_VLINE", "L2_LANDMARKS_SIFT"}) {
    bus.Subscribe<landmark_set_t>(ch, [&last, ch](const landmark_set_t& m) { last[ch] = m; });
  }
  bus.Publish("L2_OMNI_PANORAMA", lab.Panorama({0.2, 0.1, 0}, 7));
  HandleAll(bus);
  ASSERT_EQ(last.size(), 2u);
  EXPECT_EQ(last["L2_LANDMARKS_VLINE"].method, landmark_set_t::VLINE);
  EXPECT_EQ(last["L2_LANDMARKS_SIFT"].method, landmark_set_t::SIFT);
  EXPECT_EQ(last["L2_LANDMARKS_SIFT"].descriptor_length, 128);
  EXPECT_EQ(last["L2_LANDMARKS_SIFT"].utime, 7);
}

// A featureless frame gives an empty set (not an error), and homing says "no estimate".
// Malformed sets are counted by reason and skipped.
TEST(LandmarkNodes, EmptyAndMalformedSets) {
  Lab lab;
  glue::Bus bus("memq://");
  LandmarksNode landmarks(bus, LmConfig("L3_", "sift"));
  HomingNode homing(bus, Config("L3_", {{"homing", "input", "landmarks"}, {"channels", "landmarks", "LANDMARKS_SIFT"}}));
  std::vector<homing_vector_t> got;
  bus.Subscribe<homing_vector_t>("L3_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });
  omni_frame_t flat = glue::ImageToFrame(cv::Mat(120, 720, CV_8UC1, cv::Scalar(128)), omni_frame_t::GRAY8);
  flat.kind = omni_frame_t::PANORAMA;
  glue::SetPanorama(lab.camera().panorama, &flat);
  bus.Publish("L3_OMNI_PANORAMA", flat);
  HandleAll(bus);
  EXPECT_EQ(landmarks.empty_sets(), 1);
  EXPECT_EQ(homing.before_home(), 1);  // no home yet: counted, no vector

  // Home from a real set on HOME_LANDMARKS, then the empty set: published as valid = false.
  nav::LandmarkExtractorConfig sift;
  sift.method = nav::LandmarkMethod::kSift;
  const auto home_set = glue::LandmarkSetToMsg(
      nav::ExtractLandmarks(glue::FrameToImage(lab.Panorama({0, 0, 0}, 1)), sift), lab.camera().panorama, 1, "test");
  bus.Publish("L3_HOME_LANDMARKS", home_set);
  bus.Publish("L3_OMNI_PANORAMA", flat);
  HandleAll(bus);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_FALSE(got[0].valid);

  ASSERT_GT(home_set.nlandmarks, 0);
  landmark_set_t bad = home_set;
  bad.bearings_rad[0] = std::nanf("");
  bus.Publish("L3_LANDMARKS_SIFT", bad);
  landmark_set_t wrong_size = home_set;
  wrong_size.panorama_width_px = 360;
  bus.Publish("L3_LANDMARKS_SIFT", wrong_size);
  landmark_set_t vline = home_set;
  vline.method = landmark_set_t::VLINE;
  bus.Publish("L3_LANDMARKS_SIFT", vline);
  HandleAll(bus);
  EXPECT_EQ(homing.rejected().at("bad landmark set"), 2);
  EXPECT_EQ(homing.rejected().at("method differs from the home's"), 1);
  EXPECT_EQ(got.size(), 1u);
}

TEST(LandmarksConfig, ShippedConfigLoadsAndBadValuesAreErrors) {
  const auto c = LandmarksConfig::FromIni(glue::IniFile::Load(kLandmarksConfig), "P_");
  EXPECT_EQ(c.landmarks_channel, "P_LANDMARKS_SURF");
  std::ostringstream printed;
  c.Print(printed);
  const auto back = LandmarksConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed.ini"), "");
  EXPECT_EQ(back.landmarks_channel, "P_LANDMARKS_SURF");
  EXPECT_EQ(back.extractor.vline.window_px, c.extractor.vline.window_px);
  EXPECT_THROW(LandmarksConfig::FromIni(glue::IniFile::Load(kLandmarksConfig), "", "orb"), glue::ConfigError);
  const std::string text = ReadText(kLandmarksConfig);
  EXPECT_THROW(LandmarksConfig::FromIni(glue::IniFile::Parse(Edit(text, "surf", "octaves", "0"), "t.ini"), ""),
               glue::ConfigError);
  EXPECT_THROW(LandmarksConfig::FromIni(glue::IniFile::Parse(Edit(text, "vline", "window_px", nullptr), "t.ini"), ""),
               glue::ConfigError);
  EXPECT_THROW(LandmarksConfig::FromIni(glue::IniFile::Parse(text + "[sift]\nsigmaa = 2\n", "t.ini"), ""),
               glue::ConfigError);
}

// [view_fusion] with frames (HOG): home = first takes the first home_frames frames that are
// home_interval_s apart (no vectors for them, frames in between are skipped), then every frame
// gets a vector; with current_frames > 1 only frames current_interval_s apart do.
TEST(HomingNode, HomeFusedFromFramesTakenAnIntervalApart) {
  Lab lab;
  glue::Bus bus("memq://");
  HomingNode node(bus, Config("F1_", {{"homing", "input", "panorama"},
                                      {"homing", "home", "first"},
                                      {"view_fusion", "home_frames", "3"},
                                      {"view_fusion", "home_interval_s", "1.0"},
                                      {"view_fusion", "current_frames", "2"},
                                      {"view_fusion", "current_interval_s", "0.5"}}));
  std::vector<homing_vector_t> got;
  bus.Subscribe<homing_vector_t>("F1_HOMING_VECTOR", [&](const homing_vector_t& v) { got.push_back(v); });
  // Home frames at 0, 0.5 (too soon), 1.0 and 2.0 s: the home is complete with the third taken.
  for (const int64_t t : {0, 500000, 1000000, 2000000}) bus.Publish("F1_OMNI_PANORAMA", lab.Panorama({0, 0, 0}, t));
  HandleAll(bus);
  EXPECT_TRUE(node.has_home());
  EXPECT_EQ(node.homes_set(), 1);
  EXPECT_EQ(node.before_home(), 3);
  EXPECT_TRUE(got.empty());
  // Current frames at 3.0, 3.2 (too soon), 3.5 and 4.0 s: three vectors, the last two from two frames.
  const nav::Pose2 away{0.6, 0.2, 0.3};
  for (const int64_t t : {3000000, 3200000, 3500000, 4000000}) bus.Publish("F1_OMNI_PANORAMA", lab.Panorama(away, t));
  HandleAll(bus);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(node.between_fused_frames(), 1);
  EXPECT_EQ(got[0].utime, 3000000);
  EXPECT_EQ(got[2].utime, 4000000);
  for (const auto& v : got) {
    ASSERT_TRUE(v.valid);
    EXPECT_LT(DirectionError(v, away), kSixtyDeg);
  }
  EXPECT_EQ(node.rejected_total(), 0);
}

// [view_fusion] with landmark sets: the home is fused from the last home_frames sets on the home
// channel, keeping the landmarks found again at the same place; one that moves between the sets
// (a walking person) is dropped, and a gap of more than home_frames intervals starts a new home.
TEST(HomingNode, HomeLandmarksKeepWhatPersists) {
  glue::Bus bus("memq://");
  HomingNode node(bus, Config("F2_", {{"homing", "input", "landmarks"},
                                      {"channels", "landmarks", "LANDMARKS_SIFT"},
                                      {"view_fusion", "home_frames", "3"},
                                      {"view_fusion", "home_interval_s", "1.0"},
                                      {"view_fusion", "min_fraction", "0.6"}}));
  const nav::PanoramaModel pm = Config("", {}).panorama;
  cv::RNG rng(5);
  cv::Mat static_desc(6, 128, CV_32F), moving_desc(1, 128, CV_32F);
  rng.fill(static_desc, cv::RNG::UNIFORM, 0.0f, 100.0f);
  rng.fill(moving_desc, cv::RNG::UNIFORM, 0.0f, 100.0f);
  auto set_at = [&](double moving_column) {
    nav::LandmarkSet s;
    s.method = nav::LandmarkMethod::kSift;
    s.width_px = pm.width_px;
    s.height_px = pm.height_px;
    for (int i = 0; i < 6; ++i) s.landmarks.push_back({60.0f + 100 * i, 50.0f, 1.0f, 8.0f, 0.0f});
    s.landmarks.push_back({static_cast<float>(moving_column), 40.0f, 1.0f, 8.0f, 0.0f});
    cv::vconcat(static_desc, moving_desc, s.descriptors);
    return s;
  };
  const int64_t s1 = 1000000;
  bus.Publish("F2_HOME_LANDMARKS", glue::LandmarkSetToMsg(set_at(30), pm, 0, "test"));
  HandleAll(bus);
  EXPECT_EQ(node.home_landmarks(), 7);  // one set: taken as it is
  bus.Publish("F2_HOME_LANDMARKS", glue::LandmarkSetToMsg(set_at(90), pm, s1, "test"));
  bus.Publish("F2_HOME_LANDMARKS", glue::LandmarkSetToMsg(set_at(150), pm, 2 * s1, "test"));
  HandleAll(bus);
  EXPECT_EQ(node.homes_set(), 3);
  EXPECT_EQ(node.home_landmarks(), 6);  // the moving one is in one set of three: dropped
  // Ten seconds later: a new home, from its first set alone.
  bus.Publish("F2_HOME_LANDMARKS", glue::LandmarkSetToMsg(set_at(400), pm, 12 * s1, "test"));
  HandleAll(bus);
  EXPECT_EQ(node.home_landmarks(), 7);
  EXPECT_EQ(node.rejected_total(), 0);
}

// fusion = median needs the frames: with landmark sets it is a config error, as are zero frames.
TEST(HomingConfig, ViewFusionValuesAreChecked) {
  EXPECT_THROW(Config("", {{"homing", "input", "landmarks"},
                           {"view_fusion", "fusion", "median"},
                           {"view_fusion", "home_frames", "5"}}),
               glue::ConfigError);
  EXPECT_NO_THROW(Config("", {{"homing", "input", "raw"}, {"view_fusion", "fusion", "median"}, {"view_fusion", "home_frames", "5"}}));
  EXPECT_THROW(Config("", {{"view_fusion", "current_frames", "0"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"view_fusion", "home_interval_s", "0"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"view_fusion", "min_fraction", "1.5"}}), glue::ConfigError);
  EXPECT_THROW(Config("", {{"view_fusion", "fusion", "mean"}}), glue::ConfigError);
}

// Every number of the shipped homing.ini and landmarks.ini made negative or NaN: each error names the
// file, the line and the key.
TEST(HomingConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(kShippedConfig,
                                                [](const glue::IniFile& ini) { HomingConfig::FromIni(ini, ""); }),
            0);
  EXPECT_GT(test_support::ExpectBadNumbersNamed(
                kLandmarksConfig, [](const glue::IniFile& ini) { LandmarksConfig::FromIni(ini, "", ""); }),
            0);
}

}  // namespace
}  // namespace snapnav::processes
