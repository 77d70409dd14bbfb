#pragma once
// Route following evaluated in closed loop (thesis 5.1.2-5.1.3, issue 6): the simulated robot
// follows a thesis route (figure 5.5, scaled to the scene's grid square) for several laps,
// localizing with place cells explored beforehand, driving by odometry between fixes, and
// arriving by snapshot homing towards the waypoint's own snapshot. In process, no bus; the
// same seed gives the same run.
//
//   memory     a place cell at every grid position (every cell_step-th, heading 0) and at each
//              route waypoint, the views rendered as raw omni images and unwrapped (the real
//              pipeline), people walking between images in scenes with people;
//   each control step (the camera rate): odometry -> PoseTracker; every localize_every steps
//              render the view at the true pose, Localize with the tracked pose as the prediction
//              (distance filter) -> a fix; within homing_radius_m of the waypoint the
//              LandmarkHomer (cell landmarks as the home) gives the direction and, with
//              homing_arrived_rad, the bearing distance to the cell says "arrived";
//              RouteFollower -> command -> World::Step (control error, people).
//   baseline   the same follower driven by odometry alone (no fixes, no homing).
//   people     (people11) walk through the views but never block the robot: the simulator's
//              people and robot block each other, which deadlocks a robot without obstacle
//              avoidance; a person within 15 cm of the camera is not drawn.
//
// Outputs: every waypoint arrival's true error against the waypoint, per lap mean / max, the
// growth of the error over laps, the baseline's errors, a trajectory plot.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/places/navigator.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"
#include "snapnav/nav/sim/world.hpp"

namespace snapnav::eval {

struct RouteEvalOptions {
  nav::sim::OmniCameraOptions camera;  // the simulator's camera, mirror and panorama
  std::string mask = "none";           // the raw frames' self-occlusion mask (homing_eval.hpp UseMask)
  nav::sim::DriveOptions drive;        // control error and odometry noise
  nav::PlaceViewOptions view;
  nav::LocalizerOptions localizer;
  nav::VocabularyOptions vocabulary;
  nav::LandmarkHomingConfig homing;  // final approach: matching and landmark ALV
  nav::PoseTrackerOptions tracker;
  nav::FollowerOptions follower;

