#pragma once
// The viewer's picture (library snapnav_viewer_render, no LCM): what the viewer has seen, as plain
// data (ViewerScene), and one function drawing it into an image: the top view with the laser map,
// every pose channel's trajectory with its covariance ellipses, the ground truth, place cells, the
// laser scan of the moment and the homing vector at the robot; a side panel with the legend and the
// figures; the current panorama with its landmarks and the homing direction below.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::viewer {

struct PoseSample {
  int64_t utime = 0;
  nav::Pose2 pose;       // drawn: as published, or as the estimator's newest correction puts it
  nav::Pose2 published;  // as published
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // (x, y, theta); zero: unknown
};

// One pose channel: its trajectory (thinned), the latest pose (always exact) and the count.
struct Track {
  std::string estimator;  // pose_t estimator of the last message
  std::string frame;      // pose_t frame of the last message
  std::vector<PoseSample> poses;
  PoseSample latest;
  int64_t received = 0;
  // The message times of the jumps its estimator announced (laser SLAM's graph corrections): the
  // trail is not joined across them and a ring marks where each landed.
  std::vector<int64_t> jumps;
};

// The current panorama (BGR or grey) and the bearing of its column 0 [rad]; column c looks at
// bearing_col0_rad - c * 2 pi / width (omni_frame_t's convention).
struct PanoramaView {
  cv::Mat image;
  int64_t utime = 0;
  double bearing_col0_rad = 0;
  std::string source;  // channel, and "unwrapped" when it came from a raw frame
};

// One landmark set: bearings [rad] and rows in a panorama of width x height px.
struct LandmarkMarks {
  int64_t utime = 0;
  std::string method;  // "vline", "sift", ...
  int panorama_width_px = 0, panorama_height_px = 0;
  std::vector<float> bearings_rad, rows_px;
};

struct HomingView {
  int64_t utime = 0;
  bool valid = false;
  double direction_rad = 0;         // robot frame, counter-clockwise
  double magnitude = 0;
  double compass_rotation_rad = 0;  // current view relative to home
  int landmarks_used = 0;
  std::string method;               // "hog", "sift", ...
  std::string alv_variant;
};

struct PlaceCellMark {
  int64_t utime = 0;
  int cell_id = -1;
  double x_m = 0, y_m = 0, theta_rad = 0;
  double distance = 0, score = 0;
};

// The latest laser sweep in the sensor frame, with the sensor's mounting on the robot.
struct ScanView {
  int64_t utime = 0;
  nav::Pose2 mount;
  std::vector<cv::Point2f> points;  // returns only (range in [min, max)) [m], sensor frame
};

// The last occupancy grid (occupancy_grid_t), drawn under everything else.
struct GridView {
  int64_t utime = 0;
  std::string source;
  double resolution_m = 0, origin_x_m = 0, origin_y_m = 0, origin_theta_rad = 0;
  int width = 0, height = 0;
  std::vector<int8_t> cells;  // -1 unknown, 0 free .. 100 occupied, row-major from cell (0, 0)
  // The world rectangle of its known cells (the view widens to it); empty when none is known.
  double known_x0 = 0, known_x1 = 0, known_y0 = 0, known_y1 = 0;
  bool any_known = false;
};

struct ViewerScene {
  std::map<std::string, Track> tracks;  // by channel, ground truth included
  std::string truth_channel;            // the ground-truth channel's name
  std::vector<cv::Point2f> map_points;  // the last point map [m]
  std::string map_estimator;
  int64_t map_utime = 0;
  std::optional<GridView> grid;         // the last occupancy grid
  std::vector<PlaceCellMark> matches;   // matched cells (cell_id >= 0), oldest first
  std::vector<cv::Point2f> memory_cells;  // the memory file's cells [m], when given
  std::optional<PanoramaView> panorama;
  std::map<std::string, LandmarkMarks> landmarks;  // by channel
  std::optional<HomingView> homing;
  std::optional<ScanView> scan;
  int64_t first_utime = 0, latest_utime = 0;  // message time seen [us]; 0: nothing yet
  std::map<std::string, int64_t> channel_counts;  // messages per channel
  int64_t rejected = 0;                  // messages that did not decode or were refused
  std::string source;                    // where the messages come from (the LCM URL)
};

struct RenderOptions {
  cv::Size size{1400, 1000};  // the whole picture [px]; at least 900 x 700
  double ellipse_sigma = 2;           // covariance ellipses at this many standard deviations
  double ellipse_interval_s = 2;      // along a trajectory, one ellipse per this much message time [s]
  double min_span_m = 2;              // the top view shows at least this much on each axis [m]
  // The first of these channels that has a pose places the robot: the scan and the homing
  // vector are drawn there.
  std::vector<std::string> robot_pose_channels;
  double scan_max_age_s = 0.5;        // the scan is drawn when the robot pose is this close in time [s]
  int homing_arrow_px = 70;
  std::string title = "snapnav viewer";
  void Validate() const;  // throws std::invalid_argument
};

// Where the parts go in a picture of `size`.
struct Layout {
  cv::Rect map;       // the top view's plot area (axis labels outside it)
  cv::Rect panel;     // legend and figures
  cv::Rect panorama;  // the panorama image (scaled to this rectangle)
};
Layout ComputeLayout(cv::Size size);

// The colour of a pose channel (BGR): fixed colours for snapnav's estimators (after any channel
// prefix): ground truth black, dead reckoning orange, laser SLAM blue, the fused EKF red, RatSLAM
// purple, place cells green; other channels get one of the remaining palette colours by name.
cv::Scalar ChannelColour(const std::string& channel);
// The colour of a landmark method's marks on the panorama ("vline", "sift", "surf", "hog").
cv::Scalar LandmarkColour(const std::string& method);
extern const cv::Scalar kHomingColour;    // the homing vector
extern const cv::Scalar kMapColour;       // laser map points
extern const cv::Scalar kGridOccupiedColour;  // occupied cells of the occupancy grid (free ones are a light grey)
extern const cv::Scalar kScanColour;      // the scan of the moment
extern const cv::Scalar kPlaceCellColour; // place cells

// The robot pose RenderScene uses: the latest pose of the first robot_pose_channels channel that
// has one (a channel name matches with or without a prefix), else nullopt.
std::optional<std::pair<std::string, PoseSample>> RobotPose(const ViewerScene& scene, const RenderOptions& options);

// The picture (CV_8UC3). Throws std::invalid_argument for invalid options.
cv::Mat RenderScene(const ViewerScene& scene, const RenderOptions& options);

// Several views (BGR, e.g. one robot's RenderScene each) in one picture at most max_width_px wide:
// a row of up to 3, then a grid of ceil(sqrt(n)) columns; each view scaled to its cell with its
// title in a band above it. Throws std::invalid_argument on no views or a title count that differs.
cv::Mat TileViews(const std::vector<cv::Mat>& views, const std::vector<std::string>& titles, int max_width_px);

}  // namespace snapnav::viewer
