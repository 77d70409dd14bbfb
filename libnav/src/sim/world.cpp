#include "snapnav/nav/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace snapnav::nav::sim {

void DriveOptions::Validate() const {
  // Each message names its option (and the sim config's key: the robot's radius_m).
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw std::invalid_argument(std::string("drive: ") + name + " must be positive");
  };
  positive(max_linear_mps, "max_linear_mps");
  positive(max_angular_radps, "max_angular_radps");
  positive(robot_radius_m, "the robot's radius_m");
  const auto noise = [](double v, const char* name) {
    if (!(v >= 0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("drive: ") + name + " must be finite and non-negative");
    }
  };
  noise(linear_noise_frac, "linear_noise_frac");
  noise(angular_noise_radps, "angular_noise_radps");
  noise(odometry_linear_noise_frac, "odometry_linear_noise_frac");
  noise(odometry_angular_noise_frac, "odometry_angular_noise_frac");
  if (!std::isfinite(heading_drift_deg_per_m))
    throw std::invalid_argument("drive: heading_drift_deg_per_m must be finite");
}

void LaserOptions::Validate() const {
  if (beams < 2) throw std::invalid_argument("laser: beams must be >= 2");
  if (!(angle_max_rad > angle_min_rad)) throw std::invalid_argument("laser: angle_max_deg must exceed angle_min_deg");
  if (!(range_min_m >= 0) || !(range_max_m > range_min_m)) {
    throw std::invalid_argument("laser: need 0 <= range_min_m < range_max_m");
  }
  if (!(range_noise_m >= 0)) throw std::invalid_argument("laser: range_noise_m must be >= 0");
  if (!(mount_height_m >= 0)) throw std::invalid_argument("laser: mount_height_m must be >= 0");
  faults.Validate();
}

void LaserFaults::Validate() const {
  if (!enabled) return;
  auto probability = [](double p) { return p >= 0 && p <= 1; };
  if (!(range_scale > 0.9 && range_scale < 1.1)) throw std::invalid_argument("laser faults: range_scale must be in (0.9, 1.1)");
  if (!(std::abs(range_bias_m) <= 0.2)) throw std::invalid_argument("laser faults: range_bias_m must be within 0.2 m");
  if (!(mixed_pixel_jump_m > 0)) throw std::invalid_argument("laser faults: mixed_pixel_jump_m must be positive");
  if (!probability(mixed_pixel_probability) || !probability(dark_dropout_probability) || !probability(dropout_probability)) {
    throw std::invalid_argument("laser faults: probabilities must be in [0, 1]");
  }
  if (!(dark_grey >= 0 && dark_grey <= 255)) throw std::invalid_argument("laser faults: dark_grey must be in 0..255");
  if (!(leg_radius_m > 0) || !(leg_spacing_m >= 2 * leg_radius_m)) {
    throw std::invalid_argument("laser faults: legs need a positive radius and a spacing of at least two radii");
  }
}

LaserFaults LaserFaultsPreset(const std::string& name) {
  LaserFaults f;
  if (name == "clean") return f;
  if (name != "realistic") throw std::invalid_argument("laser preset '" + name + "': expected clean or realistic");
  f.enabled = true;
  return f;
}

World::World(const Scene& scene, const DriveOptions& drive, const LaserOptions& laser, uint64_t seed)
    : scene_(scene), drive_(drive), laser_(laser), rng_(seed) {
  scene_.Validate();
  for (const Texture& t : scene_.textures) {
    const cv::Scalar m = cv::mean(t.levels.back());
    texture_grey_.push_back((m[0] + m[1] + m[2]) / 3.0);
  }
  drive_.Validate();
  laser_.Validate();
  true_pose_ = {scene.start_pose.x(), scene.start_pose.y(), scene.start_pose.z()};
  odom_pose_ = true_pose_;
  odom_at_last_take_ = odom_pose_;
  const PeopleSpec& p = scene.people;
  std::uniform_real_distribution<double> ux(p.area_min.x(), p.area_max.x()), uy(p.area_min.y(), p.area_max.y());
  const Eigen::Vector2d robot = true_pose_.Transform({0, 0});
  const double clearance = p.radius_m + drive_.robot_radius_m;
  for (int i = 0; i < p.count; ++i) {
    Cylinder c;
    // Not on the robot (a few tries; an area smaller than the robot keeps the last draw).
    for (int attempt = 0; attempt < 20; ++attempt) {
      c.center = {ux(rng_), uy(rng_)};
      if ((c.center - robot).norm() > clearance) break;
    }
    c.radius_m = p.radius_m;
    c.height_m = p.height_m;
    c.texture = p.textures[i % p.textures.size()];
    people_.push_back(c);
    people_goals_.push_back({ux(rng_), uy(rng_)});
  }
}

