// The RatSLAM evaluation's simulated runs (tools/eval/ratslam/ratslam_eval): the camera run is the laser
// SLAM evaluation's run (same odometry, scans and truth) with frames added, in time order; an
// evaluation measures RatSLAM and dead reckoning on it and writes its files.
#include "ratslam_eval.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace snapnav::eval {
namespace {

SimCameraOptions ShortRun() {
  SimCameraOptions o;
  o.sim.scene = "indoor13";
  o.sim.laps = 0;
  o.sim.duration_s = 6;
  o.sim.seed = 3;
  return o;
}

struct Recorder : SimSensorSink {
  struct Odometry {
    int64_t utime;
    nav::Pose2 delta, truth;
    double dt_s;
  };
  std::vector<Odometry> odometry;
  std::vector<int64_t> scans, frames;
  std::vector<std::vector<float>> ranges;
  int64_t last_utime = 0;
  bool ordered = true;
  void Check(int64_t utime) {
    ordered = ordered && utime >= last_utime;
    last_utime = utime;
  }
  void OnOdometry(int64_t utime, const nav::Pose2& delta, double dt_s, const nav::Pose2& truth) override {
    Check(utime);
    odometry.push_back({utime, delta, truth, dt_s});
  }
  void OnScan(int64_t utime, const laser_scan_t& scan) override {
    Check(utime);
    scans.push_back(utime);
    ranges.push_back(scan.ranges_m);
  }
  void OnPanorama(int64_t utime, const cv::Mat& gray, const nav::Pose2&) override {
    Check(utime);
    EXPECT_EQ(gray.type(), CV_8UC1);
    EXPECT_EQ(gray.cols, 720);
    frames.push_back(utime);
  }
};

TEST(RatSlamEval, CameraRunIsTheLaserSlamRunWithFrames) {
  const SimCameraOptions options = ShortRun();
  Recorder r;
  const SimCameraRun run = RunSimulatedSensors(options, r);
  const SimulatedSlamLog slam = SimulateSlamLog(options.sim);
  EXPECT_TRUE(r.ordered);
  EXPECT_EQ(run.frames, 60);  // 10 Hz for 6 s
  EXPECT_EQ(static_cast<int64_t>(r.frames.size()), run.frames);
  EXPECT_EQ(run.scans, slam.log.scans);
  EXPECT_EQ(run.odometry, slam.log.odometry);
  EXPECT_NEAR(run.distance_m, slam.distance_m, 1e-12);
  // The same increments (the first only fixes the start) and the same true poses.
  std::vector<const SlamStep*> odo, scans;
  for (const SlamStep& s : slam.log.steps) (s.is_scan ? scans : odo).push_back(&s);
  ASSERT_EQ(r.odometry.size() + 1, odo.size());
  for (size_t i = 0; i < r.odometry.size(); ++i) {
    EXPECT_EQ(r.odometry[i].utime, odo[i + 1]->utime);
    EXPECT_EQ(r.odometry[i].delta.x_m, odo[i + 1]->odometry_delta.x_m);
    EXPECT_EQ(r.odometry[i].delta.theta_rad, odo[i + 1]->odometry_delta.theta_rad);
    EXPECT_EQ(r.odometry[i].truth.x_m, slam.reference.by_time[i + 1].pose.x_m);
  }
  ASSERT_EQ(r.ranges.size(), scans.size());
  for (size_t i = 0; i < scans.size(); ++i) {
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(r.ranges[i].data()), r.ranges[i].size() * sizeof(float)),
              scans[i]->ranges_key);
  }
}

TEST(RatSlamEval, EvaluationMeasuresBothAndWritesItsFiles) {
  RatSlamEvalOptions options;
  options.run = ShortRun();
  options.run.sim.duration_s = 20;
  const RatSlamEvaluation e = EvaluateRatSlam(options);
  EXPECT_EQ(e.truth.size(), 200u);
  EXPECT_EQ(e.ratslam.size(), e.truth.size());
  EXPECT_GT(e.templates, 5);
  EXPECT_EQ(e.experience_truth.size(), e.experiences.size());
  EXPECT_GT(e.image_ms_mean, 0);
  // 20 s of a route: both estimators stay near the truth.
  EXPECT_LT(e.ratslam_errors.ate_aligned.rmse_m, 0.3);
  EXPECT_LT(e.dead_reckoning_errors.ate_aligned.rmse_m, 0.3);
  const std::string dir = (std::filesystem::temp_directory_path() / "ratslam_eval_test").string();
  std::filesystem::remove_all(dir);
  WriteRatSlamEvaluation(e, options, dir);
  for (const char* f : {"summary.json", "experience_map.png", "errors.png", "trajectories.csv", "experiences.csv",
                        "links.csv"}) {
    EXPECT_GT(std::filesystem::file_size(std::filesystem::path(dir) / f), 100u) << f;
  }
  std::ifstream summary(std::filesystem::path(dir) / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  for (const char* key : {"\"ratslam_ate_rmse_m\"", "\"dead_reckoning_ate_rmse_m\"", "\"ratslam_loop_closures\"",
                          "\"ratslam_ms_per_odometry\"", "\"ratslam_ms_per_image\""}) {
    EXPECT_NE(text.find(key), std::string::npos) << key;
  }
  // Several configurations on one run: the same run, each its own result.
  nav::RatSlamOptions coarse;
  coarse.local_view.vt_match_threshold = 0.2;
  const auto both = EvaluateRatSlamVariants(options, {nav::RatSlamOptions{}, coarse});
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[0].templates, e.templates);
  EXPECT_LT(both[1].templates, both[0].templates);
  EXPECT_EQ(both[0].truth.back().x_m, both[1].truth.back().x_m);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace snapnav::eval
