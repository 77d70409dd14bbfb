// Laser SLAM in the simulator with ground truth (tools/eval/slam/slam_sim): the simulated log is
// what eval-slam reads from a recorded one, and on a long corridor route laser SLAM stays on
// the truth where dead reckoning drifts.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim_node.hpp"
#include "slam_sim.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav::eval {
namespace {

// The simulator as the sim process and slam-sim-eval configure it (config/sim.ini).
SimSlamOptions ShippedOptions() {
  return SimSlamOptions::FromSimConfig(
      processes::SimConfig::FromIni(glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), ""));
}

const std::vector<Eigen::Vector2d>& LastScan(const SlamLog& log) {
  for (auto it = log.steps.rbegin(); it != log.steps.rend(); ++it) {
    if (it->is_scan) return it->points;
  }
  throw std::runtime_error("no scan");
}

std::string TempLogPath(const std::string& name) {
  const char* base = std::getenv("TMPDIR");
  return (std::filesystem::path(base && *base ? base : "/tmp") / (name + "_" + std::to_string(::getpid()) + ".lcmlog"))
      .string();
}

TEST(SimulateSlamLog, GivesWhatEvalSlamReadsFromTheWrittenLog) {
  SimSlamOptions options = ShippedOptions();
  options.scene = "corridor";
  options.laps = 0;
  options.duration_s = 20;
  options.log_path = TempLogPath("slam_sim_test");
  const SimulatedSlamLog sim = SimulateSlamLog(options);
  // 20 s: scans at 10 Hz, odometry (and ground truth) at 50 Hz, sensors at t = 0 included.
  EXPECT_EQ(sim.log.scans, 200);
  EXPECT_EQ(sim.log.odometry, 1000);
  EXPECT_EQ(sim.log.beams, options.laser.beams);
  EXPECT_NEAR(sim.duration_s, 20.0, 1e-9);
  EXPECT_GT(sim.distance_m, 4.0);  // 0.3 m/s, turns included
  EXPECT_EQ(sim.collisions, 0);
  ASSERT_EQ(sim.reference.by_time.size(), 1000u);
  // The truth in the start frame: the estimators' frame.
  const nav::Pose2& first = sim.reference.by_time.front().pose;
  EXPECT_NEAR(std::hypot(first.x_m, first.y_m) + std::abs(first.theta_rad), 0.0, 1e-12);
  EXPECT_NEAR(sim.start.x_m, 1.0, 1e-12);  // corridor.scene: start 1 8 -90
  EXPECT_NEAR(sim.start.y_m, 8.0, 1e-12);
  EXPECT_EQ(sim.log_events, 200 + 2 * 1000);

  // The written log, read as eval-slam reads it, holds the same steps and gives the same run.
  const SlamLog read = LoadSlamLog(options.log_path, false);
  std::filesystem::remove(options.log_path);
  ASSERT_EQ(read.steps.size(), sim.log.steps.size());
  EXPECT_EQ(read.scans, sim.log.scans);
  EXPECT_EQ(read.odometry, sim.log.odometry);
  EXPECT_EQ(read.events, sim.log.events);
  EXPECT_EQ(read.rejected, 0);
  for (size_t i = 0; i < read.steps.size(); ++i) {
    const SlamStep &a = read.steps[i], &b = sim.log.steps[i];
    ASSERT_EQ(a.is_scan, b.is_scan) << i;
    ASSERT_EQ(a.utime, b.utime) << i;
    ASSERT_EQ(a.points, b.points) << i;
    ASSERT_EQ(a.ranges_key, b.ranges_key) << i;
    ASSERT_EQ(a.odometry_delta.x_m, b.odometry_delta.x_m) << i;
    ASSERT_EQ(a.odometry_delta.theta_rad, b.odometry_delta.theta_rad) << i;
  }
  const SlamRun from_file = RunSlam(read, {});
  const SlamRun in_memory = RunSlam(sim.log, {});
  ASSERT_EQ(from_file.slam.size(), 200u);
  EXPECT_EQ(from_file.slam.back().x_m, in_memory.slam.back().x_m);
  EXPECT_EQ(from_file.slam.back().y_m, in_memory.slam.back().y_m);

  // Same seed, same log; another seed, other noise.
  options.log_path.clear();
  ASSERT_FALSE(LastScan(sim.log).empty());
  EXPECT_EQ(LastScan(SimulateSlamLog(options).log), LastScan(sim.log));
  options.seed += 1;
  EXPECT_NE(LastScan(SimulateSlamLog(options).log), LastScan(sim.log));
}

