#include "exploration.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace snapnav::eval {

namespace {

constexpr double kPhysicsDt = 0.05;  // [s] simulation step of the exploration drives

Eigen::Vector2d Xy(const nav::Pose2& p) { return {p.x_m, p.y_m}; }

// The exploring robot: it drives in the scene without its people (so nobody blocks it: the people
// step aside), while the people walk around it in a World of their own, kept in step.
class ExploreWorld {
 public:
  ExploreWorld(const nav::sim::Scene& scene, const nav::sim::DriveOptions& drive, uint64_t seed)
      : empty_(WithoutPeople(scene)), robot_(empty_, drive, {}, seed), crowd_(scene, seed + 1), drive_(drive) {}
  void Step(double linear_mps, double angular_radps, double dt_s) {
    robot_.Step(linear_mps, angular_radps, dt_s);
    crowd_.Step(dt_s, robot_.true_pose());
  }
  nav::sim::World& robot() { return robot_; }
  const nav::sim::World& robot() const { return robot_; }
  std::vector<nav::sim::Cylinder> people() const { return crowd_.Around(robot_.true_pose(), drive_.robot_radius_m); }

 private:
  static nav::sim::Scene WithoutPeople(nav::sim::Scene scene) {
    scene.people.count = 0;
    return scene;
  }
  nav::sim::Scene empty_;  // before robot_, which keeps a reference to it
  nav::sim::World robot_;
  Crowd crowd_;
  nav::sim::DriveOptions drive_;
};

}  // namespace

std::vector<nav::sim::Cylinder> Crowd::Around(const nav::Pose2& robot, double robot_radius_m) const {
  std::vector<nav::sim::Cylinder> out;
  if (!active_) return out;
  for (const auto& c : world_.people()) {
    if ((c.center - Xy(robot)).norm() > c.radius_m + robot_radius_m) out.push_back(c);
  }
  return out;
}

std::vector<nav::sim::Cylinder> Crowd::Advance(double dt_s, const nav::Pose2& robot, double robot_radius_m) {
  const int steps = std::max(1, static_cast<int>(std::lround(dt_s / 0.1)));
  for (int i = 0; i < steps; ++i) Step(0.1, robot);
  return Around(robot, robot_radius_m);
}

bool Area::Contains(const Eigen::Vector2d& p, double margin_m) const {
  return p.x() >= min.x() - margin_m && p.x() <= max.x() + margin_m && p.y() >= min.y() - margin_m &&
         p.y() <= max.y() + margin_m;
}

Area GridArea(const nav::sim::GridSpec& grid) {
  if (grid.nx < 2 || grid.ny < 2) throw std::invalid_argument("grid area: the grid needs at least 2 x 2 positions");
  Area a;
  a.min = grid.Position(0, 0);
  a.max = grid.Position(grid.nx - 1, grid.ny - 1);
  return a;
}