  int route = 1;  // thesis figure 5.5: 1 (left) or 2 (right)
  int laps = 3;
  double tolerance_m = 0.05;   // arrival tolerance of the route (tracked position)
  int cell_step = 1;           // memory: every cell_step-th grid position in x and y
  bool waypoint_cells = true;  // memory: a cell at every waypoint too
  bool use_homing = true;      // final approach by landmark homing
  // The homing says "arrived" when the bearing distance (5.1.1) between the view and the
  // waypoint's cell falls below this [rad]; 0: never (arrival by the tracked position).
  double homing_arrived_rad = 0;
  double physics_rate_hz = 100;  // World::Step rate
  double control_rate_hz = 10;   // control steps (the camera rate); must divide the physics rate
  int localize_every = 1;        // localize every N control steps
  double people_dt_s = 2.0;      // exploration: the people walk this long between images
  double max_time_s = 0;         // simulated time limit; 0: from the route length and laps
  double start_heading_rad = 0;  // heading at the start (the robot stands on waypoint 0)
  uint64_t seed = 1;
  void Validate() const;  // throws std::invalid_argument
};

// One waypoint reached (the follower said so).
struct WaypointArrival {
  int lap = 0;                                         // 1-based
  int waypoint = 0;                                    // index in the route
  double time_s = 0;                                   // simulated time
  Eigen::Vector2d truth = Eigen::Vector2d::Zero();     // true position then
  Eigen::Vector2d estimate = Eigen::Vector2d::Zero();  // tracked position
  Eigen::Vector2d odometry = Eigen::Vector2d::Zero();  // dead reckoning from the start
  double error_m = 0;                                  // |truth - waypoint|
  double estimate_error_m = 0;                         // |estimate - truth|
  std::string reason;                                  // estimate | homing | timeout
};

// One homing call of the final approach.
struct HomingSample {
  double true_distance_m = 0;        // robot to waypoint (truth)
  double true_direction_rad = 0;     // direction to the waypoint, robot frame (truth)
  bool estimate = false;             // the homer gave a direction
  double direction_rad = 0;          // ... this one
  double error_rad = 0;              // |direction - true direction| (pi without an estimate)
  double bearing_distance_rad = -1;  // the measure (5.1.1) to the waypoint's cell; -1: not seen
  int matches = 0;
};

// One closed-loop run.
struct RouteRun {
  std::string name;                                   // "place cells" or "odometry only"
  std::vector<nav::Pose2> truth, estimate, odometry;  // at every control step
  std::vector<Eigen::Vector2d> fixes;                 // place-cell fixes (positions)
  std::vector<bool> fix_accepted;
  std::vector<WaypointArrival> arrivals;
  int laps_completed = 0;
  bool finished = false;  // all laps done within the time limit
  double sim_time_s = 0, distance_m = 0;
  int collisions = 0;
  int control_steps = 0, views = 0, localizations = 0, no_answer = 0;
  int64_t fixes_accepted = 0, fixes_rejected = 0, resets = 0;
  int homing_calls = 0, homing_estimates = 0, homing_steps = 0, homing_refused = 0;
  std::vector<HomingSample> homing;
  double tracking_error_mean_m = 0, tracking_error_max_m = 0;  // |estimate - truth| over the control steps
  double odometry_error_final_m = 0;                           // dead reckoning at the end
  // Wall time [ms]: per control step (everything), per view (render, MakePlaceView) and per call.
  double ms_per_step = 0, ms_render = 0, ms_view = 0, ms_localize = 0, ms_homing = 0;
};

struct LapErrors {
  int lap = 0;
  int arrivals = 0;
  double mean_m = 0, max_m = 0;
};
struct ArrivalSummary {
  int arrivals = 0;
  double mean_m = 0, median_m = 0, max_m = 0;
  std::vector<LapErrors> laps;
  double growth_m_per_lap = 0;        // least-squares slope of the arrival errors over the lap number
  double last_minus_first_lap_m = 0;  // mean of the last lap - mean of the first
};
ArrivalSummary SummarizeArrivals(const std::vector<WaypointArrival>& arrivals);

struct RouteEvalResult {
  std::string scene;
  int route = 1;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double size_m = 0;
  std::vector<Eigen::Vector2d> waypoints;
  std::vector<nav::Pose2> cells;  // the memory's cell poses
  int waypoints_per_lap = 0;
  double explore_seconds = 0;  // rendering and views of the memory
  double mean_landmarks = 0;   // per cell view
  RouteRun run, baseline;
  ArrivalSummary summary, baseline_summary;
};

// The thesis route square of a scene: its grid's lower-left position and the smaller side.
// Throws std::invalid_argument for a grid of fewer than 2 x 2 positions.
void RouteSquare(const nav::sim::GridSpec& grid, Eigen::Vector2d* origin, double* size_m);

// Explores, then runs both closed loops. `progress` gets text lines (second argument true: a
// line that replaces the previous one, "\r").
RouteEvalResult RunRouteEval(const nav::sim::Scene& scene, const RouteEvalOptions& options,
                             const std::function<void(const std::string&, bool)>& progress = {});

// Trajectories (truth, odometry, tracked estimate), the place-cell fixes, the cells and the
// waypoints with the 15 cm target circle, fitted to a square image.
cv::Mat DrawRouteMap(const RouteEvalResult& result, const std::string& title);

// summary.json, arrivals.csv, report.md, trajectory.png and waypoint_errors.png into out_dir.
void WriteRouteOutputs(const RouteEvalResult& result, const RouteEvalOptions& options, const std::string& out_dir,
                       const std::string& options_text);

// The target: every waypoint within 0.15 m.
inline constexpr double kTargetWaypointErrorM = 0.15;

}  // namespace snapnav::eval
