// RatSLAM (libnav): pose-cell packet under path integration, normalisation and injection; local
// view templates and their shifts; experience-map relaxation; a loop closure of the whole system
// on a square route with drifting odometry. Synthetic inputs built inline.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include <opencv2/imgproc.hpp>

#include "snapnav/nav/ratslam/ratslam.hpp"
#include "snapnav/nav/trajectory.hpp"

namespace snapnav::nav {
namespace {

constexpr double kPi = 3.14159265358979323846;

double CircularDistance(double a, double b, double n) {
  const double d = std::fmod(std::abs(a - b), n);
  return std::min(d, n - d);
}

double Sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

PoseCellOptions CellOptions() {
  PoseCellOptions o;  // OpenRatSLAM's network: 21 x 21 x 36, 7/5 weight cubes
  o.pc_cell_x_size_m = 1.0;
  o.pc_vt_inject_energy = 0.15;  // OpenRatSLAM's default (snapnav's is tuned for milder drift)
  return o;
}

// ------------------------------------------------------------------------------- pose cells

TEST(RatSlamPoseCells, PacketStaysOneBoundedNormalisedPacket) {
  PoseCellNetwork net(CellOptions());
  net.SetSingleCell(10, 10, 0);
  for (int i = 0; i < 200; ++i) net.OnOdometry(0, 0, 0);
  EXPECT_NEAR(Sum(net.cells()), 1.0, 1e-9);
  for (double v : net.cells()) ASSERT_GE(v, 0.0);
  const PoseCellPeak p = net.peak();
  EXPECT_NEAR(p.x, 10, 1e-6);
  EXPECT_NEAR(p.y, 10, 1e-6);
  EXPECT_LT(CircularDistance(p.th, 0, 36), 1e-6);
  // One compact packet: every active cell within a few cells of the peak, and not smeared out.
  EXPECT_GT(p.max_activity, 0.01);
  EXPECT_LT(p.active_cells, 7 * 7 * 7);
  for (int th = 0; th < 36; ++th) {
    for (int y = 0; y < 21; ++y) {
      for (int x = 0; x < 21; ++x) {
        if (net.activity(x, y, th) > 0) {
          EXPECT_LE(CircularDistance(x, 10, 21), 3);
          EXPECT_LE(CircularDistance(y, 10, 21), 3);
          EXPECT_LE(CircularDistance(th, 0, 36), 3);
        }
      }
    }
  }
}

// The activity-weighted circular mean of each axis over the whole network [cells].
struct Centroid {
  double x, y, th;
};
Centroid CentroidOf(const PoseCellNetwork& net) {
  const int d = net.options().pc_dim_xy, t = net.options().pc_dim_th;
  double xs = 0, xc = 0, ys = 0, yc = 0, ts = 0, tc = 0;
  for (int th = 0; th < t; ++th) {
    for (int y = 0; y < d; ++y) {
      for (int x = 0; x < d; ++x) {
        const double a = net.activity(x, y, th);
        xs += a * std::sin(2 * kPi * x / d);
        xc += a * std::cos(2 * kPi * x / d);
        ys += a * std::sin(2 * kPi * y / d);
        yc += a * std::cos(2 * kPi * y / d);
        ts += a * std::sin(2 * kPi * th / t);
        tc += a * std::cos(2 * kPi * th / t);
      }
    }
  }
  auto wrap = [](double a, int n) { return std::fmod(a * n / (2 * kPi) + 2 * n, n); };
  return {wrap(std::atan2(xs, xc), d), wrap(std::atan2(ys, yc), d), wrap(std::atan2(ts, tc), t)};
}

// A settled packet (the attractor dynamics for a while without motion) at (x, y, th).
PoseCellNetwork SettledPacket(int x, int y, int th, PoseCellOptions o = CellOptions()) {
  PoseCellNetwork net(o);
  net.SetSingleCell(x, y, th);
  for (int i = 0; i < 20; ++i) net.OnOdometry(0, 0, 0);
  return net;
}

TEST(RatSlamPoseCells, PathIntegrationMovesThePacketByTheExpectedCellsAndWraps) {
  for (const int th : {0, 9, 18, 27, 4}) {  // headings 0, 90, 180, 270 and 40 degrees (36 layers)
    PoseCellNetwork net = SettledPacket(10, 10, th);
    const Centroid c0 = CentroidOf(net);
    // Each layer moves along its own heading: the packet's centroid moves along its heading.
    const double dir = th * 2 * kPi / 36;
    for (int i = 1; i <= 100; ++i) {
      net.PathIntegrate(0.25, 0, 0);  // 100 x 0.25 = 25 cells: past the 21-cell wrap-around
      if (i == 40 || i == 100) {
        const Centroid c = CentroidOf(net);
        // The layers of the packet around `th` move along slightly other headings (+-10 degrees
        // a layer), so the packet as a whole moves by the mean cosine: within 3 %.
        const double dist = 0.25 * i;
        EXPECT_LT(CircularDistance(c.x, c0.x + dist * std::cos(dir), 21), 0.03 * dist) << "th " << th << " step " << i;
        EXPECT_LT(CircularDistance(c.y, c0.y + dist * std::sin(dir), 21), 0.03 * dist) << "th " << th << " step " << i;
        EXPECT_LT(CircularDistance(c.th, th, 36), 1e-6);
        EXPECT_NEAR(Sum(net.cells()), 1.0, 1e-9) << "path integration moves activity, it keeps its total";
      }
    }
  }
  // Rotation by fractions of a cell, then back past the wrap-around.
  PoseCellNetwork net = SettledPacket(10, 10, 30);
  const double cell = 2 * kPi / 36;
  for (int i = 0; i < 40; ++i) net.PathIntegrate(0, 0, 0.05);  // 2 rad = 11.46 cells: 30 -> 5.46
  EXPECT_NEAR(CircularDistance(CentroidOf(net).th, 30 + 2.0 / cell, 36), 0, 0.02);
  for (int i = 0; i < 60; ++i) net.PathIntegrate(0, 0, -0.05);  // 3 rad back
  EXPECT_NEAR(CircularDistance(CentroidOf(net).th, 30 - 1.0 / cell, 36), 0, 0.02);
  EXPECT_NEAR(CentroidOf(net).x, 10, 1e-6);
}

TEST(RatSlamPoseCells, FullStepsMoveTheBestCellWithThePacketsLag) {
  // With the attractor dynamics every step, a packet moved by a fraction of a cell is partly
  // pulled back to the lattice: it lags, the more the smaller the steps (a property of the
  // discrete network, OpenRatSLAM's too). At 0.25 cells per step it keeps 90 % of the pace.
  for (const int th : {0, 9, 18, 27}) {
    PoseCellNetwork net = SettledPacket(10, 10, th);
    const double dir = th * 2 * kPi / 36;
    for (int i = 1; i <= 100; ++i) {
      net.OnOdometry(0.25, 0, 0);  // 1 m cells: 0.25 m = 0.25 cells
      if (i == 40 || i == 100) {
        const double dist = 0.25 * i;
        const double ex = 10 + dist * std::cos(dir), ey = 10 + dist * std::sin(dir);
        EXPECT_LT(CircularDistance(net.best_x(), ex, 21), 0.1 * dist) << "th " << th << " step " << i;
        EXPECT_LT(CircularDistance(net.best_y(), ey, 21), 0.1 * dist) << "th " << th << " step " << i;
        EXPECT_LT(CircularDistance(net.best_th(), th, 36), 0.2);
        EXPECT_NEAR(Sum(net.cells()), 1.0, 1e-9);
      }
    }
  }
  PoseCellNetwork net = SettledPacket(10, 10, 30);
  const double cell = 2 * kPi / 36;
  for (int i = 1; i <= 40; ++i) net.OnOdometry(0, 0, 0.05);
  EXPECT_LT(CircularDistance(net.best_th(), 30 + 2.0 / cell, 36), 0.1 * 2.0 / cell);
  EXPECT_NEAR(net.best_x(), 10, 0.05);
}

TEST(RatSlamPoseCells, ShiftsOfSeveralCellsPerStepAndSideways) {
  PoseCellNetwork net(CellOptions());
  net.SetSingleCell(5, 5, 0);
  net.PathIntegrate(3.5, 0, 0);  // three and a half cells in one step (OpenRatSLAM: < 1)
  net.FindBest();
  EXPECT_NEAR(net.best_x(), 8.5, 1e-6);
  net.PathIntegrate(2.0, kPi / 2, 0);  // sideways (left of the heading): +y at heading 0
  net.FindBest();
  EXPECT_NEAR(net.best_y(), 7, 1e-6);
  net.PathIntegrate(-4.0, 0, 0);  // backwards
  net.FindBest();
  EXPECT_NEAR(net.best_x(), 4.5, 1e-6);
  net.PathIntegrate(-6.0, 0, 0);  // backwards past the edge
  net.FindBest();
  EXPECT_NEAR(net.best_x(), 19.5, 1e-6);
}

// Learns templates 0..15 every half cell along x from (3, 3), is kidnapped to (3, 14), and drives
// the same way again seeing the same templates: their energy relocalises the packet.
TEST(RatSlamPoseCells, FamiliarViewsInjectEnergyAndRelocaliseThePacket) {
  PoseCellOptions o = CellOptions();
  o.pc_vt_skip_recent = 2;
  for (const double relative_rad : {0.0, kPi / 2}) {
    PoseCellNetwork net = SettledPacket(3, 3, 0, o);
    for (int i = 0; i < 32; ++i) {
      if (i % 2 == 0) net.OnViewTemplate(i / 2, 0);
      net.OnOdometry(0.25, 0, 0);
    }
    EXPECT_EQ(net.injections(), 0);
    for (int i = 16; i < 20; ++i) net.OnViewTemplate(i, 0);  // others, so 0..15 are not recent
    net.SetSingleCell(3, 14, 0);
    for (int i = 0; i < 20; ++i) net.OnOdometry(0, 0, 0);
    // Again, seeing the templates turned by relative_rad: the energy goes to the heading they
    // were learnt at plus that turn. (Turned, the robot moves along x sideways.)
    for (int i = 0; i < 32; ++i) {
      if (i % 2 == 0) net.OnViewTemplate(i / 2, relative_rad);
      net.OnOdometry(0.25, -relative_rad, 0);
    }
    EXPECT_EQ(net.injections(), 16);
    EXPECT_LT(CircularDistance(net.best_y(), 3, 21), 0.5) << "relocalised from y = 14";
    EXPECT_LT(CircularDistance(net.best_th(), relative_rad / (2 * kPi) * 36, 36), 0.5);
    EXPECT_LT(CircularDistance(net.best_x(), 11, 21), 1.5);
  }
}

TEST(RatSlamPoseCells, TemplateSeenOnAndOnInjectsLessAndLess) {
  PoseCellOptions o = CellOptions();
  o.pc_vt_skip_recent = 0;
  o.pc_vt_restore = 0;  // no recovery: the decay only grows
  PoseCellNetwork net(o);
  net.OnViewTemplate(0, 0);
  net.OnViewTemplate(1, 0);
  int before = net.injections();
  for (int i = 0; i < 10; ++i) net.OnViewTemplate(0, 0);
  // decay 1, 2, 3...: energy 0.15/30 (30 - e^(1.2 decay)) is positive only while e^(1.2 d) < 30.
  EXPECT_EQ(net.injections() - before, 2);
}

// ------------------------------------------------------------------------------- local view

// A textured 720x120 panorama, different for each seed: smooth random blobs.
cv::Mat TexturedPanorama(uint64_t seed) {
  cv::Mat noise(12, 72, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat pano;
  cv::resize(noise, pano, cv::Size(720, 120), 0, 0, cv::INTER_CUBIC);
  return pano;
}

// The panorama after a counter-clockwise turn of `columns` * 360/720 degrees: columns move up.
cv::Mat Turned(const cv::Mat& pano, int columns) {
  cv::Mat out(pano.size(), pano.type());
  const int w = pano.cols;
  for (int c = 0; c < w; ++c) pano.col(c).copyTo(out.col(((c + columns) % w + w) % w));
  return out;
}

TEST(RatSlamLocalView, NewViewMakesATemplateAndTheSameViewMatches) {
  LocalViewCells view(LocalViewOptions{});
  const cv::Mat a = TexturedPanorama(1), b = TexturedPanorama(2);
  ViewMatch m = view.OnImage(a);
  EXPECT_TRUE(m.new_template);
  EXPECT_EQ(m.template_id, 0);
  EXPECT_FALSE(m.difference.has_value());
  m = view.OnImage(a);
  EXPECT_FALSE(m.new_template);
  EXPECT_EQ(m.template_id, 0);
  ASSERT_TRUE(m.difference.has_value());
  EXPECT_NEAR(*m.difference, 0, 1e-6);
  m = view.OnImage(b);
  EXPECT_TRUE(m.new_template);
  EXPECT_EQ(m.template_id, 1);
  EXPECT_EQ(view.size(), 2);
  m = view.OnImage(a);
  EXPECT_EQ(m.template_id, 0);
  EXPECT_EQ(view.size(), 2);
}

TEST(RatSlamLocalView, RotatedPanoramaMatchesWithItsHeadingOffset) {
  LocalViewCells view(LocalViewOptions{});  // 72 columns: 10 px = 5 degrees each
  const cv::Mat a = TexturedPanorama(3);
  view.OnImage(a);
  for (const int template_columns : {1, 7, 20, 36, -5, -30}) {
    const ViewMatch m = view.OnImage(Turned(a, template_columns * 10));
    EXPECT_FALSE(m.new_template) << template_columns;
    EXPECT_EQ(m.template_id, 0);
    EXPECT_NEAR(*m.difference, 0, 1e-6);
    if (template_columns == 36) {  // half a turn: either sign
      EXPECT_NEAR(std::abs(m.relative_rad), kPi, 1e-9);
    } else {
      EXPECT_NEAR(m.relative_rad, template_columns * 5.0 * kPi / 180, 1e-9) << template_columns;
      EXPECT_EQ(m.shift_columns, template_columns);
    }
  }
  // A turn between template columns still matches, with a difference.
  const ViewMatch off = view.OnImage(Turned(a, 2));
  EXPECT_FALSE(off.new_template);
  EXPECT_GT(*off.difference, 0);
}

// A turn between template columns: the heading offset to a fraction of a column, and a smaller
// difference than at the nearest whole column (OpenRatSLAM's).
TEST(RatSlamLocalView, TurnsBetweenColumnsAreRefined) {
  const cv::Mat a = TexturedPanorama(6);
  LocalViewOptions whole;
  whole.vt_shift_subcolumn = false;
  whole.vt_match_threshold = 1;
  LocalViewOptions fine = whole;
  fine.vt_shift_subcolumn = true;
  LocalViewCells w(whole), f(fine);
  w.OnImage(a);
  f.OnImage(a);
  for (const int px : {3, 5, 14, -4, -27}) {  // 10 px per template column
    const cv::Mat turned = Turned(a, px);
    const ViewMatch mw = w.OnImage(turned), mf = f.OnImage(turned);
    const double truth = px * 0.5 * kPi / 180;  // 0.5 degree per pixel
    EXPECT_LT(std::abs(mf.relative_rad - truth), 0.6 * kPi / 180) << px;  // whole columns: up to 2.5
    EXPECT_LE(std::abs(mf.relative_rad - truth), std::abs(mw.relative_rad - truth) + 1e-12) << px;
    EXPECT_LT(*mf.difference, *mw.difference) << px;
    EXPECT_NEAR(mf.shift_columns + mf.shift_fraction, px / 10.0, 0.12) << px;
  }
}

TEST(RatSlamLocalView, ScanlineProfileAndLimitedShiftsOfANarrowCamera) {
  LocalViewOptions o;
  o.template_y_size = 1;  // the intensity profile
  o.vt_panoramic = false;
  o.vt_shift_match = 5;
  o.vt_patch_normalise = 0;
  o.vt_match_threshold = 0.01;
  LocalViewCells view(o);
  const cv::Mat a = TexturedPanorama(4);
  view.OnImage(a);
  ViewMatch m = view.OnImage(Turned(a, 30));  // 3 template columns: within the +-5 searched
  EXPECT_FALSE(m.new_template);
  EXPECT_EQ(m.shift_columns, 3);
  EXPECT_EQ(m.relative_rad, 0);  // not panoramic: no heading from the view
  EXPECT_NEAR(*m.difference, 0, 1e-6);
}

TEST(RatSlamLocalView, CropAndImageSizeAreChecked) {
  LocalViewCells view(LocalViewOptions{});
  EXPECT_THROW(view.OnImage(cv::Mat(120, 720, CV_8UC3)), std::invalid_argument);
  EXPECT_THROW(view.OnImage(cv::Mat(5, 720, CV_8UC1)), std::invalid_argument);  // fewer rows than the template
  LocalViewOptions o;
  o.image_crop_y_min_px = 20;
  o.image_crop_y_max_px = 200;
  LocalViewCells cropped(o);
  EXPECT_THROW(cropped.OnImage(cv::Mat(120, 720, CV_8UC1, cv::Scalar(7))), std::invalid_argument);
}

TEST(RatSlamLocalView, NormalisationsMakeTemplatesInsensitiveToBrightness) {
  const cv::Mat a = TexturedPanorama(5);
  cv::Mat darker;
  a.convertTo(darker, CV_8UC1, 0.7, 10);
  LocalViewOptions plain;
  plain.vt_patch_normalise = 0;
  LocalViewCells raw(plain);
  raw.OnImage(a);
  EXPECT_TRUE(raw.OnImage(darker).new_template);  // 30 % darker: a different place
  LocalViewCells patch(LocalViewOptions{});  // patch normalisation
  patch.OnImage(a);
  EXPECT_FALSE(patch.OnImage(darker).new_template);
  LocalViewOptions global = plain;
  global.vt_normalisation = 0.4;
  LocalViewCells normalised(global);
  normalised.OnImage(a);
  EXPECT_LT(*normalised.OnImage(darker).difference, 0.03);
}

// ------------------------------------------------------------------------------- options

TEST(RatSlamOptions, InvalidValuesAreRejected) {
  EXPECT_NO_THROW(RatSlamOptions{}.Validate());
  auto bad = [](auto edit) {
    RatSlamOptions o;
    edit(o);
    EXPECT_THROW(o.Validate(), std::invalid_argument);
    EXPECT_THROW(RatSlam(o, {}), std::invalid_argument);
  };
  bad([](RatSlamOptions& o) { o.pose_cells.pc_dim_xy = 2; });
  bad([](RatSlamOptions& o) { o.pose_cells.pc_w_e_dim = 6; });
  bad([](RatSlamOptions& o) { o.pose_cells.pc_w_i_dim = 41; });
  bad([](RatSlamOptions& o) { o.pose_cells.pc_w_e_var = 0; });
  bad([](RatSlamOptions& o) { o.pose_cells.pc_cell_x_size_m = -1; });
  bad([](RatSlamOptions& o) { o.pose_cells.pc_global_inhib = NAN; });
  bad([](RatSlamOptions& o) { o.pose_cells.exp_delta_pc_threshold = 0; });
  bad([](RatSlamOptions& o) { o.pose_cells.pc_cells_to_avg = 20; });
  bad([](RatSlamOptions& o) { o.local_view.template_x_size = 0; });
  bad([](RatSlamOptions& o) { o.local_view.vt_step_match = 0; });
  bad([](RatSlamOptions& o) { o.local_view.vt_match_threshold = -0.1; });
  bad([](RatSlamOptions& o) { o.local_view.image_crop_x_max_px = 0; });
  bad([](RatSlamOptions& o) {
    o.local_view.vt_panoramic = false;
    o.local_view.vt_shift_match = 40;
  });
  bad([](RatSlamOptions& o) { o.experience_map.exp_correction = 1.5; });
  bad([](RatSlamOptions& o) { o.experience_map.exp_loops = -1; });
  RatSlam slam(RatSlamOptions{}, {});
  EXPECT_THROW(slam.OnOdometry({NAN, 0, 0}, 0.02), std::invalid_argument);
  EXPECT_THROW(slam.OnOdometry({0.01, 0, 0}, -1), std::invalid_argument);
}

// ------------------------------------------------------------------------------- experience map

TEST(RatSlamExperienceMap, RelaxationAfterALoopClosurePullsTheEndBackToTheStart) {
  // A 4 m square, one experience per 0.5 m; the odometry turns 3 degrees too far at each corner.
  ExperienceMapOptions o;
  o.exp_loops = 100;
  ExperienceMap map(o, {0, 0, 0});
  const double step = 0.5, corner_error = 3 * kPi / 180;
  std::vector<Pose2> truth;
  map.CreateExperience(0);
  truth.push_back({0, 0, 0});
  Pose2 t{0, 0, 0};
  for (int side = 0; side < 4; ++side) {
    for (int i = 0; i < 8; ++i) {
      map.OnOdometry({step, 0, 0}, 1);
      t = t.Compose({step, 0, 0});
      if (side == 3 && i == 7) break;  // the last step ends at the start
      map.CreateExperience(0);
      truth.push_back(t);
    }
    if (side < 3) {
      map.OnOdometry({0, 0, kPi / 2 + corner_error}, 1);
      t = t.Compose({0, 0, kPi / 2});
    }
  }
  // Without the loop closure the robot is far from where it started.
  const Pose2 before = map.robot_pose();
  const double gap_before = std::hypot(before.x_m, before.y_m);
  EXPECT_GT(gap_before, 0.5);
  auto error = [&] {  // RMS position error of the experiences after the best SE(2) alignment
    std::vector<std::pair<Pose2, Pose2>> pairs;
    for (size_t i = 0; i < truth.size(); ++i) pairs.push_back({map.experiences()[i].pose, truth[i]});
    return ComputeAte(pairs, AlignSE2(pairs)).rmse_m;
  };
  map.Relax();  // relaxation alone changes nothing: the links agree with the chain
  const double error_before = error();
  // Back at the start: the view of experience 0 is recognised (relative heading 0: the true one).
  map.OnOdometry({0, 0, kPi / 2}, 1);
  ASSERT_TRUE(map.LinkTo(0, 0.0, true));
  map.SetExperience(0, 0.0);
  EXPECT_FALSE(map.LinkTo(static_cast<int>(truth.size()) - 1, 0.0, true)) << "already linked";
  map.Relax();
  const Experience& last = map.experiences().back();
  const Experience& first = map.experiences().front();
  const double gap_after = std::hypot(last.pose.x_m - first.pose.x_m, last.pose.y_m - first.pose.y_m);
  EXPECT_LT(gap_after, 0.75) << "the end is one 0.5 m step from the start";
  EXPECT_LT(error(), 0.6 * error_before) << "relaxation spreads the corner errors around the loop";
  EXPECT_EQ(map.links().back().loop_closure, true);
}

// ------------------------------------------------------------------------------- whole system

// Drives a 4 x 4 m square twice with odometry that drifts by 4 degrees per metre, seeing a place
// panorama that depends on the true position (one per 0.25 m of route) and is rotated by the true
// heading: the second lap closes the loop.
TEST(RatSlamSystem, SquareRouteWithDriftingOdometryClosesTheLoop) {
  RatSlamOptions o;
  o.pose_cells.pc_cell_x_size_m = 0.25;
  // OpenRatSLAM's injection: this odometry drifts 64 degrees a lap, far more than the simulator's
  // (the defaults are tuned for that, eval-ratslam).
  o.pose_cells.pc_vt_inject_energy = 0.15;
  RatSlam slam(o, {0, 0, 0});
  const double side = 4.0, speed = 0.4, dt = 0.02, drift_rad_per_m = 4 * kPi / 180;
  std::vector<cv::Mat> places;
  for (int i = 0; i < 64; ++i) places.push_back(TexturedPanorama(100 + i));
  Pose2 truth{0, 0, 0}, dead_reckoning{0, 0, 0};
  double travelled = 0;
  int step = 0, loop_closure_step = -1;
  double dr_error_at_end = 0, ratslam_error_at_end = 0;
  for (int lap = 0; lap < 2; ++lap) {
    for (int s = 0; s < 4; ++s) {
      for (int i = 0; i < static_cast<int>(side / (speed * dt)); ++i, ++step) {
        const Pose2 move{speed * dt, 0, 0};
        const Pose2 measured{speed * dt, 0, drift_rad_per_m * speed * dt};
        truth = truth.Compose(move);
        dead_reckoning = dead_reckoning.Compose(measured);
        travelled += speed * dt;
        slam.OnOdometry(measured, dt);
        if (step % 5 == 0) {  // 10 Hz views
          const int place = static_cast<int>(std::lround(std::fmod(travelled, 4 * side) / 0.25)) % 64;
          const int columns = static_cast<int>(std::lround(truth.theta_rad / (2 * kPi) * 720));
          slam.OnImage(Turned(places[static_cast<size_t>(place)], columns));
        }
        if (loop_closure_step < 0 && slam.loop_closures() > 0) loop_closure_step = step;
      }
      // Turn on the spot, left by 90 degrees (odometry sees it exactly).
      for (int i = 0; i < 25; ++i, ++step) {
        const Pose2 turn{0, 0, kPi / 2 / 25};
        truth = truth.Compose(turn);
        dead_reckoning = dead_reckoning.Compose(turn);
        slam.OnOdometry(turn, dt);
      }
    }
  }
  dr_error_at_end = std::hypot(dead_reckoning.x_m - truth.x_m, dead_reckoning.y_m - truth.y_m);
  const Pose2 p = slam.pose();
  ratslam_error_at_end = std::hypot(p.x_m - truth.x_m, p.y_m - truth.y_m);
  EXPECT_GT(slam.loop_closures(), 0);
  EXPECT_GT(loop_closure_step, 0);
  EXPECT_GT(slam.templates(), 40);
  EXPECT_LT(slam.templates(), 80) << "the second lap recognises the first lap's views";
  EXPECT_GT(dr_error_at_end, 1.0);
  EXPECT_LT(ratslam_error_at_end, 0.5 * dr_error_at_end)
      << "dead reckoning " << dr_error_at_end << " m, RatSLAM " << ratslam_error_at_end << " m";
  // Loop-closure links join experiences made a lap apart.
  int long_links = 0;
  for (const ExperienceLink& l : slam.experience_map().links()) {
    if (l.loop_closure && std::abs(l.to - l.from) > 20) ++long_links;
  }
  EXPECT_GT(long_links, 0);
}

TEST(RatSlamSystem, SameInputsGiveTheSameMap) {
  auto run = [] {
    RatSlamOptions o;
    RatSlam slam(o, {1, 2, 0.5});
    for (int i = 0; i < 300; ++i) {
      slam.OnOdometry({0.01, 0.001, 0.01}, 0.02);
      if (i % 5 == 0) slam.OnImage(TexturedPanorama(static_cast<uint64_t>(i / 25)));
    }
    return slam.pose();
  };
  const Pose2 a = run(), b = run();
  EXPECT_EQ(a.x_m, b.x_m);
  EXPECT_EQ(a.y_m, b.y_m);
  EXPECT_EQ(a.theta_rad, b.theta_rad);
}

TEST(RatSlamSystem, PoseStartsAtTheStartAndFollowsOdometryUntilTheFirstExperience) {
  RatSlam slam(RatSlamOptions{}, {1, 2, kPi / 2});
  EXPECT_FALSE(slam.experience_pose().has_value());
  slam.OnOdometry({0.5, 0, 0}, 1);
  EXPECT_NEAR(slam.pose().x_m, 1, 1e-12);
  EXPECT_NEAR(slam.pose().y_m, 2.5, 1e-12);
  slam.OnImage(TexturedPanorama(9));
  slam.OnOdometry({0.5, 0, 0}, 1);  // the first experience, where the robot is now
  ASSERT_TRUE(slam.experience_pose().has_value());
  EXPECT_NEAR(slam.experience_pose()->y_m, 3.0, 1e-12);
  EXPECT_EQ(slam.experience_map().experiences().size(), 1u);
}

}  // namespace
}  // namespace snapnav::nav
