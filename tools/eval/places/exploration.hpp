#pragma once
// How the simulated robot explores a scene for the place-cell evaluations (thesis 5.1.4): the area
// of interest, random test poses off the grid, the random walk, the manual serpentine route, and
// the people who walk around the robot while it takes its views. Shared by `eval localization`
// and `eval compare`.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::eval {

// An axis-aligned rectangle of the floor (the area of interest: the scene's grid).
struct Area {
  Eigen::Vector2d min = Eigen::Vector2d::Zero();
  Eigen::Vector2d max = Eigen::Vector2d::Zero();
  bool Contains(const Eigen::Vector2d& p, double margin_m = 0) const;
  double area_m2() const { return (max - min).prod(); }
  Eigen::Vector2d centre() const { return (min + max) / 2; }
};
// The rectangle the grid's positions span. Throws std::invalid_argument for a grid of fewer than
// 2 x 2 positions.
Area GridArea(const nav::sim::GridSpec& grid);

// `count` test poses, uniform in `area` with uniform headings, each at least min_grid_distance_m
// from every grid position (off the grid).
std::vector<nav::Pose2> RandomTestPoses(const Area& area, const nav::sim::GridSpec& grid, int count,
                                        double min_grid_distance_m, uint64_t seed);

// Where the robot took a view while exploring.
struct ExploreSample {
  nav::Pose2 truth;     // true pose
  nav::Pose2 odometry;  // wheel odometry from the run's known start pose
  int64_t utime = 0;    // simulated time [us]
  int run = 0;
  std::vector<nav::sim::Cylinder> people;  // where the scene's people were
};

// The random exploration of 5.1.4: random heading changes with a tendency to go forward; when the
// next step would leave the area the robot turns back towards its centre. A view every step.
struct RandomWalkOptions {
  int runs = 4;                       // runs from the area's centre, start headings spread over the circle
  int steps = 150;                    // views per run (after the start view)
  double step_m = 0.05;               // forward motion between views
  double speed_mps = 0.25;
  double turn_sigma_rad = 0.3;        // std. dev. of the random heading change per step
  double turn_back_spread_rad = 0.6;  // turning back: towards the centre +- this (uniform)
  double border_margin_m = 0.05;      // the area grown by this is where the robot may go
  double start_heading_rad = 0.3;     // run k starts at this + k 2 pi / runs
  void Validate() const;              // throws std::invalid_argument
};
// The views of every run in order (the World of `scene` moves the robot with the control and
// odometry noise of `drive`, and its people).
std::vector<ExploreSample> RandomWalk(const nav::sim::Scene& scene, const Area& area, const nav::sim::DriveOptions& drive,
                                      const RandomWalkOptions& options, uint64_t seed);

// The manual exploration route (like the thesis' fig. 5.4): a serpentine over the area, rows
// row_spacing_m apart, then back along the columns, so the route covers the area twice.
std::vector<Eigen::Vector2d> ManualRouteWaypoints(const Area& area, double row_spacing_m);
// Drives the waypoints (the sim's pure-pursuit driver on the true pose) and takes a view at the
// start and every spacing_m of travel.
std::vector<ExploreSample> DriveRoute(const nav::sim::Scene& scene, const std::vector<Eigen::Vector2d>& waypoints,
                                      const nav::sim::DriveOptions& drive, double spacing_m, uint64_t seed);

// The people of a scene walk (random waypoints) around a robot that stands at `robot`: they do
// not walk into it, and one who stands where the robot is (radius + robot radius) has stepped
// aside and is left out of the image.
class Crowd {
 public:
  Crowd(const nav::sim::Scene& scene, uint64_t seed) : world_(scene, {}, {}, seed), active_(scene.people.count > 0) {}
  bool active() const { return active_; }
  void Step(double dt_s, const nav::Pose2& robot) {
    if (!active_) return;
    world_.SetTruePose(robot);
    world_.Step(0, 0, dt_s);
  }
  std::vector<nav::sim::Cylinder> Around(const nav::Pose2& robot, double robot_radius_m) const;
  // People after dt_s of walking (in 0.1 s steps) around the robot standing at `robot`.
  std::vector<nav::sim::Cylinder> Advance(double dt_s, const nav::Pose2& robot, double robot_radius_m);

 private:
  nav::sim::World world_;
  bool active_;
};

}  // namespace snapnav::eval