std::vector<nav::Pose2> RandomTestPoses(const Area& area, const nav::sim::GridSpec& grid, int count,
                                        double min_grid_distance_m, uint64_t seed) {
  if (count < 0) throw std::invalid_argument("test poses: count must be >= 0");
  if (!(min_grid_distance_m >= 0) || min_grid_distance_m >= grid.spacing_m / 2) {
    throw std::invalid_argument("test poses: min_grid_distance_m must be in [0, spacing / 2)");
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(area.min.x(), area.max.x()), uy(area.min.y(), area.max.y()),
      heading(-M_PI, M_PI);
  std::vector<nav::Pose2> poses;
  while (static_cast<int>(poses.size()) < count) {
    const Eigen::Vector2d p(ux(rng), uy(rng));
    const double th = heading(rng);
    const int ix = std::clamp(static_cast<int>(std::lround((p.x() - grid.origin_x_m) / grid.spacing_m)), 0, grid.nx - 1);
    const int iy = std::clamp(static_cast<int>(std::lround((p.y() - grid.origin_y_m) / grid.spacing_m)), 0, grid.ny - 1);
    if ((grid.Position(ix, iy) - p).norm() < min_grid_distance_m) continue;
    poses.push_back({p.x(), p.y(), th});
  }
  return poses;
}

void RandomWalkOptions::Validate() const {
  if (runs < 1 || steps < 0) throw std::invalid_argument("random walk: runs must be >= 1 and steps >= 0");
  if (!(step_m > 0) || !(speed_mps > 0)) throw std::invalid_argument("random walk: step_m and speed_mps must be positive");
  if (!(turn_sigma_rad >= 0) || !(turn_back_spread_rad >= 0) || !(turn_back_spread_rad < M_PI / 2)) {
    throw std::invalid_argument("random walk: turn_sigma_rad >= 0, turn_back_spread_rad in [0, pi / 2)");
  }
  if (!(border_margin_m >= 0)) throw std::invalid_argument("random walk: border_margin_m must be >= 0");
  if (!std::isfinite(start_heading_rad)) throw std::invalid_argument("random walk: start_heading_rad must be finite");
}

namespace {

// Turns in place by `angle_rad`, then drives `distance_m` forward, in physics steps.
void TurnAndDrive(ExploreWorld& world, double angle_rad, double distance_m, double speed_mps,
                  double turn_rate_radps) {
  for (double left = std::abs(angle_rad) / turn_rate_radps; left > 1e-9; left -= kPhysicsDt) {
    world.Step(0, std::copysign(turn_rate_radps, angle_rad), std::min(kPhysicsDt, left));
  }
  for (double left = distance_m / speed_mps; left > 1e-9; left -= kPhysicsDt) {
    world.Step(speed_mps, 0, std::min(kPhysicsDt, left));
  }
}

ExploreSample Sample(const ExploreWorld& world, const nav::Pose2& start, const nav::Pose2& odom_start,
                     const nav::Pose2& odom_now, double time_offset_s, int run) {
  ExploreSample s;
  s.truth = world.robot().true_pose();
  s.odometry = start.Compose(odom_start.Between(odom_now));
  s.utime = static_cast<int64_t>(std::llround((time_offset_s + world.robot().time_s()) * 1e6));
  s.run = run;
  s.people = world.people();
  return s;
}

}  // namespace

std::vector<ExploreSample> RandomWalk(const nav::sim::Scene& scene, const Area& area, const nav::sim::DriveOptions& drive,
                                      const RandomWalkOptions& options, uint64_t seed) {
  options.Validate();
  std::vector<ExploreSample> samples;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> turn(0.0, options.turn_sigma_rad);
  std::uniform_real_distribution<double> spread(-options.turn_back_spread_rad, options.turn_back_spread_rad);
  const double turn_rate = 0.8 * drive.max_angular_radps;
  const double speed = std::min(options.speed_mps, drive.max_linear_mps);
  double time_offset_s = 0;
  for (int run = 0; run < options.runs; ++run) {
    ExploreWorld world(scene, drive, seed * 7919 + static_cast<uint64_t>(run) + 1);
    const nav::Pose2 start{area.centre().x(), area.centre().y(),
                           nav::WrapAngle(options.start_heading_rad + run * 2 * M_PI / options.runs)};
    world.robot().SetTruePose(start);
    const nav::Pose2 odom_start = world.robot().TakeOdometry().cumulative;
    nav::Pose2 odom = odom_start;
    samples.push_back(Sample(world, start, odom_start, odom, time_offset_s, run));
    for (int step = 0; step < options.steps; ++step) {
      const nav::Pose2 p = world.robot().true_pose();
      double dtheta = turn(rng);
      const double h = p.theta_rad + dtheta;
      const Eigen::Vector2d next = Xy(p) + options.step_m * Eigen::Vector2d(std::cos(h), std::sin(h));
      if (!area.Contains(next, options.border_margin_m)) {
        // Over the border: turn back drastically, towards the centre give or take a little.
        const Eigen::Vector2d to = area.centre() - Xy(p);
        dtheta = nav::WrapAngle(std::atan2(to.y(), to.x()) + spread(rng) - p.theta_rad);
      }
      TurnAndDrive(world, dtheta, options.step_m, speed, turn_rate);
      odom = world.robot().TakeOdometry().cumulative;
      samples.push_back(Sample(world, start, odom_start, odom, time_offset_s, run));
    }
    time_offset_s += world.robot().time_s() + 1.0;
  }
  return samples;
}

std::vector<Eigen::Vector2d> ManualRouteWaypoints(const Area& area, double row_spacing_m) {
  if (!(row_spacing_m > 0)) throw std::invalid_argument("manual route: row_spacing_m must be positive");
  const double h = area.max.y() - area.min.y();
  const int rows = std::max(2, static_cast<int>(std::lround(h / row_spacing_m)) + 1);
  std::vector<Eigen::Vector2d> w;
  for (int r = 0; r < rows; ++r) {
    const double y = area.min.y() + h * r / (rows - 1);
    const bool east = r % 2 == 0;
    w.push_back({east ? area.min.x() : area.max.x(), y});
    w.push_back({east ? area.max.x() : area.min.x(), y});
  }
  return w;
}

std::vector<ExploreSample> DriveRoute(const nav::sim::Scene& scene, const std::vector<Eigen::Vector2d>& waypoints,
                                      const nav::sim::DriveOptions& drive, double spacing_m, uint64_t seed) {
  if (waypoints.size() < 2) throw std::invalid_argument("drive route: needs at least 2 waypoints");
  if (!(spacing_m > 0)) throw std::invalid_argument("drive route: spacing_m must be positive");
  ExploreWorld world(scene, drive, seed);
  const Eigen::Vector2d d = waypoints[1] - waypoints[0];
  const nav::Pose2 start{waypoints[0].x(), waypoints[0].y(), std::atan2(d.y(), d.x())};
  world.robot().SetTruePose(start);
  const nav::Pose2 odom_start = world.robot().TakeOdometry().cumulative;
  nav::sim::RouteDriver driver(std::vector<Eigen::Vector2d>(waypoints.begin() + 1, waypoints.end()),
                               std::min(0.25, drive.max_linear_mps), 0.05, false);
  std::vector<ExploreSample> samples = {Sample(world, start, odom_start, odom_start, 0, 0)};
  double last = 0;
  for (int i = 0; i < 200000 && !driver.finished(); ++i) {
    const Eigen::Vector2d cmd = driver.Command(world.robot().true_pose());
    if (driver.finished()) break;
    world.Step(cmd.x(), cmd.y(), kPhysicsDt);
    if (world.robot().distance_m() - last >= spacing_m) {
      last = world.robot().distance_m();
      samples.push_back(Sample(world, start, odom_start, world.robot().TakeOdometry().cumulative, 0, 0));
    }
  }
  if (world.robot().distance_m() - last >= spacing_m / 2) {
    samples.push_back(Sample(world, start, odom_start, world.robot().TakeOdometry().cumulative, 0, 0));
  }
  return samples;
}

}  // namespace snapnav::eval