void KidnapOptions::Validate() const {
  if (!std::isfinite(at_s)) throw std::invalid_argument("kidnap: at_s must be finite");
  if (!std::isfinite(to.x_m) || !std::isfinite(to.y_m) || !std::isfinite(to.theta_rad)) {
    throw std::invalid_argument("kidnap: the pose `to` must be finite");
  }
}

void World::SetKidnap(const KidnapOptions& kidnap) {
  kidnap.Validate();
  if (kidnap.enabled()) {
    const double clearance = ClearanceAt(scene_, {}, kidnap.to.Transform({0, 0}), drive_.obstacle_min_height_m);
    if (!(clearance > drive_.robot_radius_m)) {
      throw std::invalid_argument("kidnap: the robot does not fit at (" + std::to_string(kidnap.to.x_m) + ", " +
                                  std::to_string(kidnap.to.y_m) + "): " + std::to_string(clearance) +
                                  " m from the nearest obstacle, radius " + std::to_string(drive_.robot_radius_m) +
                                  " m");
    }
  }
  kidnap_ = kidnap;
  kidnapped_ = false;
}

void World::MovePeople(double dt_s) {
  const PeopleSpec& p = scene_.people;
  std::uniform_real_distribution<double> ux(p.area_min.x(), p.area_max.x()), uy(p.area_min.y(), p.area_max.y());
  // People do not walk through the robot: one whose way crosses it walks around it, along the
  // circle at radius + robot radius, on the side of its goal; one who finds itself on the robot
  // (a teleported robot) steps away from it; a goal on the robot is replaced.
  const Eigen::Vector2d robot = true_pose_.Transform({0, 0});
  const double clearance = p.radius_m + drive_.robot_radius_m;
  const double step = p.speed_mps * dt_s;
  for (size_t i = 0; i < people_.size(); ++i) {
    Eigen::Vector2d& center = people_[i].center;
    for (int attempt = 0; attempt < 20 && (people_goals_[i] - robot).norm() <= clearance; ++attempt) {
      people_goals_[i] = {ux(rng_), uy(rng_)};
    }
    const Eigen::Vector2d to_goal = people_goals_[i] - center;
    const Eigen::Vector2d from_robot = center - robot;
    const double r = from_robot.norm();
    if (r <= clearance) {
      center += (r > 1e-9 ? from_robot / r : Eigen::Vector2d(1, 0)) * step;
      continue;
    }
    if (to_goal.norm() <= step) {
      center = people_goals_[i];
      people_goals_[i] = {ux(rng_), uy(rng_)};
      continue;
    }
    const Eigen::Vector2d next = center + to_goal.normalized() * step;
    if ((next - robot).norm() > clearance) {
      center = next;
    } else {
      Eigen::Vector2d tangent(-from_robot.y() / r, from_robot.x() / r);
      if (tangent.dot(to_goal) < 0) tangent = -tangent;
      center += tangent * step;  // moves away from the robot: sqrt(r^2 + step^2) > r
    }
  }
}

