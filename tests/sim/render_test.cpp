// Geometry of the simulated sensors on small scenes built inline.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::nav::sim {
namespace {

// A grey 10 x 10 m room with one red post (radius 5 cm) at `post`.
Scene RoomWithPost(const Eigen::Vector2d& post) {
  Scene s;
  s.name = "test";
  s.textures.push_back(MakeTexture("grey", cv::Mat(16, 16, CV_8UC3, cv::Scalar(128, 128, 128)), 1, 1));
  s.textures.push_back(MakeTexture("red", cv::Mat(16, 16, CV_8UC3, cv::Scalar(0, 0, 255)), 1, 1));
  s.walls = {{{-5, -5}, {5, -5}, 2.5, 0, 0, 0}, {{5, -5}, {5, 5}, 2.5, 0, 0, 0},
             {{5, 5}, {-5, 5}, 2.5, 0, 0, 0},   {{-5, 5}, {-5, -5}, 2.5, 0, 0, 0}};
  Cylinder c;
  c.center = post;
  c.radius_m = 0.05;
  c.height_m = 2.5;
  c.texture = 1;
  s.cylinders.push_back(c);
  return s;
}

// Centre of the red columns in `row`, as a circular mean around `near_col`.
double RedColumn(const cv::Mat& pano, int row, double near_col) {
  double sum = 0;
  int n = 0;
  for (int c = 0; c < pano.cols; ++c) {
    const cv::Vec3b px = pano.at<cv::Vec3b>(row, c);
    if (px[2] - 0.5 * (px[0] + px[1]) < 100) continue;
    double d = c - near_col;
    d -= std::round(d / pano.cols) * pano.cols;
    sum += d;
    ++n;
  }
  return n ? near_col + sum / n : -1e9;
}

TEST(OmniRender, LandmarkAppearsAtItsBearingColumn) {
  OmniCameraOptions o;
  o.panorama.width_px = 720;
  for (const double bearing_deg : {0.0, 37.0, 90.0, 163.0, -120.0}) {
    const double b = bearing_deg * M_PI / 180;
    const Scene scene = RoomWithPost({2.0 * std::cos(b + 0.3), 2.0 * std::sin(b + 0.3)});
    OmniRenderer r(scene, o);
    cv::Mat pano;
    r.RenderPanorama(Pose2{0, 0, 0.3}, {}, &pano);  // robot turned by 0.3 rad: bearing is relative
    const double expected = o.panorama.ColumnOfBearing(b);
    const double got = RedColumn(pano, pano.rows / 2, expected);
    const double diff = std::abs(got - expected);
    EXPECT_LE(diff, 1.0) << "bearing " << bearing_deg << " deg: column " << got << ", expected " << expected;
  }
}

TEST(OmniRender, RawImageShowsLandmarkAtMirrorPixel) {
  OmniCameraOptions o;
  const double b = 50 * M_PI / 180;
  const Scene scene = RoomWithPost({2.0 * std::cos(b), 2.0 * std::sin(b)});
  OmniRenderer r(scene, o);
  cv::Mat raw;
  r.RenderOmni(Pose2{0, 0, 0}, {}, &raw);
  ASSERT_EQ(raw.cols, 640);
  ASSERT_EQ(raw.rows, 480);
  const auto px = MirrorPixel(o.mirror, b, 0.0);
  ASSERT_TRUE(px.has_value());
  const cv::Vec3b v = raw.at<cv::Vec3b>(static_cast<int>(std::round(px->y())), static_cast<int>(std::round(px->x())));
  EXPECT_GT(v[2], 150) << "expected the red post at the mirror pixel";
  EXPECT_LT(v[0], 80);
  // The mirror of the other side shows grey wall.
  const auto opposite = MirrorPixel(o.mirror, b + M_PI, 0.0);
  const cv::Vec3b w = raw.at<cv::Vec3b>(static_cast<int>(opposite->y()), static_cast<int>(opposite->x()));
  EXPECT_LT(std::abs(w[2] - w[0]), 30);
  // Outside the ring: dark border.
  EXPECT_LT(raw.at<cv::Vec3b>(2, 2)[0], 40);
}

TEST(OmniGeometry, MirrorPixelAndDirectionAreInverse) {
  MirrorModel m;
  for (double b = -3.0; b < 3.1; b += 0.7) {
    for (double e = -0.6; e < 0.3; e += 0.2) {
      const auto px = MirrorPixel(m, b, e);
      ASSERT_TRUE(px);
      const auto dir = MirrorDirection(m, px->x(), px->y());
      ASSERT_TRUE(dir);
      EXPECT_NEAR((*dir)[0], b, 1e-9);
      EXPECT_NEAR((*dir)[1], e, 1e-9);
    }
  }
  EXPECT_FALSE(MirrorPixel(m, 0, 1.0));  // above the mirror's field of view
  EXPECT_FALSE(MirrorDirection(m, m.center_x_px, m.center_y_px));
}

TEST(Laser, WallAtKnownDistanceGivesExpectedRanges) {
  const Scene scene = RoomWithPost({-4, -4});
  LaserOptions l;
  l.range_noise_m = 0;
  l.mount_x_m = 0.1;
  l.range_max_m = 5.6;
  World world(scene, DriveOptions{}, l, 1);
  world.SetTruePose(Pose2{2.0, 0, 0});  // wall at x = 5: 2.9 m ahead of the sensor
  const auto ranges = world.Scan();
  ASSERT_EQ(ranges.size(), 681u);
  const int centre = 340;
  EXPECT_NEAR(ranges[centre], 2.9, 1e-4);
  const double a = l.angle_min_rad + 300 * l.AngleIncrement();
  EXPECT_NEAR(ranges[300], 2.9 / std::cos(a), 1e-4);
  // Beams towards the far corner (behind-left, > 5.6 m) read max range.
  world.SetTruePose(Pose2{4.0, 4.0, M_PI});
  const auto far = world.Scan();
  EXPECT_FLOAT_EQ(far[centre], 5.6f);  // 8.9 m to the west wall
}

TEST(Laser, LowObjectsAreBelowTheScanPlane) {
  Scene scene = RoomWithPost({-4, -4});
  scene.AddBox({1.0, 0}, 0.4, 0.4, 0, 0.2, 0);  // 20 cm high box in front
  LaserOptions l;
  l.range_noise_m = 0;
  l.mount_height_m = 0.3;
  World world(scene, DriveOptions{}, l, 1);
  EXPECT_NEAR(world.Scan()[340], 4.9, 1e-4);  // sees the wall, not the box
}

TEST(Laser, TheRealisticLaserHasARealLasersFaults) {
  EXPECT_FALSE(LaserFaultsPreset("clean").enabled);
  EXPECT_THROW(LaserFaultsPreset("lidar"), std::invalid_argument);
  LaserOptions clean;
  clean.range_noise_m = 0;
  LaserOptions real = clean;
  real.faults = LaserFaultsPreset("realistic");
  real.faults.dropout_probability = 0;
  real.faults.mixed_pixel_probability = 1;
  // Scale and bias: the wall 2.9 m ahead reads 2.9 x 1.006 + 0.012.
  {
    const Scene scene = RoomWithPost({-4, -4});
    World w(scene, DriveOptions{}, real, 1);
    w.SetTruePose(Pose2{2.0, 0, 0});
    EXPECT_NEAR(w.Scan()[340], 2.9 * real.faults.range_scale + real.faults.range_bias_m, 1e-4);
  }
  // A black post absorbs the beam (no return: max range); the grey wall does not.
  {
    Scene scene = RoomWithPost({2.0, 0.0});
    scene.textures.push_back(MakeTexture("black", cv::Mat(16, 16, CV_8UC3, cv::Scalar(10, 10, 10)), 1, 1));
    scene.cylinders[0].texture = static_cast<int>(scene.textures.size()) - 1;
    scene.cylinders[0].radius_m = 0.3;
    real.faults.dark_dropout_probability = 1;
    World w(scene, DriveOptions{}, real, 1);
    w.SetTruePose(Pose2{0, 0, 0});
    EXPECT_FLOAT_EQ(w.Scan()[340], static_cast<float>(real.range_max_m));
    World c(scene, DriveOptions{}, clean, 1);
    c.SetTruePose(Pose2{0, 0, 0});
    EXPECT_NEAR(c.Scan()[340], 2.0 - 0.3 - 0.1, 1e-3);
  }
  // Mixed pixels: at the post's edge (1.6 m in front of a wall 3 m behind it) some beam reads in
  // between, where the clean laser reads only the post or the wall.
  {
    const Scene scene = RoomWithPost({2.0, 0.0});
    real.faults.dark_dropout_probability = 0;
    World w(scene, DriveOptions{}, real, 1), c(scene, DriveOptions{}, clean, 1);
    w.SetTruePose(Pose2{0, 0, 0});
    c.SetTruePose(Pose2{0, 0, 0});
    const auto rw = w.Scan(), rc = c.Scan();
    auto between = [](const std::vector<float>& r) {
      int n = 0;
      for (int i = 300; i < 380; ++i) n += (r[i] > 2.1 && r[i] < 4.7);
      return n;
    };
    EXPECT_EQ(between(rc), 0);
    EXPECT_GE(between(rw), 1);
  }
  // People are legs: through the gap between a person's legs the laser sees the wall behind.
  {
    Scene scene = RoomWithPost({-4, -4});
    scene.people.count = 1;
    scene.people.area_min = {1.3, -0.01};  // walking along x: the legs side by side across the beams
    scene.people.area_max = {1.7, 0.01};
    scene.people.textures = {0};
    scene.people.radius_m = 0.22;
    DriveOptions d;
    World w(scene, d, real, 3), c(scene, d, clean, 3);
    w.SetTruePose(Pose2{0, 0, 0});
    c.SetTruePose(Pose2{0, 0, 0});
    const auto rw = w.Scan(), rc = c.Scan();
    int body = 0, legs = 0, gap = 0;
    for (int i = 300; i < 380; ++i) {
      body += rc[i] < 1.6;
      legs += rw[i] < 1.6;
      gap += rw[i] > 4 && rc[i] < 1.6;
    }
    EXPECT_GT(body, legs);
    EXPECT_GT(legs, 0);
    EXPECT_GT(gap, 0);
  }
  LaserFaults bad = LaserFaultsPreset("realistic");
  bad.leg_spacing_m = 0.05;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

TEST(Robot, HeadingDriftPerMetreAndOdometryDoNotSeeIt) {
  const Scene scene = RoomWithPost({-4, -4});
  DriveOptions d;
  d.linear_noise_frac = d.angular_noise_radps = 0;
  d.odometry_linear_noise_frac = d.odometry_angular_noise_frac = 0;
  d.heading_drift_deg_per_m = 0.3;
  World world(scene, d, LaserOptions{}, 1);
  world.SetTruePose(Pose2{-2, 0, 0});
  for (int i = 0; i < 100; ++i) world.Step(0.2, 0, 0.05);  // 1 m
  EXPECT_NEAR(world.true_pose().theta_rad * 180 / M_PI, 0.3, 1e-6);
  EXPECT_NEAR(world.distance_m(), 1.0, 1e-9);
  const auto odo = world.TakeOdometry();
  EXPECT_NEAR(odo.delta.x_m, 1.0, 1e-9);
  EXPECT_NEAR(odo.delta.theta_rad, 0.0, 1e-12);
  EXPECT_NEAR(odo.dt_s, 5.0, 1e-9);
}

TEST(Robot, WallsBlockTheRobot) {
  const Scene scene = RoomWithPost({-4, -4});
  World world(scene, DriveOptions{}, LaserOptions{}, 1);
  world.SetTruePose(Pose2{4.5, 0, 0});
  for (int i = 0; i < 100; ++i) world.Step(0.5, 0, 0.05);
  EXPECT_LT(world.true_pose().x_m, 5.0 - 0.19);
  EXPECT_GT(world.collisions(), 0);
}

TEST(RouteDriver, ReachesEveryWaypoint) {
  const Scene scene = RoomWithPost({-4, -4});
  World world(scene, DriveOptions{}, LaserOptions{}, 3);
  RouteDriver driver({{1, 0}, {1, 1}, {-1, 1}}, 0.3, 0.1, false);
  double min_d[3] = {9, 9, 9};
  const Eigen::Vector2d wp[3] = {{1, 0}, {1, 1}, {-1, 1}};
  for (int i = 0; i < 4000 && !driver.finished(); ++i) {
    const auto cmd = driver.Command(world.true_pose());
    world.Step(cmd.x(), cmd.y(), 0.01);
    for (int k = 0; k < 3; ++k) min_d[k] = std::min(min_d[k], (Eigen::Vector2d(world.true_pose().x_m, world.true_pose().y_m) - wp[k]).norm());
  }
  EXPECT_TRUE(driver.finished());
  for (double d : min_d) EXPECT_LT(d, 0.1);
}

// People walk around the robot: none comes closer than its radius plus the robot's, none stands
// frozen against it (the simulator once stopped them for good), and one the robot is teleported
// onto walks off it.
TEST(People, WalkAroundTheRobotAndNeverStandOnIt) {
  Scene scene = RoomWithPost({-4, -4});
  scene.people.count = 6;
  scene.people.textures = {1};
  scene.people.area_min = {-2, -2};
  scene.people.area_max = {2, 2};
  DriveOptions drive;
  World world(scene, drive, LaserOptions{}, 4);
  world.SetTruePose(Pose2{0, 0, 0});
  const double clearance = scene.people.radius_m + drive.robot_radius_m;
  std::vector<double> walked(6, 0.0);
  std::vector<Eigen::Vector2d> last;
  for (const auto& p : world.people()) last.push_back(p.center);
  double nearest = 1e9;
  for (int i = 0; i < 1200; ++i) {  // 120 s
    world.Step(0, 0, 0.1);
    for (size_t k = 0; k < 6; ++k) {
      const Eigen::Vector2d c = world.people()[k].center;
      nearest = std::min(nearest, c.norm());
      walked[k] += (c - last[k]).norm();
      last[k] = c;
    }
  }
  EXPECT_GT(nearest, clearance - 1e-9);
  EXPECT_LT(nearest, clearance + 0.2);  // they do pass close by
  for (double w : walked) EXPECT_GT(w, 0.9 * scene.people.speed_mps * 120);  // nobody stands still
  // Teleported onto a person: the person steps off within a second.
  const Eigen::Vector2d someone = world.people()[0].center;
  world.SetTruePose(Pose2{someone.x(), someone.y(), 0});
  for (int i = 0; i < 10; ++i) world.Step(0, 0, 0.1);
  for (const auto& p : world.people()) EXPECT_GT((p.center - someone).norm(), clearance - 1e-9);
}

TEST(Scene, BadElementsAreRejected) {
  Scene s = RoomWithPost({0, 0});
  s.walls.push_back({{0, 0}, {0, 0}, 2, 0, 0, 0});
  EXPECT_THROW(s.Validate(), std::invalid_argument);
  Scene t = RoomWithPost({0, 0});
  t.cylinders[0].texture = 7;
  EXPECT_THROW(t.Validate(), std::invalid_argument);
  EXPECT_THROW(MakeTexture("x", cv::Mat(), 1, 1), std::invalid_argument);
}

TEST(RealisticCamera, HousingReflectionVignettingPartsAndNoise) {
  const Scene scene = RoomWithPost({2.0, 0.5});
  OmniCameraOptions clean;
  OmniCameraOptions real = clean;
  real.optics = CameraOpticsPreset("realistic");
  // The fixed optics alone here (the auto-exposure, JPEG and motion blur: the tests below).
  real.optics.auto_exposure = false;
  real.optics.jpeg_quality = 0;
  EXPECT_FALSE(CameraOpticsPreset("clean").enabled);
  EXPECT_THROW(CameraOpticsPreset("fancy"), std::invalid_argument);
  OmniRenderer rc(scene, clean), rr(scene, real);
  cv::Mat a, b, b2;
  rc.RenderOmni({0, 0, 0}, {}, &a);
  rr.RenderOmni({0, 0, 0}, {}, &b);
  rr.RenderOmni({0, 0, 0}, {}, &b2);
  const MirrorModel& m = real.mirror;
  auto grey = [](const cv::Mat& img, int x, int y) {
    const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
    return (p[0] + p[1] + p[2]) / 3.0;
  };
  // The housing outside the rim (corner), darkened by the vignetting beyond the rim.
  EXPECT_NEAR(grey(b, 5, 5), real.optics.housing_grey * 0.2, 6.0);
  // The camera's reflection: dark in the middle.
  EXPECT_LT(grey(b, static_cast<int>(m.center_x_px), static_cast<int>(m.center_y_px)), 30);
  // A warm cast: red over blue on the grey walls.
  const cv::Vec3b wall = b.at<cv::Vec3b>(static_cast<int>(m.center_y_px - 0.9 * m.outer_radius_px), static_cast<int>(m.center_x_px) + 20);
  EXPECT_GT(wall[2], wall[0] + 10);
  // Vignetting: the clean image is brighter near the rim than the realistic one (apart from the cast).
  // (Forward, away from the window at 200 deg.)
  const int yr = static_cast<int>(m.center_y_px - 0.95 * m.outer_radius_px), xr = static_cast<int>(m.center_x_px) + 15;
  EXPECT_LT(b.at<cv::Vec3b>(yr, xr)[1], 0.8 * a.at<cv::Vec3b>(yr, xr)[1]);
  // Noise: two frames of the same pose differ, by about the read and shot noise.
  cv::Mat diff;
  cv::absdiff(b, b2, diff);
  const double mean_diff = cv::mean(diff)[1];
  EXPECT_GT(mean_diff, 1.0);
  EXPECT_LT(mean_diff, 8.0);
  // The struts: the parts' mask covers bearing 60 deg at 70 % of the radius, dark in the image.
  const cv::Mat parts = rr.PartsMask();
  const auto strut = MirrorPixel(m, 60 * M_PI / 180, m.elevation_inner_rad + 0.64 * (m.elevation_outer_rad - m.elevation_inner_rad));
  ASSERT_TRUE(strut.has_value());
  EXPECT_EQ(parts.at<uint8_t>(static_cast<int>(std::lround(strut->y())), static_cast<int>(std::lround(strut->x()))), 0);
  EXPECT_LT(grey(b, static_cast<int>(std::lround(strut->x())), static_cast<int>(std::lround(strut->y()))), 55);
  EXPECT_EQ(cv::countNonZero(rc.PartsMask()), static_cast<int>(rc.PartsMask().total()));
  // The calibration the frames carry is off by a few pixels; its ring starts at the reflection.
  const MirrorModel reported = real.ReportedMirror();
  EXPECT_NEAR(reported.center_x_px - m.center_x_px, real.optics.calibration_error_x_px, 1e-9);
  EXPECT_NEAR(reported.center_y_px - m.center_y_px, real.optics.calibration_error_y_px, 1e-9);
  EXPECT_NEAR(reported.outer_radius_px - m.outer_radius_px, real.optics.calibration_error_radius_px, 1e-9);
  EXPECT_GT(reported.inner_radius_px, real.optics.lens_radius_frac * m.outer_radius_px);
  EXPECT_EQ(clean.ReportedMirror().center_x_px, m.center_x_px);
  // The same seed, the same frames.
  OmniRenderer again(scene, real);
  cv::Mat c;
  again.RenderOmni({0, 0, 0}, {}, &c);
  EXPECT_EQ(cv::norm(b, c, cv::NORM_INF), 0);
}

TEST(RealisticCamera, TheWindowMovesWithTheRobotsHeading) {
  const Scene scene = RoomWithPost({2.0, 0.5});
  OmniCameraOptions real;
  real.optics = CameraOpticsPreset("realistic");
  real.optics.read_noise_grey = 0;
  real.optics.shot_noise = 0;
  real.optics.parts.clear();
  OmniRenderer r(scene, real);
  const MirrorModel& m = real.mirror;
  // The window at world bearing 200 deg, elevation 10 deg: seen at robot bearing 200 - heading.
  auto brightness_at = [&](double heading, double bearing_deg) {
    cv::Mat img;
    r.RenderOmni({0, 0, heading}, {}, &img);
    const auto px = MirrorPixel(m, bearing_deg * M_PI / 180, 10 * M_PI / 180);
    return cv::mean(img(cv::Rect(static_cast<int>(px->x()) - 2, static_cast<int>(px->y()) - 2, 5, 5)))[1];
  };
  const double heading = 0.5;
  const double inside = brightness_at(heading, real.optics.window_bearing_rad * 180 / M_PI - heading * 180 / M_PI);
  const double outside = brightness_at(heading, real.optics.window_bearing_rad * 180 / M_PI - heading * 180 / M_PI + 90);
  EXPECT_GT(inside, 1.5 * outside);
}

// The realistic camera without sensor noise, parts or window: only the part under test differs.
OmniCameraOptions QuietRealisticCamera() {
  OmniCameraOptions real;
  real.optics = CameraOpticsPreset("realistic");
  real.optics.read_noise_grey = 0;
  real.optics.shot_noise = 0;
  real.optics.parts.clear();
  real.optics.window_gain = 1.0;
  real.optics.jpeg_quality = 0;
  return real;
}

double Sharpness(const cv::Mat& image, const MirrorModel& m) {
  // Mean absolute Laplacian over the mirror's ring (between the reflection and the rim).
  cv::Mat grey, lap;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  cv::Laplacian(grey, lap, CV_32F);
  cv::Mat ring(image.size(), CV_8U, cv::Scalar(0));
  cv::circle(ring, {static_cast<int>(m.center_x_px), static_cast<int>(m.center_y_px)}, static_cast<int>(0.92 * m.outer_radius_px),
             cv::Scalar(255), -1);
  cv::circle(ring, {static_cast<int>(m.center_x_px), static_cast<int>(m.center_y_px)}, static_cast<int>(0.5 * m.outer_radius_px),
             cv::Scalar(0), -1);
  return cv::mean(cv::abs(lap), ring)[0];
}

TEST(RealisticCamera, AutoExposureDarkensTheImageWhenTheWindowIsInViewAndLags) {
  const Scene scene = RoomWithPost({2.0, 0.5});
  OmniCameraOptions dim = QuietRealisticCamera(), bright = QuietRealisticCamera();
  bright.optics.window_gain = 6.0;
  bright.optics.window_width_rad = 1.5;
  OmniRenderer rd(scene, dim), rb(scene, bright);
  cv::Mat a, b;
  rd.RenderOmni({0, 0, 0}, {}, &a);
  rb.RenderOmni({0, 0, 0}, {}, &b);
  // A settled first frame; the window lowers the gain, and the wall opposite it gets darker.
  EXPECT_GT(rd.exposure(), 1.0);
  EXPECT_LT(rb.exposure(), 0.9 * rd.exposure());
  const MirrorModel& m = dim.mirror;
  const double opposite = bright.optics.window_bearing_rad + M_PI;  // the robot at heading 0
  const auto px = MirrorPixel(m, opposite, 5 * M_PI / 180);
  ASSERT_TRUE(px.has_value());
  const cv::Rect patch(static_cast<int>(px->x()) - 3, static_cast<int>(px->y()) - 3, 7, 7);
  EXPECT_LT(cv::mean(b(patch))[1], 0.9 * cv::mean(a(patch))[1]);
  // The clean camera and a camera without auto-exposure keep gain 1.
  OmniCameraOptions fixed = QuietRealisticCamera();
  fixed.optics.auto_exposure = false;
  OmniRenderer rf(scene, fixed);
  rf.RenderOmni({0, 0, 0}, {}, &a);
  EXPECT_EQ(rf.exposure(), 1.0);
  // It lags: someone dark steps up to the robot, and the camera moves half the way (in log,
  // exposure_rate 0.5) from its gain to the new view's settled gain, not at once.
  Scene with_dark = scene;
  with_dark.textures.push_back(MakeTexture("dark", cv::Mat(16, 16, CV_8UC3, cv::Scalar(20, 20, 20)), 1, 1));
  Cylinder person;
  person.center = {0.45, 0};
  person.radius_m = 0.25;
  person.height_m = 1.8;
  person.texture = static_cast<int>(with_dark.textures.size()) - 1;
  OmniRenderer turning(with_dark, dim);
  turning.RenderOmni({0, 0, 0}, {}, &a);
  const double before = turning.exposure();
  turning.RenderOmni({0, 0, 0}, {person}, &a);
  const double after = turning.exposure();
  OmniRenderer fresh(with_dark, dim);
  fresh.RenderOmni({0, 0, 0}, {person}, &a);
  EXPECT_GT(fresh.exposure(), 1.05 * before);
  // Halfway in log between the previous gain and the new view's settled gain.
  EXPECT_NEAR(std::log(after), 0.5 * (std::log(before) + std::log(fresh.exposure())), 1e-6);
}

TEST(RealisticCamera, CompressesItsOwnFramesAsJpeg) {
  const Scene scene = RoomWithPost({2.0, 0.5});
  OmniCameraOptions raw = QuietRealisticCamera(), jpeg = QuietRealisticCamera();
  jpeg.optics.jpeg_quality = 60;
  OmniRenderer rr(scene, raw), rj(scene, jpeg);
  cv::Mat a, b, c;
  rr.RenderOmni({0, 0, 0.3}, {}, &a);
  rj.RenderOmni({0, 0, 0.3}, {}, &b);
  // Artefacts: small but not nothing.
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const double mean = cv::mean(diff)[1];
  EXPECT_GT(mean, 0.3);
  EXPECT_LT(mean, 6.0);
  // The camera's bytes, when asked for: a JPEG of the image before compression, which decodes to the frame.
  std::vector<uint8_t> bytes;
  OmniRenderer rj2(scene, jpeg);
  rj2.RenderOmni({0, 0, 0.3}, {}, &c, {}, &bytes);
  ASSERT_GT(bytes.size(), 1000u);
  EXPECT_EQ(bytes[0], 0xff);
  EXPECT_EQ(bytes[1], 0xd8);
  EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0);
  const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_COLOR);
  EXPECT_EQ(cv::norm(decoded, b, cv::NORM_INF), 0);
  // No compression: no bytes.
  rr.RenderOmni({0, 0, 0.3}, {}, &c, {}, &bytes);
  EXPECT_TRUE(bytes.empty());
}

