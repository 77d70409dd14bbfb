#pragma once
// A simulated world: a 2D floor plan with heights. Vertical surfaces (walls,
// box faces, doors, cylinders) carry textures; the floor and the ceiling too.
// Pure data and geometry: loading a scene file lives outside libnav.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace snapnav::nav::sim {

// A texture with its mip pyramid; one repeat covers width_m x height_m.
struct Texture {
  std::string name;
  std::vector<cv::Mat> levels;  // CV_8UC3 (BGR), level 0 full resolution, each next half size
  double width_m = 1.0;
  double height_m = 1.0;
};
// Builds the mip pyramid of `image` (CV_8UC3 or CV_8UC1). Throws std::invalid_argument on an empty image.
Texture MakeTexture(const std::string& name, const cv::Mat& image, double width_m, double height_m);

// A vertical rectangle along segment a-b from bottom_m to height_m above the
// floor (a poster or window has bottom_m > 0); visible from both sides.
struct Wall {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  double height_m = 2.5;
  double bottom_m = 0.0;
  int texture = 0;
  double u_offset_m = 0;  // texture coordinate at `a` [m]
};

// A vertical cylinder standing on the floor (pillars, bins, and people).
struct Cylinder {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius_m = 0.2;
  double height_m = 1.0;
  int texture = 0;
};

// The grid of image positions of the thesis' databases (Appendix A).
struct GridSpec {
  double origin_x_m = 0;  // position of grid cell (0, 0)
  double origin_y_m = 0;
  double spacing_m = 0.2;
  int nx = 0;
  int ny = 0;
  Eigen::Vector2d Position(int ix, int iy) const { return {origin_x_m + ix * spacing_m, origin_y_m + iy * spacing_m}; }
};

// Moving people: random-waypoint walkers inside an area.
struct PeopleSpec {
  int count = 0;
  double radius_m = 0.22;
  double height_m = 1.75;
  double speed_mps = 0.8;
  Eigen::Vector2d area_min = Eigen::Vector2d::Zero();
  Eigen::Vector2d area_max = Eigen::Vector2d::Zero();
  std::vector<int> textures;  // clothing, picked per person
};

struct Scene {
  std::string name;
  std::vector<Texture> textures;
  std::vector<Wall> walls;
  std::vector<Cylinder> cylinders;
  double ceiling_height_m = 2.6;  // 0: open sky
  int floor_texture = -1;         // -1: plain floor colour
  int ceiling_texture = -1;       // -1: plain ceiling colour
  cv::Vec3b floor_bgr{90, 100, 110};
  cv::Vec3b ceiling_bgr{225, 225, 220};
  cv::Vec3b sky_bgr{235, 200, 150};
  GridSpec grid;
  std::vector<Eigen::Vector2d> route;  // waypoints of the scripted driver
  Eigen::Vector3d start_pose = Eigen::Vector3d::Zero();  // x [m], y [m], theta [rad]
  PeopleSpec people;

  // Adds the four faces of a box centred at (cx, cy), size_x by size_y, rotated by yaw.
  void AddBox(const Eigen::Vector2d& center, double size_x_m, double size_y_m, double yaw_rad, double height_m,
              int texture);
  // Throws std::invalid_argument when an element refers to a missing texture or has a bad size.
  void Validate() const;
};

// The nearest surface along a horizontal ray.
struct RayHit {
  double distance_m = 0;
  double height_m = 0;  // top of the surface that was hit
  double bottom_m = 0;  // bottom of the surface that was hit
  int texture = 0;
  double u_m = 0;       // horizontal texture coordinate [m]
  double shade = 1;     // lighting factor from the surface normal
};

// All surfaces crossed by the ray from `origin` along unit `dir` (walls, the scene's
// cylinders and `extra` cylinders), nearest first; only those spanning height min_height_m
// (a negative min_height_m: every surface).
void CastRay(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& origin,
             const Eigen::Vector2d& dir, double min_height_m, std::vector<RayHit>* hits);
// The nearest surface taller than min_height_m, or nullopt.
std::optional<RayHit> NearestHit(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& origin,
                                 const Eigen::Vector2d& dir, double min_height_m);
// Distance from point p to the nearest surface taller than min_height_m (for collisions).
double ClearanceAt(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& p,
                   double min_height_m);

}  // namespace snapnav::nav::sim
