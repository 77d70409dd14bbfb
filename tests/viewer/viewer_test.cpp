// The viewer: the picture of a scene checked by its pixels (trajectory colours in the top view,
// landmark marks and the homing direction on the panorama), and the node on memq:// turning
// messages into that scene; bad input is counted, never fatal.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "../support/config_errors.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/laser_slam_status_t.hpp"
#include "viewer_node.hpp"
#include "viewer_render.hpp"

namespace snapnav {
namespace {

using viewer::ChannelColour;
using viewer::ComputeLayout;
using viewer::RenderOptions;
using viewer::RenderScene;
using viewer::ViewerScene;

const std::string kShippedConfig = std::string(SNAPNAV_CONFIG_DIR) + "/viewer.ini";

int CountColour(const cv::Mat& img, const cv::Scalar& colour, const cv::Rect& roi) {
  cv::Mat mask;
  cv::inRange(img(roi), colour, colour, mask);
  return cv::countNonZero(mask);
}

double StdDev(const cv::Mat& img, const cv::Rect& roi) {
  cv::Mat grey;
  cv::cvtColor(img(roi), grey, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, sd;
  cv::meanStdDev(grey, mean, sd);
  return sd[0];
}

RenderOptions Options() {
  RenderOptions o;
  o.robot_pose_channels = {"POSE_LASER_SLAM", "POSE_GROUND_TRUTH"};
  return o;
}

// A square drive with a ground truth, two estimates with growing covariance, a map, a scan, a
// place cell, a textured panorama with SIFT marks and a homing vector.
ViewerScene RichScene() {
  ViewerScene s;
  s.truth_channel = "POSE_GROUND_TRUTH";
  s.first_utime = 1'000'000;
  for (const char* ch : {"POSE_GROUND_TRUTH", "POSE_DEAD_RECKONING", "POSE_LASER_SLAM"}) {
    viewer::Track& t = s.tracks[ch];
    const double drift = std::string(ch) == "POSE_DEAD_RECKONING" ? 0.15 : 0.0;
    for (int i = 0; i <= 200; ++i) {
      const double a = i / 200.0 * 2 * M_PI;
      viewer::PoseSample p;
      p.utime = s.first_utime + i * 100'000;
      p.pose = {2 * std::cos(a) + drift * i / 200.0, 2 * std::sin(a), a + M_PI / 2};
      if (std::string(ch) != "POSE_GROUND_TRUTH") p.covariance.diagonal() << 0.001 + 0.0004 * i, 0.001 + 0.0002 * i, 0.01;
      t.poses.push_back(p);
      t.latest = p;
      ++t.received;
    }
    s.latest_utime = t.latest.utime;
  }
  for (int i = 0; i < 400; ++i) {
    const double a = i / 400.0 * 2 * M_PI;
    s.map_points.emplace_back(static_cast<float>(3.5 * std::cos(a)), static_cast<float>(3.5 * std::sin(a)));
  }
  s.map_estimator = "laser_slam";
  viewer::ScanView scan;
  scan.utime = s.latest_utime;
  for (int i = 0; i < 100; ++i) {
    const double a = -2 + i * 0.04;
    scan.points.emplace_back(static_cast<float>(1.5 * std::cos(a)), static_cast<float>(1.5 * std::sin(a)));
  }
  s.scan = scan;
  s.matches.push_back({s.latest_utime, 7, 1.0, -1.0, 0.0, 0.02, 0.1});
  s.memory_cells = {{0.5f, 0.5f}, {-1.0f, 1.0f}};
  viewer::PanoramaView pano;
  pano.image = cv::Mat(120, 720, CV_8UC3);
  cv::randu(pano.image, 0, 255);
  pano.bearing_col0_rad = M_PI;
  pano.utime = s.latest_utime;
  pano.source = "OMNI_PANORAMA";
  s.panorama = pano;
  viewer::LandmarkMarks marks;
  marks.method = "sift";
  marks.panorama_width_px = 720;
  marks.panorama_height_px = 120;
  for (int i = 0; i < 12; ++i) {
    marks.bearings_rad.push_back(static_cast<float>(-M_PI + i * 0.5));
    marks.rows_px.push_back(static_cast<float>(10 + 8 * i));
  }
  s.landmarks["LANDMARKS_SIFT"] = marks;
  viewer::HomingView h;
  h.valid = true;
  h.direction_rad = 0.7;
  h.method = "hog";
  s.homing = h;
  s.channel_counts = {{"POSE_GROUND_TRUTH", 201}, {"OMNI_PANORAMA", 1}};
  return s;
}

TEST(ViewerRender, RichSceneShowsEveryPart) {
  const RenderOptions options = Options();
  const cv::Mat img = RenderScene(RichScene(), options);
  ASSERT_EQ(img.size(), options.size);
  const viewer::Layout layout = ComputeLayout(options.size);
  for (const char* ch : {"POSE_GROUND_TRUTH", "POSE_DEAD_RECKONING", "POSE_LASER_SLAM"}) {
    EXPECT_GT(CountColour(img, ChannelColour(ch), layout.map), 200) << ch;
    EXPECT_GT(CountColour(img, ChannelColour(ch), layout.panel), 10) << ch << " in the legend";
  }
  EXPECT_GT(CountColour(img, viewer::kMapColour, layout.map), 400);
  EXPECT_GT(CountColour(img, viewer::kScanColour, layout.map), 100);
  EXPECT_GT(CountColour(img, viewer::kHomingColour, layout.map), 50);
  EXPECT_GT(CountColour(img, viewer::kPlaceCellColour, layout.map), 20);
  // The panorama is there, with SIFT marks and the homing direction.
  EXPECT_GT(StdDev(img, layout.panorama), 30);
  EXPECT_GT(CountColour(img, viewer::LandmarkColour("sift"), layout.panorama), 100);
  EXPECT_GT(CountColour(img, cv::Scalar(255, 0, 255), layout.panorama), 50);
}

TEST(ViewerRender, LandmarkMarkAtItsBearingsColumn) {
  ViewerScene s;
  viewer::PanoramaView pano;
  pano.image = cv::Mat(120, 720, CV_8UC3, cv::Scalar(128, 128, 128));
  pano.bearing_col0_rad = M_PI;  // column 360 looks forward
  s.panorama = pano;
  viewer::LandmarkMarks marks;
  marks.method = "vline";
  marks.panorama_width_px = 720;
  marks.panorama_height_px = 120;
  marks.bearings_rad = {static_cast<float>(M_PI / 2)};  // left: column 180, a quarter of the width
  marks.rows_px = {60};
  s.landmarks["LANDMARKS_VLINE"] = marks;
  const RenderOptions options = Options();
  const cv::Mat img = RenderScene(s, options);
  const cv::Rect r = ComputeLayout(options.size).panorama;
  cv::Mat mask;
  cv::inRange(img(r), viewer::LandmarkColour("vline"), viewer::LandmarkColour("vline"), mask);
  const cv::Rect box = cv::boundingRect(mask);
  ASSERT_GT(box.width, 0);
  EXPECT_NEAR(box.x + box.width / 2.0, r.width / 4.0, 6);
}

TEST(ViewerRender, EmptySceneIsAPictureToo) {
  const RenderOptions options = Options();
  const cv::Mat img = RenderScene(ViewerScene{}, options);
  const viewer::Layout layout = ComputeLayout(options.size);
  EXPECT_EQ(CountColour(img, ChannelColour("POSE_DEAD_RECKONING"), layout.map), 0);
  EXPECT_LT(StdDev(img, layout.panorama), 10);  // the grey "waiting" box
  RenderOptions bad = options;
  bad.size = {300, 200};
  EXPECT_THROW(RenderScene(ViewerScene{}, bad), std::invalid_argument);
}

TEST(ViewerRender, TileViewsPutsEachRobotInItsCellWithItsTitle) {
  std::vector<cv::Mat> views;
  for (const auto& colour : {cv::Scalar(0, 0, 255), cv::Scalar(0, 255, 0), cv::Scalar(255, 0, 0)}) {
    views.emplace_back(1000, 1400, CV_8UC3, colour);
  }
  const cv::Mat out = viewer::TileViews(views, {"robot R1_", "robot R2_", "robot R3_"}, 2400);
  EXPECT_EQ(out.cols, 2400);  // one row of three 800-px cells
  EXPECT_EQ(out.rows, 30 + 571);
  // The middle of each cell has its view's colour.
  EXPECT_EQ(out.at<cv::Vec3b>(300, 400), cv::Vec3b(0, 0, 255));
  EXPECT_EQ(out.at<cv::Vec3b>(300, 1200), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(out.at<cv::Vec3b>(300, 2000), cv::Vec3b(255, 0, 0));
  // Five views: a grid of three columns, two rows.
  views.resize(5, views[0]);
  EXPECT_EQ(viewer::TileViews(views, std::vector<std::string>(5, "r"), 2400).rows, 2 * (30 + 571));
  EXPECT_THROW(viewer::TileViews(views, {"one title"}, 2400), std::invalid_argument);
  EXPECT_THROW(viewer::TileViews({}, {}, 2400), std::invalid_argument);
}

TEST(ViewerRender, ChannelColoursAreFixedAndPrefixed) {
  EXPECT_EQ(ChannelColour("POSE_GROUND_TRUTH"), cv::Scalar(0, 0, 0));
  EXPECT_EQ(ChannelColour("RUN2_POSE_LASER_SLAM"), ChannelColour("POSE_LASER_SLAM"));
  EXPECT_NE(ChannelColour("POSE_EKF"), ChannelColour("POSE_LASER_SLAM"));
  EXPECT_EQ(ChannelColour("POSE_SOMETHING"), ChannelColour("POSE_SOMETHING"));
}

// ---------------------------------------------------------------- the node on memq://

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

processes::ViewerConfig Config(const std::string& prefix) {
  return processes::ViewerConfig::FromIni(glue::IniFile::Parse(ReadText(kShippedConfig), kShippedConfig), prefix);
}

void HandleAll(glue::Bus& bus) {
  while (bus.HandleOnce(0)) {
  }
}

TEST(ViewerConfig, ShippedConfigLoadsAndUnknownKeysFail) {
  const auto c = Config("T_");
  EXPECT_EQ(c.pose_channels, "T_POSE_.*");
  EXPECT_EQ(c.truth_channel, "T_POSE_GROUND_TRUTH");
  EXPECT_EQ(c.render.robot_pose_channels.front(), "T_POSE_EKF");
  EXPECT_EQ(processes::RegexEscape("A.B*"), "A\\.B\\*");
  EXPECT_EQ(Config("RUN.1_").pose_channels, "RUN\\.1_POSE_.*");
  const std::string text = ReadText(kShippedConfig) + "\n[viewer]\nbogus = 1\n";
  EXPECT_THROW(processes::ViewerConfig::FromIni(glue::IniFile::Parse(text, "x.ini"), ""), glue::ConfigError);
  std::string small = ReadText(kShippedConfig);
  small.replace(small.find("width_px = 1400"), 15, "width_px = 100");
  EXPECT_THROW(processes::ViewerConfig::FromIni(glue::IniFile::Parse(small, "x.ini"), ""), glue::ConfigError);
}

TEST(ViewerNode, MessagesBecomeTheScene) {
  glue::Bus bus("memq://");
  processes::ViewerNode node(bus, Config("V_"));

  for (int i = 0; i < 50; ++i) {
    Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 0.01 * (i + 1);
    bus.Publish("V_POSE_DEAD_RECKONING",
                glue::ToPoseMsg(1'000'000 + i * 20'000, "dead_reckoning", "odom", {0.01 * i, 0, 0}, cov));
    bus.Publish("V_POSE_GROUND_TRUTH", glue::ToPoseMsg(1'000'000 + i * 20'000, "ground_truth", "map",
                                                       {0.01 * i, 0.001 * i, 0}, Eigen::Matrix3d::Zero()));
  }
  // Another prefix's poses are not ours.
  bus.Publish("OTHER_POSE_DEAD_RECKONING",
              glue::ToPoseMsg(1'000'000, "dead_reckoning", "odom", {5, 5, 0}, Eigen::Matrix3d::Zero()));
  point_map_t map;
  map.utime = 1'500'000;
  map.estimator = "laser_slam";
  map.resolution_m = 0.05f;
  map.npoints = 3;
  map.x_m = {0, 1, NAN};
  map.y_m = {0, 1, 2};
  bus.Publish("V_POINT_MAP", map);
  place_cell_match_t m{};
  m.utime = 1'500'000;
  m.cell_id = 4;
  m.x_m = 0.3;
  m.y_m = 0.2;
  bus.Publish("V_PLACE_CELL_MATCH", m);
  m.cell_id = -1;  // nothing matched: not drawn
  bus.Publish("V_PLACE_CELL_MATCH", m);
  landmark_set_t set{};
  set.utime = 1'500'000;
  set.method = landmark_set_t::SURF;
  set.panorama_width_px = 720;
  set.panorama_height_px = 120;
  set.nlandmarks = 2;
  set.bearings_rad = {0.1f, -0.2f};
  set.rows_px = {10, 20};
  set.strengths = {1, 1};
  set.scales_px = {2, 2};
  set.descriptor_length = 1;
  set.descriptors = {{0.5f}, {0.25f}};
  bus.Publish("V_LANDMARKS_SURF", set);
  homing_vector_t hv{};
  hv.utime = 1'500'000;
  hv.method = landmark_set_t::HOG;
  hv.alv_variant = "hog";
  hv.valid = true;
  hv.direction_rad = 1.0f;
  bus.Publish("V_HOMING_VECTOR", hv);
  laser_scan_t scan{};
  scan.utime = 1'980'000;
  scan.angle_min_rad = -1;
  scan.angle_increment_rad = 0.5f;
  scan.range_min_m = 0.1f;
  scan.range_max_m = 5;
  scan.nranges = 4;
  scan.ranges_m = {1, 5, 0.05f, 2};  // the max-range and the too-short readings are no returns
  bus.Publish("V_LASER_SCAN", scan);
  // A raw frame: noise inside a mirror ring, unwrapped into the configured panorama.
  cv::Mat raw(480, 640, CV_8UC1);
  cv::randu(raw, 0, 255);
  omni_frame_t frame = glue::ImageToFrame(raw, omni_frame_t::GRAY8);
  frame.utime = 1'900'000;
  bus.Publish("V_OMNI_FRAME", frame);
  // Garbage on a pose channel is counted.
  const char junk[] = "not a pose";
  bus.PublishRaw("V_POSE_JUNK", junk, sizeof(junk));
  HandleAll(bus);

  const ViewerScene& s = node.Scene();
  ASSERT_EQ(s.tracks.size(), 2u);
  const viewer::Track& dr = s.tracks.at("V_POSE_DEAD_RECKONING");
  EXPECT_EQ(dr.received, 50);
  EXPECT_NEAR(dr.latest.pose.x_m, 0.49, 1e-9);
  EXPECT_NEAR(dr.latest.covariance(0, 0), 0.5, 1e-9);
  // Thinned: of 1 cm steps only about every second one is kept (2 cm apart).
  EXPECT_LE(dr.poses.size(), 26u);
  EXPECT_GE(dr.poses.size(), 15u);
  EXPECT_EQ(s.truth_channel, "V_POSE_GROUND_TRUTH");
  EXPECT_EQ(s.map_points.size(), 2u);  // the NaN point is dropped
  ASSERT_EQ(s.matches.size(), 1u);
  EXPECT_EQ(s.matches[0].cell_id, 4);
  ASSERT_EQ(s.landmarks.count("V_LANDMARKS_SURF"), 1u);
  EXPECT_EQ(s.landmarks.at("V_LANDMARKS_SURF").method, "surf");
  ASSERT_TRUE(s.homing);
  EXPECT_TRUE(s.homing->valid);
  ASSERT_TRUE(s.scan);
  EXPECT_EQ(s.scan->points.size(), 2u);
  ASSERT_TRUE(s.panorama);
  EXPECT_EQ(s.panorama->image.cols, 720);
  EXPECT_EQ(s.panorama->image.rows, 120);
  EXPECT_EQ(s.first_utime, 1'000'000);
  EXPECT_EQ(s.latest_utime, 1'980'000);
  EXPECT_EQ(s.rejected, 1);
  EXPECT_EQ(bus.stats().at("V_POSE_JUNK").decode_errors, 1u);

  // A panorama channel, once seen, is preferred over raw frames.
  cv::Mat pano(120, 360, CV_8UC3, cv::Scalar(10, 20, 30));
  omni_frame_t pf = glue::ImageToFrame(pano, omni_frame_t::RGB8);
  pf.kind = omni_frame_t::PANORAMA;
  pf.utime = 2'000'000;
  pf.bearing_col0_rad = static_cast<float>(M_PI);
  bus.Publish("V_OMNI_PANORAMA", pf);
  frame.utime = 2'100'000;
  bus.Publish("V_OMNI_FRAME", frame);
  HandleAll(bus);
  EXPECT_EQ(node.Scene().panorama->image.cols, 360);
  EXPECT_EQ(node.Scene().panorama->source, "V_OMNI_PANORAMA");

  // The picture shows both trajectories.
  const cv::Mat img = node.Render();
  const viewer::Layout layout = ComputeLayout(img.size());
  EXPECT_GT(CountColour(img, ChannelColour("V_POSE_DEAD_RECKONING"), layout.map), 20);
  EXPECT_GT(CountColour(img, ChannelColour("V_POSE_GROUND_TRUTH"), layout.map), 20);
}

// An occupancy grid (laser-slam's LASER_SLAM_GRID): accepted into the scene, drawn under the
// trajectory (its occupied colour in the plot, the track's colour over it); malformed ones are
// refused with their reason and counted, the last good one stays.
TEST(ViewerNode, OccupancyGridIsDrawnUnderTheTrajectory) {
  glue::Bus bus("memq://");
  processes::ViewerNode node(bus, Config("G_"));
  occupancy_grid_t g{};
  g.utime = 1'000'000;
  g.frame = "map";
  g.source = "laser_slam";
  g.resolution_m = 0.1f;
  g.origin_x_m = -1;
  g.origin_y_m = -1;
  g.width = 60;
  g.height = 40;
  g.ncells = g.width * g.height;
  g.cells.assign(static_cast<size_t>(g.ncells), -1);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const bool wall = x == 5 || x == 55 || y == 5 || y == 35;
      const bool inside = x > 5 && x < 55 && y > 5 && y < 35;
      if (wall && x >= 5 && x <= 55 && y >= 5 && y <= 35) g.cells[static_cast<size_t>(y * g.width + x)] = 100;
      else if (inside) g.cells[static_cast<size_t>(y * g.width + x)] = 0;
    }
  }
  bus.Publish("G_LASER_SLAM_GRID", g);
  for (int i = 0; i < 20; ++i) {
    bus.Publish("G_POSE_LASER_SLAM", glue::ToPoseMsg(1'000'000 + i * 100'000, "laser_slam", "map", {0.5 + 0.15 * i, 1.5, 0},
                                                     Eigen::Matrix3d::Zero()));
  }
  occupancy_grid_t bad = g;
  bad.ncells = 7;
  bad.cells.resize(7);
  bus.Publish("G_LASER_SLAM_GRID", bad);
  bad = g;
  bad.resolution_m = NAN;
  bus.Publish("G_LASER_SLAM_GRID", bad);
  HandleAll(bus);
  const ViewerScene& s = node.Scene();
  ASSERT_TRUE(s.grid);
  EXPECT_EQ(s.grid->width, 60);
  EXPECT_EQ(s.grid->source, "laser_slam");
  EXPECT_TRUE(s.grid->any_known);
  EXPECT_NEAR(s.grid->known_x0, -0.5, 1e-6);  // cell 5's corner
  EXPECT_NEAR(s.grid->known_x1, 4.6, 1e-6);   // cell 55's far corner
  EXPECT_EQ(node.rejected().at("bad grid size"), 1);
  EXPECT_EQ(node.rejected().at("bad resolution"), 1);
  const cv::Mat img = node.Render();
  const viewer::Layout layout = ComputeLayout(img.size());
  EXPECT_GT(CountColour(img, viewer::kGridOccupiedColour, layout.map), 200);
  EXPECT_GT(CountColour(img, ChannelColour("G_POSE_LASER_SLAM"), layout.map), 20);  // the track over the grid
  EXPECT_GT(CountColour(img, cv::Scalar(232, 232, 232), layout.map), 10000);       // free cells
}

// Laser SLAM's graph back end announces a correction on its status (`corrected`): the viewer does not
// join its trail across the jump (the line from where the pose was to where it landed) and rings
// where it landed. The same poses without the announcement draw that line.
TEST(ViewerNode, ALaserSlamCorrectionBreaksItsTrailAtTheJump) {
  const auto run = [](bool announce, int64_t* jumps) {
    glue::Bus bus("memq://");
    processes::ViewerNode node(bus, Config("J_"));
    laser_slam_status_t early{};
    early.utime = 500'000;
    early.corrected = true;  // before any pose: no trail to break
    early.correction_utime = 500'000;
    bus.Publish("J_LASER_SLAM_STATUS", early);
    HandleAll(bus);
    for (int i = 0; i < 40; ++i) {
      const int64_t t = 1'000'000 + i * 100'000;
      const double y = i < 20 ? 0.0 : 2.0;  // the correction at scan 20 moves the pose 2 m across
      bus.Publish("J_POSE_LASER_SLAM", glue::ToPoseMsg(t, "laser_slam", "map", {0.1 * i, y, 0}, Eigen::Matrix3d::Zero()));
      laser_slam_status_t st{};
      st.utime = t;
      st.corrected = announce && i == 20;
      st.correction_utime = announce && i >= 20 ? 1'000'000 + 20 * 100'000 : 0;
      bus.Publish("J_LASER_SLAM_STATUS", st);
      if (i == 21 && announce) {
        st.corrected = true;  // the same correction again: one jump
        bus.Publish("J_LASER_SLAM_STATUS", st);
      }
      HandleAll(bus);
    }
    *jumps = static_cast<int64_t>(node.Scene().tracks.at("J_POSE_LASER_SLAM").jumps.size());
    return node.Render();
  };
  int64_t announced_jumps = -1, silent_jumps = -1;
  const cv::Mat broken = run(true, &announced_jumps);
  const cv::Mat joined = run(false, &silent_jumps);
  EXPECT_EQ(announced_jumps, 1);
  EXPECT_EQ(silent_jumps, 0);
  const viewer::Layout layout = ComputeLayout(broken.size());
  const cv::Scalar colour = ChannelColour("J_POSE_LASER_SLAM");
  cv::Mat in_broken, in_joined;
  cv::inRange(broken(layout.map), colour, colour, in_broken);
  cv::inRange(joined(layout.map), colour, colour, in_joined);
  const int only_joined = cv::countNonZero(in_joined & ~in_broken);  // the line across the jump
  const int only_broken = cv::countNonZero(in_broken & ~in_joined);  // the ring where it landed
  EXPECT_GT(only_joined, 100) << "the line across the 2 m jump is not drawn";
  EXPECT_GT(only_broken, 10) << "a ring marks where the pose landed";
  EXPECT_GT(cv::countNonZero(in_broken), 400) << "both stretches of the trail are drawn";
}

// The correction's table (pose_correction_t) redraws the trail where the graph now puts it: the
// poses before the correction move 2 m across onto the line of the later ones, the jump is joined;
// the trail's poses as published are kept (a later table applies to them again). A table of
// another pose channel changes nothing; a malformed one is refused and counted.
TEST(ViewerNode, ALaserSlamCorrectionTableRedrawsItsTrail) {
  glue::Bus bus("memq://");
  processes::ViewerNode node(bus, Config("K_"));
  for (int i = 0; i < 40; ++i) {
    const int64_t t = 1'000'000 + i * 100'000;
    const double y = i < 20 ? 0.0 : 2.0;
    bus.Publish("K_POSE_LASER_SLAM", glue::ToPoseMsg(t, "laser_slam", "map", {0.1 * i, y, 0}, Eigen::Matrix3d::Zero()));
    laser_slam_status_t st{};
    st.utime = t;
    st.corrected = i == 20;
    st.correction_utime = i >= 20 ? 3'000'000 : 0;
    bus.Publish("K_LASER_SLAM_STATUS", st);
    HandleAll(bus);
  }
  const viewer::Track& track = node.Scene().tracks.at("K_POSE_LASER_SLAM");
  ASSERT_EQ(track.jumps.size(), 1u);
  const nav::PoseCorrectionTable table = {{1'000'000, {0, 2, 0}}, {3'000'000, {}}};
  bus.Publish("K_LASER_SLAM_CORRECTION", glue::ToPoseCorrectionMsg(3'000'000, "OTHER_POSE", 1, {{0, {5, 5, 1}}}));
  pose_correction_t broken = glue::ToPoseCorrectionMsg(3'000'000, "K_POSE_LASER_SLAM", 1, table);
  broken.from_utime = {3'000'000, 1'000'000};  // out of order
  bus.Publish("K_LASER_SLAM_CORRECTION", broken);
  HandleAll(bus);
  EXPECT_EQ(track.poses.front().pose.y_m, 0.0);
  EXPECT_EQ(node.rejected_total(), 1);
  bus.Publish("K_LASER_SLAM_CORRECTION", glue::ToPoseCorrectionMsg(3'000'000, "K_POSE_LASER_SLAM", 1, table));
  HandleAll(bus);
  EXPECT_TRUE(track.jumps.empty());
  for (const viewer::PoseSample& p : track.poses) {
    EXPECT_NEAR(p.pose.y_m, 2.0, 1e-12) << p.utime;
    EXPECT_EQ(p.published.y_m, p.utime < 3'000'000 ? 0.0 : 2.0) << p.utime;
  }
  EXPECT_NEAR(track.latest.pose.y_m, 2.0, 1e-12);
  // laser-slam publishes a correction's table before its status: the status then announces a jump
  // the table has joined already.
  laser_slam_status_t late{};
  late.utime = 3'000'000;
  late.corrected = true;
  late.correction_utime = 3'000'000;
  bus.Publish("K_LASER_SLAM_STATUS", late);
  HandleAll(bus);
  EXPECT_TRUE(track.jumps.empty());
  // A pose published after the table: drawn as the table puts it (the current range: unchanged).
  bus.Publish("K_POSE_LASER_SLAM", glue::ToPoseMsg(5'100'000, "laser_slam", "map", {4.1, 2.0, 0}, Eigen::Matrix3d::Zero()));
  HandleAll(bus);
  EXPECT_NEAR(node.Scene().tracks.at("K_POSE_LASER_SLAM").latest.pose.y_m, 2.0, 1e-12);
}

TEST(ViewerNode, BadFramesAreCountedAndTracksStayBounded) {
  glue::Bus bus("memq://");
  processes::ViewerConfig config = Config("");
  config.max_poses_per_channel = 100;
  config.trajectory_min_step_m = 0;
  processes::ViewerNode node(bus, config);
  omni_frame_t bad{};
  bad.kind = omni_frame_t::RAW_OMNI;
  bad.encoding = omni_frame_t::JPEG;
  bad.width = 640;
  bad.height = 480;
  bad.data_size = 4;
  bad.data = {1, 2, 3, 4};
  bad.utime = 5;
  bus.Publish("OMNI_FRAME", bad);
  for (int i = 0; i < 1000; ++i) {
    bus.Publish("POSE_X", glue::ToPoseMsg(1'000'000 + i * 1000, "x", "map", {0.1 * i, 0, 0}, Eigen::Matrix3d::Zero()));
  }
  pose_t nan_pose = glue::ToPoseMsg(3'000'000, "x", "map", {NAN, 0, 0}, Eigen::Matrix3d::Zero());
  bus.Publish("POSE_X", nan_pose);
  HandleAll(bus);
  const ViewerScene& s = node.Scene();
  EXPECT_FALSE(s.panorama);
  EXPECT_EQ(node.rejected_total(), 2);  // the undecodable frame and the NaN pose
  const viewer::Track& t = s.tracks.at("POSE_X");
  EXPECT_LE(t.poses.size(), 100u);
  EXPECT_GE(t.poses.size(), 50u);
  EXPECT_NEAR(t.poses.back().pose.x_m, 99.9, 1e-9);
  EXPECT_NEAR(t.latest.pose.x_m, 99.9, 1e-9);
  EXPECT_NO_THROW(node.Render());
}

// Every number of the shipped viewer.ini made negative or NaN: each error names the file, the line and
// the key.
TEST(ViewerConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(
                kShippedConfig, [](const glue::IniFile& ini) { processes::ViewerConfig::FromIni(ini, ""); }),
            0);
}

}  // namespace
}  // namespace snapnav