TEST(SimulateSlamLog, RejectsBadOptions) {
  SimSlamOptions options;
  options.laps = 0;
  options.duration_s = 0;
  EXPECT_THROW(options.Validate(), std::invalid_argument);  // no stop condition
  options.laps = 1;
  options.laser_rate_hz = 30;  // does not divide 100 Hz
  EXPECT_THROW(options.Validate(), std::invalid_argument);
  options.laser_rate_hz = 10;
  options.route_speed_mps = 0;
  EXPECT_THROW(SimulateSlamLog(options), std::invalid_argument);
  options.route_speed_mps = 0.3;
  options.scene = "no_such_scene";
  EXPECT_THROW(SimulateSlamLog(options), std::runtime_error);
}

// Two laps of the corridor route (config/scenes/corridor.scene: a 30 m corridor and its two
// 8 m wings, about 175 m) with the shipped simulator noise: odometry noise 2 % and a heading
// drift of 0.3 deg/m that odometry does not see.
TEST(CorridorLaserSlam, TwoLapsStayOnTheTruthWhereDeadReckoningDrifts) {
  SimSlamOptions options = ShippedOptions();
  options.scene = "corridor";
  options.laps = 2;
  const SimulatedSlamLog sim = SimulateSlamLog(options);
  const SimSlamEvaluation e = EvaluateSimulatedSlam(sim, {}, 1.0);
  const TrajectoryErrors &slam = e.laser_slam, &dr = e.dead_reckoning;
  std::cout << "corridor, " << sim.laps << " laps, " << sim.distance_m << " m, " << sim.log.scans << " scans, "
            << e.run.ms_per_scan() << " ms/scan, map " << e.run.map.size() << " points\n"
            << "  laser slam:     ATE " << slam.ate.rmse_m << " m (max " << slam.ate.max_m << ", aligned "
            << slam.ate_aligned.rmse_m << "), RPE/1 m " << slam.rpe.translation_rmse_m << " m "
            << slam.rpe.rotation_rmse_deg << " deg (max " << slam.rpe.translation_max_m << " m "
            << slam.rpe.rotation_max_deg << " deg)\n"
            << "  dead reckoning: ATE " << dr.ate.rmse_m << " m (max " << dr.ate.max_m << ", aligned "
            << dr.ate_aligned.rmse_m << "), RPE/1 m " << dr.rpe.translation_rmse_m << " m " << dr.rpe.rotation_rmse_deg
            << " deg\n";
  ASSERT_EQ(sim.laps, 2);
  EXPECT_GE(sim.distance_m, 150.0);
  EXPECT_EQ(sim.collisions, 0);
  // Bounds from measurement with margin (seeds 1-6; LaserSlam defaults): unaligned ATE
  // 0.35-0.42 m RMSE (max 0.63-0.75 m), aligned 0.07-0.10 m; RPE per metre 0.010-0.014 m and
  // 0.12-0.17 deg RMSE. Not yet the few centimetres wanted: the heading drift odometry does not
  // see is only partly corrected down the 28 m corridor (about 3 deg at its far end), so the
  // map bends and the position is off sideways by up to 0.7 m there, in both laps alike.
  EXPECT_LT(slam.ate.rmse_m, 0.6);
  EXPECT_LT(slam.ate.max_m, 1.0);
  EXPECT_LT(slam.ate_aligned.rmse_m, 0.15);
  // Locally: per metre driven, centimetres and a fraction of a degree.
  EXPECT_LT(slam.rpe.translation_rmse_m, 0.025);
  EXPECT_LT(slam.rpe.translation_max_m, 0.15);
  EXPECT_LT(slam.rpe.rotation_rmse_deg, 0.3);
  // Dead reckoning drifts by metres (5.6-5.8 m RMSE, 13-14 m at the end): its heading error
  // grows by the unseen 0.3 deg per metre.
  EXPECT_GT(dr.ate.rmse_m, 2.0);
  EXPECT_GT(dr.ate.rmse_m, 5 * slam.ate.rmse_m);
  EXPECT_GT(dr.rpe.rotation_rmse_deg, 0.2);
  // The map is bounded by the corridor's walls: about 92 m of wall, one point per 5 cm at most
  // (1000-1300 measured); a map drawn twice over (a lap that does not match the first) is not.
  EXPECT_LT(e.run.map.size(), 2500u);
}

}  // namespace
}  // namespace snapnav::eval