void World::Step(double linear_mps, double angular_radps, double dt_s) {
  if (!(dt_s > 0)) throw std::invalid_argument("world step needs dt_s > 0");
  if (kidnap_.enabled() && !kidnapped_ && time_s_ >= kidnap_.at_s - 1e-9) {
    true_pose_ = {kidnap_.to.x_m, kidnap_.to.y_m, WrapAngle(kidnap_.to.theta_rad)};  // odometry does not see it
    kidnapped_ = true;
    kidnapped_at_s_ = time_s_;
  }
  const double v = std::clamp(linear_mps, -drive_.max_linear_mps, drive_.max_linear_mps);
  const double w = std::clamp(angular_radps, -drive_.max_angular_radps, drive_.max_angular_radps);
  std::normal_distribution<double> n01(0.0, 1.0);

  // True motion: the command plus control error (a heading drift per metre and noise).
  const double v_true = v * (1.0 + drive_.linear_noise_frac * n01(rng_));
  const double d_true = v_true * dt_s;
  const double w_true = w + (v != 0 || w != 0 ? drive_.angular_noise_radps * n01(rng_) : 0.0);
  const double dtheta_true = w_true * dt_s + drive_.heading_drift_deg_per_m * M_PI / 180.0 * std::abs(d_true);
  const Pose2 candidate = true_pose_.Compose({d_true, 0, dtheta_true});
  const double clearance = ClearanceAt(scene_, drive_.people_block_robot ? people_ : std::vector<Cylinder>{},
                                       candidate.Transform({0, 0}), drive_.obstacle_min_height_m);
  if (clearance > drive_.robot_radius_m) {
    true_pose_ = candidate;
    distance_m_ += std::abs(d_true);
  } else {
    ++collisions_;  // blocked: turn in place only
    true_pose_ = true_pose_.Compose({0, 0, w_true * dt_s});
  }

  // Wheel odometry: what the wheels report of the command, with its own noise
  // (it does not see the heading drift nor a blocked robot).
  const double d_odo = v * dt_s * (1.0 + drive_.odometry_linear_noise_frac * n01(rng_));
  const double dtheta_odo = w * dt_s * (1.0 + drive_.odometry_angular_noise_frac * n01(rng_));
  odom_pose_ = odom_pose_.Compose({d_odo, 0, dtheta_odo});

  MovePeople(dt_s);
  time_s_ += dt_s;
}

OdometryReading World::TakeOdometry() {
  OdometryReading r;
  r.delta = odom_at_last_take_.Between(odom_pose_);
  r.cumulative = odom_pose_;
  r.dt_s = time_s_ - time_at_last_take_;
  odom_at_last_take_ = odom_pose_;
  time_at_last_take_ = time_s_;
  return r;
}

std::vector<float> World::Scan() {
  std::vector<float> ranges(laser_.beams);
  const Eigen::Vector2d origin = true_pose_.Transform({laser_.mount_x_m, 0});
  const double inc = laser_.AngleIncrement();
  std::normal_distribution<double> noise(0.0, laser_.range_noise_m);
  const LaserFaults& f = laser_.faults;
  if (!f.enabled) {
    for (int i = 0; i < laser_.beams; ++i) {
      const double a = true_pose_.theta_rad + laser_.angle_min_rad + i * inc;
      const auto hit = NearestHit(scene_, people_, origin, {std::cos(a), std::sin(a)}, laser_.mount_height_m);
      double r = laser_.range_max_m;
      if (hit && hit->distance_m < laser_.range_max_m) {
        r = std::clamp(hit->distance_m + (laser_.range_noise_m > 0 ? noise(rng_) : 0.0), laser_.range_min_m,
                       laser_.range_max_m);
      }
      ranges[i] = static_cast<float>(r);
    }
    return ranges;
  }
  // A real laser: people are two legs at the scan height (across their way), dark surfaces absorb
  // the beam, a beam across a depth edge returns a mixed range, every range is off by a scale and a bias.
  std::vector<Cylinder> legs;
  const std::vector<Cylinder>* obstacles = &people_;
  if (f.legs) {
    for (size_t k = 0; k < people_.size(); ++k) {
      const Cylinder& p = people_[k];
      Eigen::Vector2d way = k < people_goals_.size() ? Eigen::Vector2d(people_goals_[k] - p.center) : Eigen::Vector2d(1, 0);
      if (way.norm() < 1e-6) way = {1, 0};
      const Eigen::Vector2d across = Eigen::Vector2d(-way.y(), way.x()).normalized() * (0.5 * f.leg_spacing_m);
      for (double side : {-1.0, 1.0}) {
        Cylinder leg = p;
        leg.center = p.center + side * across;
        leg.radius_m = f.leg_radius_m;
        legs.push_back(leg);
      }
    }
    obstacles = &legs;
  }
  std::vector<double> truth(static_cast<size_t>(laser_.beams), INFINITY);
  std::vector<bool> absorbed(static_cast<size_t>(laser_.beams), false);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < laser_.beams; ++i) {
    const double a = true_pose_.theta_rad + laser_.angle_min_rad + i * inc;
    const auto hit = NearestHit(scene_, *obstacles, origin, {std::cos(a), std::sin(a)}, laser_.mount_height_m);
    if (!hit) continue;
    truth[i] = hit->distance_m;
    const double grey = hit->texture >= 0 && hit->texture < static_cast<int>(texture_grey_.size()) ? texture_grey_[hit->texture] : 128;
    absorbed[i] = (grey < f.dark_grey && u(rng_) < f.dark_dropout_probability) || u(rng_) < f.dropout_probability;
  }
  std::vector<double> measured = truth;
  for (int i = 0; i + 1 < laser_.beams; ++i) {
    const double a = truth[i], b = truth[i + 1];
    if (!std::isfinite(a) || !std::isfinite(b) || std::abs(a - b) < f.mixed_pixel_jump_m) continue;
    if (u(rng_) >= f.mixed_pixel_probability) continue;
    const int far = a > b ? i : i + 1;
    const double near_r = std::min(a, b), far_r = std::max(a, b);
    measured[far] = near_r + u(rng_) * (far_r - near_r);
  }
  for (int i = 0; i < laser_.beams; ++i) {
    double r = laser_.range_max_m;
    if (!absorbed[i] && measured[i] < laser_.range_max_m) {
      r = std::clamp(f.range_scale * measured[i] + f.range_bias_m + (laser_.range_noise_m > 0 ? noise(rng_) : 0.0),
                     laser_.range_min_m, laser_.range_max_m);
    }
    ranges[i] = static_cast<float>(r);
  }
  return ranges;
}

