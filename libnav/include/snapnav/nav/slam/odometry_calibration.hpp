#pragma once
// Online calibration of wheel odometry's systematic errors from the scan matches (laser SLAM's
// front end): the heading drift per metre driven (wheels of unequal diameter: the robot curves
// when it means to go straight), the turn scale (a wrong wheel base: every turn a few percent too
// large or too small) and the distance scale (worn or soft tyres). These are the errors that
// Borenstein and Feng's UMBmark (1996) measures once by hand; here the scans measure them all the
// time (as Censi et al. 2013 and Kuemmerle et al. 2011 calibrate odometry from the laser): each
// stretch of scans whose matches were all good is one observation of what odometry said against
// what the scans say, and a weighted least-squares fit with a prior at "no error" and a memory of
// the last memory_m metres driven gives the three figures: a lab learns how its robot's odometry
// errs from any log. With `apply`, the laser SLAM's prediction uses odometry corrected by them
// (its mean right where it was biased) and, with `noise`, a motion noise scaled to the corrected
// odometry's error (shipped off: measured, docs/experiments/2026-12-07-odometry-calibration.md).
//
// Pure: no clock, no I/O.

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/slam/map_matcher.hpp"  // kRadPerDeg

namespace snapnav::nav {

struct OdometryCalibrationOptions {
  bool apply = false;  // correct odometry (Correct) and scale the noise (NoiseScale2); else estimate only
  // Evidence older than this much travel weighs e^-1 of new evidence (a robot's load, floor and
  // tyres change) [m].
  double memory_m = 100;
  // The prior: no error, with these std. devs. (how far a real robot's odometry is off at most, as
  // a 1-sigma figure): a calibration needs evidence of about this size before it moves.
  double prior_drift_rad_per_m = 2 * kRadPerDeg;
  double prior_turn_scale = 0.05;
  double prior_distance_scale = 0.05;
  // An observation: a stretch of at least this much travel or turn [m, rad].
  double segment_m = 0.5;
  double segment_rad = 10 * kRadPerDeg;
  // Its heading error's std. dev.: the two scan poses' (each match's own, std. dev. pose_sigma_rad)
  // and odometry's random error over its travel (random_rad_per_sqrt_m per square root of a metre)
  // and turn (random_turn_fraction of it).
  double pose_sigma_rad = 0.5 * kRadPerDeg;
  double random_rad_per_sqrt_m = 0.5 * kRadPerDeg;
  double random_turn_fraction = 0.03;
  double pose_sigma_m = 0.02;               // ... the distance's: the two poses' and
  double random_distance_fraction = 0.02;   // odometry's random error per metre
  // An observation off the current fit by more than this many std. devs. is an outlier (a slipping
  // wheel, a wrong match), counted and left out [count].
  double outlier_sigmas = 4;
  // The prediction's noise from the calibration: odometry corrected is better than the noise model
  // of an uncalibrated robot says. With `noise`, NoiseScale2() is the ratio of the corrected
  // stretches' squared heading errors to the model's variance for them (a running mean with the
  // same memory), within [noise_scale_min^2, 1]: the laser SLAM scales its motion noise by it.
  bool noise = true;
  double noise_scale_min = 0.2;
  int noise_min_observations = 10;
  void Validate() const;  // throws std::invalid_argument
};

class OdometryCalibration {
 public:
  explicit OdometryCalibration(const OdometryCalibrationOptions& options = {});

  // Odometry's increment (robot frame) corrected by the current calibration: its distance divided
  // by (1 + distance scale), its turn less the drift over its signed distance, divided by
  // (1 + turn scale). The identity without `apply` or before any evidence.
  Pose2 Correct(const Pose2& raw) const;

  // One observation: odometry's raw motion over a stretch (composed increments, `raw_path_m` the
  // signed sum of their distances, `raw_turn_rad` the sum of their turns, unwrapped) against the
  // motion the scans estimated (`estimated`, the pose change between two scan poses). Returns
  // false when the stretch is too short to count or was an outlier. (With a reference trajectory's
  // motion as `estimated`, the calibration that the reference implies.)
  // `model_variance`: the motion noise model's heading variance for the stretch (NoiseScale2, and
  // the outlier test allows for it).
  bool Observe(const Pose2& raw, double raw_path_m, double raw_turn_rad, const Pose2& estimated,
               double model_variance = 0);
  // The square of the scale of the motion noise that corrected odometry deserves (1: as modelled).
  double NoiseScale2() const;
  // A stretch of odometry's raw motion long enough to be an observation (segment_m, segment_rad).
  bool LongEnough(double raw_path_m, double raw_turn_rad) const;

  double drift_rad_per_m() const { return heading_(1); }
  double turn_scale() const { return heading_(0); }
  double distance_scale() const { return distance_; }
  int observations() const { return observations_; }
  int outliers() const { return outliers_; }
  const OdometryCalibrationOptions& options() const { return options_; }

 private:
  void Solve();
  // The information of the heading fit and of the distance fit, the prior's included.
  Eigen::Matrix2d HeadingInformation() const;
  double DistanceInformation() const;

  OdometryCalibrationOptions options_;
  // Heading: raw turn - estimated turn = turn_scale * estimated turn + drift * signed distance.
  Eigen::Matrix2d heading_information_ = Eigen::Matrix2d::Zero();
  Eigen::Vector2d heading_vector_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d heading_ = Eigen::Vector2d::Zero();  // (turn scale, drift per metre)
  // Distance: |raw| - |estimated| = distance_scale * |estimated|.
  double distance_information_ = 0, distance_vector_ = 0, distance_ = 0;
  int observations_ = 0, outliers_ = 0;
  double residual2_ = 0, model_variance_ = 0;  // corrected stretches' squared heading error, the model's
};

}  // namespace snapnav::nav