TEST(RealisticCamera, MotionBlurGrowsWithTheTurnRateAndSpeed) {
  // Checkered walls and floor: edges everywhere for the blur to smear.
  Scene scene = RoomWithPost({2.0, 0.5});
  cv::Mat checker(64, 64, CV_8UC3);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) checker.at<cv::Vec3b>(y, x) = ((x / 8 + y / 8) % 2) ? cv::Vec3b(200, 200, 200) : cv::Vec3b(40, 40, 40);
  }
  scene.textures[0] = MakeTexture("checker", checker, 0.4, 0.4);
  scene.floor_texture = 0;
  const OmniCameraOptions real = QuietRealisticCamera();
  const MirrorModel& m = real.mirror;
  auto sharpness = [&](CameraMotion motion) {
    OmniRenderer r(scene, real);
    cv::Mat img;
    r.RenderOmni({0.1, -0.2, 0.3}, {}, &img, motion);
    return Sharpness(img, m);
  };
  const double still = sharpness({});
  const double slow_turn = sharpness({0, 0.3});
  const double fast_turn = sharpness({0, 1.5});
  const double driving = sharpness({0.5, 0});
  EXPECT_LT(slow_turn, still);
  EXPECT_LT(fast_turn, 0.8 * slow_turn);
  EXPECT_LT(driving, still);
  // No shutter time: no blur.
  OmniCameraOptions instant = real;
  instant.optics.exposure_time_s = 0;
  OmniRenderer r(scene, instant), s(scene, real);
  cv::Mat a, b;
  r.RenderOmni({0.1, -0.2, 0.3}, {}, &a, {0.5, 1.5});
  s.RenderOmni({0.1, -0.2, 0.3}, {}, &b);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
}

TEST(RealisticCamera, NewOpticsOptionsAreValidated) {
  for (auto change : std::vector<std::function<void(CameraOptics*)>>{
           [](CameraOptics* o) { o->exposure_target_grey = 0; }, [](CameraOptics* o) { o->exposure_rate = 0; },
           [](CameraOptics* o) { o->exposure_min = 1.5; }, [](CameraOptics* o) { o->exposure_max = 0.5; },
           [](CameraOptics* o) { o->jpeg_quality = 101; }, [](CameraOptics* o) { o->exposure_time_s = -0.01; }}) {
    CameraOptics o = CameraOpticsPreset("realistic");
    EXPECT_NO_THROW(o.Validate());
    change(&o);
    EXPECT_THROW(o.Validate(), std::invalid_argument);
  }
}

}  // namespace
}  // namespace snapnav::nav::sim