RouteDriver::RouteDriver(std::vector<Eigen::Vector2d> route, double speed_mps, double tolerance_m, bool loop)
    : route_(std::move(route)), speed_mps_(speed_mps), tolerance_m_(tolerance_m), loop_(loop) {
  if (route_.empty()) throw std::invalid_argument("route driver needs at least one waypoint");
  if (!(speed_mps > 0) || !(tolerance_m > 0)) throw std::invalid_argument("route driver needs positive speed and tolerance");
}

void RouteDriver::Restart(const Pose2& pose) {
  const Eigen::Vector2d here(pose.x_m, pose.y_m);
  const Eigen::Vector2d heading(std::cos(pose.theta_rad), std::sin(pose.theta_rad));
  size_t best_ahead = route_.size(), best_any = 0;
  for (size_t i = 0; i < route_.size(); ++i) {
    const Eigen::Vector2d to = route_[i] - here;
    if (to.norm() < (route_[best_any] - here).norm()) best_any = i;
    if (to.norm() >= tolerance_m_ && to.dot(heading) > 0 &&
        (best_ahead == route_.size() || to.norm() < (route_[best_ahead] - here).norm())) {
      best_ahead = i;
    }
  }
  next_ = best_ahead < route_.size() ? best_ahead : best_any;
  finished_ = false;
}

Eigen::Vector2d RouteDriver::Command(const Pose2& pose) {
  if (finished_) return {0, 0};
  const Eigen::Vector2d here(pose.x_m, pose.y_m);
  if ((route_[next_] - here).norm() < tolerance_m_) {
    if (++next_ == route_.size()) {
      ++laps_;
      next_ = 0;
      if (!loop_) {
        finished_ = true;
        return {0, 0};
      }
    }
  }
  const Eigen::Vector2d to = route_[next_] - here;
  const double err = WrapAngle(std::atan2(to.y(), to.x()) - pose.theta_rad);
  const double w = std::clamp(2.5 * err, -1.2, 1.2);
  const double v = std::abs(err) < 0.6 ? speed_mps_ * std::cos(err) * std::min(1.0, to.norm() / 0.3 + 0.3) : 0.0;
  return {v, w};
}

}  // namespace snapnav::nav::sim
