#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include "snapnav/nav/slam/odometry_calibration.hpp"

namespace snapnav::nav {
namespace {

constexpr double kDeg = M_PI / 180;

// Odometry with the systematic errors of UMBmark's robot (as ../shared/tools/carmen_raw_like.py
// makes them): the distance 3 % long, turns 2 % large, the heading drifting `drift_deg_per_m`
// per metre, and random errors on top.
struct BiasedOdometry {
  double distance_scale = 0.03, turn_scale = 0.02, drift_deg_per_m = 1.5;
  double random_deg_per_m = 0.3, random_m_per_m = 0.01;
  std::mt19937 rng{7};
  Pose2 operator()(const Pose2& truth) {
    std::normal_distribution<double> n(0, 1);
    const double d = std::hypot(truth.x_m, truth.y_m);
    const double s = 1 + distance_scale + random_m_per_m * n(rng);
    return {truth.x_m * s, truth.y_m * s,
            truth.theta_rad * (1 + turn_scale) + drift_deg_per_m * kDeg * d + random_deg_per_m * kDeg * d * n(rng)};
  }
};

// Stretches of a robot's drive (1 m forward with a turn of -40..40 deg), the scans' estimate of
// each a few tenths of a degree and a centimetre off the truth.
Pose2 Stretch(std::mt19937& rng) {
  std::uniform_real_distribution<double> turn(-40, 40);
  const double th = turn(rng) * kDeg;
  return {std::cos(th / 2), std::sin(th / 2), th};
}
Pose2 Estimated(const Pose2& truth, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return {truth.x_m + 0.01 * n(rng), truth.y_m + 0.01 * n(rng), truth.theta_rad + 0.3 * kDeg * n(rng)};
}
void Observe(OdometryCalibration& cal, const Pose2& raw, const Pose2& estimated) {
  cal.Observe(raw, std::copysign(std::hypot(raw.x_m, raw.y_m), raw.x_m), raw.theta_rad, estimated);
}

OdometryCalibrationOptions Applied() {
  OdometryCalibrationOptions o;
  o.apply = true;
  return o;
}

TEST(OdometryCalibration, LearnsTheDriftTurnAndDistanceScaleOfBiasedOdometry) {
  OdometryCalibration cal(Applied());
  BiasedOdometry odometry;
  std::mt19937 rng(3);
  double raw_error = 0, corrected_error = 0;
  for (int i = 0; i < 200; ++i) {  // 200 m
    const Pose2 truth = Stretch(rng);
    const Pose2 raw = odometry(truth);
    if (i >= 100) {  // the second 100 m: odometry corrected by what the first taught
      raw_error += std::abs(raw.theta_rad - truth.theta_rad);
      corrected_error += std::abs(cal.Correct(raw).theta_rad - truth.theta_rad);
    }
    Observe(cal, raw, Estimated(truth, rng));
  }
  std::cout << "drift " << cal.drift_rad_per_m() / kDeg << " deg/m, turn scale " << cal.turn_scale()
            << ", distance scale " << cal.distance_scale() << "; heading error per metre raw "
            << raw_error / 100 / kDeg << " deg, corrected " << corrected_error / 100 / kDeg << " deg\n";
  EXPECT_EQ(cal.observations(), 200);
  EXPECT_NEAR(cal.drift_rad_per_m() / kDeg, 1.5, 0.15);
  EXPECT_NEAR(cal.turn_scale(), 0.02, 0.01);
  EXPECT_NEAR(cal.distance_scale(), 0.03, 0.005);
  EXPECT_LT(corrected_error, 0.3 * raw_error);
}

// Perfect odometry: the calibration stays at "no error" (the scans' own noise teaches nothing).
TEST(OdometryCalibration, PerfectOdometryStaysUncorrected) {
  OdometryCalibration cal(Applied());
  std::mt19937 rng(5);
  for (int i = 0; i < 200; ++i) {
    const Pose2 truth = Stretch(rng);
    Observe(cal, truth, Estimated(truth, rng));
  }
  EXPECT_NEAR(cal.drift_rad_per_m() / kDeg, 0, 0.1);
  EXPECT_NEAR(cal.turn_scale(), 0, 0.005);
  EXPECT_NEAR(cal.distance_scale(), 0, 0.003);
  const Pose2 c = cal.Correct({1, 0, 0.2});
  EXPECT_NEAR(c.theta_rad, 0.2, 0.1 * kDeg);
}

// A stretch the scans got wrong (a wrong match, 25 deg off) or a slipping wheel is an outlier:
// counted, left out, the calibration unmoved.
TEST(OdometryCalibration, AWrongStretchIsAnOutlier) {
  OdometryCalibration cal;
  BiasedOdometry odometry;
  std::mt19937 rng(9);
  for (int i = 0; i < 100; ++i) {
    const Pose2 truth = Stretch(rng);
    Observe(cal, odometry(truth), Estimated(truth, rng));
  }
  const double drift = cal.drift_rad_per_m();
  const Pose2 truth{1, 0, 0};
  Observe(cal, odometry(truth), {1, 0, 25 * kDeg});
  EXPECT_EQ(cal.outliers(), 1);
  EXPECT_EQ(cal.observations(), 100);
  EXPECT_DOUBLE_EQ(cal.drift_rad_per_m(), drift);
}

// The robot changes (a load, a new floor): old evidence fades over memory_m of travel and the
// calibration follows the new drift.
TEST(OdometryCalibration, FollowsADriftThatChanges) {
  OdometryCalibrationOptions options;
  options.memory_m = 50;
  OdometryCalibration cal(options);
  BiasedOdometry odometry;
  std::mt19937 rng(11);
  for (int i = 0; i < 400; ++i) {
    if (i == 200) odometry.drift_deg_per_m = -1.0;
    const Pose2 truth = Stretch(rng);
    Observe(cal, odometry(truth), Estimated(truth, rng));
  }
  EXPECT_NEAR(cal.drift_rad_per_m() / kDeg, -1.0, 0.2);
}

// Corrected odometry is better than the noise model of an uncalibrated robot (2 deg per metre, 20 %
// of a turn) says: with `noise`, the prediction's noise scale falls to what the corrected stretches
// show (within its floor); odometry with large random errors keeps the model's noise.
TEST(OdometryCalibration, CorrectedOdometryEarnsANarrowerPrediction) {
  const auto scale2 = [](bool noise, double random_deg_per_m) {
    OdometryCalibrationOptions options = Applied();
    options.noise = noise;
    OdometryCalibration cal(options);
    BiasedOdometry odometry;
    odometry.random_deg_per_m = random_deg_per_m;
    std::mt19937 rng(13);
    for (int i = 0; i < 150; ++i) {
      const Pose2 truth = Stretch(rng);
      const Pose2 raw = odometry(truth);
      const double a = 0.2 * raw.theta_rad, b = 2 * kDeg * std::hypot(raw.x_m, raw.y_m);
      cal.Observe(raw, std::hypot(raw.x_m, raw.y_m), raw.theta_rad, Estimated(truth, rng), a * a + b * b);
    }
    return cal.NoiseScale2();
  };
  const double calibrated = scale2(true, 0.3), poor = scale2(true, 6), off = scale2(false, 0.3);
  std::cout << "noise scale: calibrated " << std::sqrt(calibrated) << ", poor odometry " << std::sqrt(poor)
            << ", off " << std::sqrt(off) << "\n";
  EXPECT_LT(std::sqrt(calibrated), 0.5);
  EXPECT_GE(calibrated, 0.2 * 0.2 - 1e-12);
  EXPECT_GT(std::sqrt(poor), 0.9);
  EXPECT_DOUBLE_EQ(off, 1);
}

// Short stretches do not count. Not applied (the shipped config), the calibration is estimated all
// the same and odometry passes unchanged; a bad option is refused.
TEST(OdometryCalibration, ShortStretchesAndNotApplied) {
  OdometryCalibration cal;
  EXPECT_FALSE(cal.Observe({0.1, 0, 0.01}, 0.1, 0.01, {0.1, 0, 0}));
  EXPECT_EQ(cal.observations(), 0);
  for (int i = 0; i < 20; ++i) EXPECT_TRUE(cal.Observe({1, 0, 0.1}, 1, 0.1, {1, 0, 0}));
  EXPECT_GT(cal.drift_rad_per_m() + cal.turn_scale(), 0.01);  // odometry turned where the scans did not
  const Pose2 c = cal.Correct({1, 0, 0.1});
  EXPECT_DOUBLE_EQ(c.theta_rad, 0.1);
  EXPECT_DOUBLE_EQ(cal.NoiseScale2(), 1);
  OdometryCalibrationOptions bad;
  bad.memory_m = 0;
  EXPECT_THROW(OdometryCalibration{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::nav
