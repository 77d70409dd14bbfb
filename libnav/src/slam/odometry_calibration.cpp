#include "snapnav/nav/slam/odometry_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

namespace snapnav::nav {

namespace {
// The calibration stays within these (a correction beyond them is no odometry error but a fault).
constexpr double kMaxScale = 0.5;
constexpr double kMaxDriftRadPerM = 10 * kRadPerDeg;
constexpr double kMinDistanceM = 0.1;  // a stretch shorter than this says nothing of the distance scale
}  // namespace

void OdometryCalibrationOptions::Validate() const {
  const auto positive = [](double v, const char* key) {
    if (!(v > 0) || !std::isfinite(v)) throw std::invalid_argument(std::string("odometry calibration: ") + key + " must be > 0");
  };
  const auto non_negative = [](double v, const char* key) {
    if (!(v >= 0) || !std::isfinite(v)) throw std::invalid_argument(std::string("odometry calibration: ") + key + " must be >= 0");
  };
  positive(memory_m, "odometry_calibration_memory_m");
  positive(prior_drift_rad_per_m, "odometry_calibration_prior_drift_deg_per_m");
  positive(prior_turn_scale, "odometry_calibration_prior_turn_scale");
  positive(prior_distance_scale, "odometry_calibration_prior_distance_scale");
  non_negative(segment_m, "odometry_calibration_stretch_m");
  non_negative(segment_rad, "odometry_calibration_stretch_deg");
  positive(pose_sigma_rad, "pose_sigma_rad");
  non_negative(random_rad_per_sqrt_m, "random_rad_per_sqrt_m");
  non_negative(random_turn_fraction, "random_turn_fraction");
  positive(pose_sigma_m, "pose_sigma_m");
  non_negative(random_distance_fraction, "random_distance_fraction");
  positive(outlier_sigmas, "outlier_sigmas");
  if (!(noise_scale_min > 0 && noise_scale_min <= 1)) {
    throw std::invalid_argument("odometry calibration: odometry_calibration_noise_min must be in (0, 1]");
  }
}

OdometryCalibration::OdometryCalibration(const OdometryCalibrationOptions& options) : options_(options) {
  options_.Validate();
}

Pose2 OdometryCalibration::Correct(const Pose2& raw) const {
  if (!options_.apply || observations_ == 0) return raw;
  const double d = std::copysign(std::hypot(raw.x_m, raw.y_m), raw.x_m);
  const double s = 1 + distance_;
  return {raw.x_m / s, raw.y_m / s, (raw.theta_rad - heading_(1) * d) / (1 + heading_(0))};
}

double OdometryCalibration::NoiseScale2() const {
  if (!options_.apply || !options_.noise || observations_ < options_.noise_min_observations || !(model_variance_ > 0)) {
    return 1;
  }
  const double lo = options_.noise_scale_min * options_.noise_scale_min;
  return std::clamp(residual2_ / model_variance_, lo, 1.0);
}

bool OdometryCalibration::Observe(const Pose2& raw, double raw_path_m, double raw_turn_rad, const Pose2& estimated,
                                  double model_variance) {
  if (!std::isfinite(raw.x_m) || !std::isfinite(raw.y_m) || !std::isfinite(raw_path_m) ||
      !std::isfinite(raw_turn_rad) || !std::isfinite(estimated.x_m) || !std::isfinite(estimated.y_m) ||
      !std::isfinite(estimated.theta_rad)) {
    return false;
  }
  // The turn the scans saw, unwrapped as odometry's (a stretch can turn more than half a circle).
  const double residual = WrapAngle(raw_turn_rad - estimated.theta_rad);
  const double turn = raw_turn_rad - residual;
  if (!LongEnough(raw_path_m, raw_turn_rad)) return false;

  const double forget = std::exp(-std::abs(raw_path_m) / options_.memory_m);
  const Eigen::Vector2d h(turn, raw_path_m);
  const double sp = options_.pose_sigma_rad, st = options_.random_turn_fraction * turn;
  const double var = 2 * sp * sp + options_.random_rad_per_sqrt_m * options_.random_rad_per_sqrt_m * std::abs(raw_path_m) +
                     st * st;
  // The prior's and the evidence's uncertainty of the fit where this observation looks.
  const double fit_var = h.dot(HeadingInformation().ldlt().solve(h));
  const double off = residual - h.dot(heading_);
  // The corrected odometry's error on this stretch (against the fit before it) against the
  // model's variance: every stretch counts (poor odometry is no outlier of itself), an outlier's
  // at most outlier_sigmas^2 model variances (one wrong match moves the scale little).
  const double o2 = options_.outlier_sigmas * options_.outlier_sigmas;
  if (model_variance > 0) {
    residual2_ = forget * residual2_ + std::min(off * off, o2 * model_variance);
    model_variance_ = forget * model_variance_ + model_variance;
  }
  // An outlier against the stretch's own error, the fit's, and the odometry noise the prediction
  // currently allows (odometry with large random errors has large residuals and is no outlier).
  if (off * off > o2 * (var + fit_var + NoiseScale2() * model_variance)) {
    ++outliers_;
    return false;
  }
  heading_information_ = forget * heading_information_ + h * h.transpose() / var;
  heading_vector_ = forget * heading_vector_ + h * residual / var;

  // The distance, where the stretch moved enough to measure it (a stretch a turn ended may be short).
  const double est_m = std::hypot(estimated.x_m, estimated.y_m);
  if (est_m >= kMinDistanceM) {
    const double dres = std::hypot(raw.x_m, raw.y_m) - est_m;
    const double sd = options_.random_distance_fraction * est_m;
    const double dvar = 2 * options_.pose_sigma_m * options_.pose_sigma_m + sd * sd;
    const double doff = dres - distance_ * est_m;
    if (doff * doff <= o2 * (dvar + est_m * est_m / DistanceInformation())) {
      distance_information_ = forget * distance_information_ + est_m * est_m / dvar;
      distance_vector_ = forget * distance_vector_ + est_m * dres / dvar;
    }
  }
  ++observations_;
  Solve();
  return true;
}

bool OdometryCalibration::LongEnough(double raw_path_m, double raw_turn_rad) const {
  return std::abs(raw_path_m) >= options_.segment_m || std::abs(raw_turn_rad) >= options_.segment_rad;
}

Eigen::Matrix2d OdometryCalibration::HeadingInformation() const {
  Eigen::Matrix2d information = heading_information_;
  information(0, 0) += 1 / (options_.prior_turn_scale * options_.prior_turn_scale);
  information(1, 1) += 1 / (options_.prior_drift_rad_per_m * options_.prior_drift_rad_per_m);
  return information;
}

double OdometryCalibration::DistanceInformation() const {
  return distance_information_ + 1 / (options_.prior_distance_scale * options_.prior_distance_scale);
}

void OdometryCalibration::Solve() {
  heading_ = HeadingInformation().ldlt().solve(heading_vector_);
  heading_(0) = std::clamp(heading_(0), -kMaxScale, kMaxScale);
  heading_(1) = std::clamp(heading_(1), -kMaxDriftRadPerM, kMaxDriftRadPerM);
  distance_ = std::clamp(distance_vector_ / DistanceInformation(), -kMaxScale, kMaxScale);
}

}  // namespace snapnav::nav
