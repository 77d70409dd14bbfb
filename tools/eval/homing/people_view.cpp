#include "people_view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace snapnav::eval {

int PeopleView::PersonAt(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, double column_px,
                         double row_px) const {
  if (people.empty()) return -1;
  const nav::PanoramaModel& pm = camera_.panorama;
  const Eigen::Vector2d eye = pose.Transform({camera_.offset_x_m, 0.0});
  const double bearing = pose.theta_rad + pm.BearingOfColumn(column_px);
  const Eigen::Vector2d dir(std::cos(bearing), std::sin(bearing));
  const double te = std::tan(pm.ElevationOfRow(row_px));
  const double cam_z = camera_.height_m;
  // The scene's surface seen along the ray (as the renderer finds it), or the floor / ceiling.
  double scene_d = std::numeric_limits<double>::infinity();
  if (te < 0) scene_d = cam_z / -te;
  if (te > 0 && scene_.ceiling_height_m > 0) scene_d = (scene_.ceiling_height_m - cam_z) / te;
  std::vector<nav::sim::RayHit> hits;
  nav::sim::CastRay(scene_, {}, eye, dir, -1.0, &hits);
  for (const auto& h : hits) {
    if (h.distance_m >= scene_d) break;
    const double z = cam_z + h.distance_m * te;
    if (z >= h.bottom_m && z <= h.height_m) {
      scene_d = h.distance_m;
      break;
    }
  }
  int best = -1;
  double best_d = scene_d;
  for (size_t i = 0; i < people.size(); ++i) {
    const auto& c = people[i];
    const Eigen::Vector2d oc = eye - c.center;
    const double b = oc.dot(dir);
    const double disc = b * b - (oc.squaredNorm() - c.radius_m * c.radius_m);
    if (disc < 0) continue;
    double t = -b - std::sqrt(disc);
    if (t <= 1e-9) t = -b + std::sqrt(disc);  // inside: the far side
    if (t <= 1e-9 || t >= best_d) continue;
    const double z = cam_z + t * te;
    if (z < 0 || z > c.height_m) continue;
    best = static_cast<int>(i);
    best_d = t;
  }
  return best;
}

bool PeopleView::NearPerson(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, double column_px,
                            double row_px, double margin_px) const {
  const int w = camera_.panorama.width_px;
  const int steps = std::max(1, static_cast<int>(std::ceil(margin_px)));
  for (int s = -steps; s <= steps; ++s) {
    const double dx = margin_px * s / steps;
    double c = std::fmod(column_px + dx, static_cast<double>(w));
    if (c < 0) c += w;
    if (PersonAt(pose, people, c, row_px) >= 0) return true;
  }
  return false;
}

PeopleInView PeopleView::Measure(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, int cols_step,
                                 int rows_step) const {
  PeopleInView v;
  v.people = static_cast<int>(people.size());
  v.nearest_surface_m = std::numeric_limits<double>::infinity();
  const Eigen::Vector2d eye = pose.Transform({camera_.offset_x_m, 0.0});
  for (const auto& c : people) {
    const double d = (c.center - eye).norm() - c.radius_m;
    v.nearest_surface_m = std::min(v.nearest_surface_m, d);
    if (d < 0) ++v.inside;
  }
  if (people.empty()) return v;
  const nav::PanoramaModel& pm = camera_.panorama;
  int seen = 0, total = 0;
  for (int r = 0; r < pm.height_px; r += rows_step) {
    for (int c = 0; c < pm.width_px; c += cols_step) {
      ++total;
      if (PersonAt(pose, people, c, r) >= 0) ++seen;
    }
  }
  v.occluded_fraction = total ? static_cast<double>(seen) / total : 0.0;
  return v;
}

}  // namespace snapnav::eval
