#include "snapnav/nav/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace snapnav::nav::sim {
namespace {

// Light from above-left: faces turned towards it are brighter.
const Eigen::Vector2d kLightDir = Eigen::Vector2d(0.6, 0.8).normalized();

double ShadeOfNormal(const Eigen::Vector2d& n) { return 0.62 + 0.38 * std::abs(n.dot(kLightDir)); }

template <class Fn>
void ForEachHit(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& o,
                const Eigen::Vector2d& d, double min_height_m, Fn&& fn) {
  const bool filter = min_height_m >= 0;  // negative: every surface
  for (const Wall& w : scene.walls) {
    if (filter && (w.height_m <= min_height_m || w.bottom_m > min_height_m)) continue;
    const Eigen::Vector2d e = w.b - w.a;
    const double denom = d.x() * e.y() - d.y() * e.x();
    if (std::abs(denom) < 1e-12) continue;
    const Eigen::Vector2d ao = w.a - o;
    const double t = (ao.x() * e.y() - ao.y() * e.x()) / denom;
    const double s = (ao.x() * d.y() - ao.y() * d.x()) / denom;
    if (t <= 1e-9 || s < 0 || s > 1) continue;
    const double len = e.norm();
    const Eigen::Vector2d n(-e.y() / len, e.x() / len);
    fn(RayHit{t, w.height_m, w.bottom_m, w.texture, w.u_offset_m + s * len, ShadeOfNormal(n)});
  }
  auto cylinder = [&](const Cylinder& c) {
    if (filter && c.height_m <= min_height_m) return;
    const Eigen::Vector2d oc = o - c.center;
    const double b = oc.dot(d);
    const double cc = oc.squaredNorm() - c.radius_m * c.radius_m;
    const double disc = b * b - cc;
    if (disc < 0) return;
    const double sq = std::sqrt(disc);
    double t = -b - sq;
    if (t <= 1e-9) t = -b + sq;  // inside the cylinder: its far wall
    if (t <= 1e-9) return;
    const Eigen::Vector2d p = o + t * d;
    const Eigen::Vector2d n = (p - c.center) / c.radius_m;
    const double angle = std::atan2(n.y(), n.x());
    fn(RayHit{t, c.height_m, 0.0, c.texture, (angle + M_PI) * c.radius_m, ShadeOfNormal(n)});
  };
  for (const Cylinder& c : scene.cylinders) cylinder(c);
  for (const Cylinder& c : extra) cylinder(c);
}

double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d e = b - a;
  const double l2 = e.squaredNorm();
  const double s = l2 > 0 ? std::clamp((p - a).dot(e) / l2, 0.0, 1.0) : 0.0;
  return (a + s * e - p).norm();
}

}  // namespace

Texture MakeTexture(const std::string& name, const cv::Mat& image, double width_m, double height_m) {
  if (image.empty()) throw std::invalid_argument("texture '" + name + "' has no pixels");
  if (!(width_m > 0) || !(height_m > 0)) throw std::invalid_argument("texture '" + name + "' needs a positive size");
  Texture t;
  t.name = name;
  t.width_m = width_m;
  t.height_m = height_m;
  cv::Mat level;
  if (image.channels() == 1) {
    cv::cvtColor(image, level, cv::COLOR_GRAY2BGR);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, level, cv::COLOR_BGRA2BGR);
  } else {
    level = image.clone();
  }
  if (level.type() != CV_8UC3) throw std::invalid_argument("texture '" + name + "' must be 8-bit");
  t.levels.push_back(level);
  while (level.cols > 4 && level.rows > 4) {
    cv::Mat next;
    cv::pyrDown(level, next);
    t.levels.push_back(next);
    level = next;
  }
  return t;
}

void Scene::AddBox(const Eigen::Vector2d& center, double size_x_m, double size_y_m, double yaw_rad, double height_m,
                   int texture) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const double hx = size_x_m / 2, hy = size_y_m / 2;
  const Eigen::Vector2d corners[4] = {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
  double u = 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d& p = corners[i];
    const Eigen::Vector2d& q = corners[(i + 1) % 4];
    Wall w;
    w.a = center + Eigen::Vector2d(c * p.x() - s * p.y(), s * p.x() + c * p.y());
    w.b = center + Eigen::Vector2d(c * q.x() - s * q.y(), s * q.x() + c * q.y());
    w.height_m = height_m;
    w.texture = texture;
    w.u_offset_m = u;
    u += (q - p).norm();
    walls.push_back(w);
  }
}

void Scene::Validate() const {
  const int n = static_cast<int>(textures.size());
  auto check_texture = [&](int t, const std::string& what) {
    if (t < 0 || t >= n) throw std::invalid_argument("scene '" + name + "': " + what + " uses a missing texture");
  };
  for (const Wall& w : walls) {
    check_texture(w.texture, "a wall");
    if (!(w.height_m > w.bottom_m) || !(w.bottom_m >= 0) || (w.b - w.a).norm() <= 0) throw std::invalid_argument("scene '" + name + "': degenerate wall");
  }
  for (const Cylinder& c : cylinders) {
    check_texture(c.texture, "a cylinder");
    if (!(c.radius_m > 0) || !(c.height_m > 0)) throw std::invalid_argument("scene '" + name + "': degenerate cylinder");
  }
  if (floor_texture >= n || ceiling_texture >= n) throw std::invalid_argument("scene '" + name + "': missing floor/ceiling texture");
  for (int t : people.textures) check_texture(t, "people");
  if (people.count > 0 && people.textures.empty()) {
    throw std::invalid_argument("scene '" + name + "': people need at least one texture");
  }
  if (!(ceiling_height_m >= 0)) throw std::invalid_argument("scene '" + name + "': negative ceiling height");
}

void CastRay(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& origin,
             const Eigen::Vector2d& dir, double min_height_m, std::vector<RayHit>* hits) {
  hits->clear();
  ForEachHit(scene, extra, origin, dir, min_height_m, [&](const RayHit& h) { hits->push_back(h); });
  std::sort(hits->begin(), hits->end(), [](const RayHit& a, const RayHit& b) { return a.distance_m < b.distance_m; });
}

std::optional<RayHit> NearestHit(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& origin,
                                 const Eigen::Vector2d& dir, double min_height_m) {
  std::optional<RayHit> best;
  ForEachHit(scene, extra, origin, dir, min_height_m, [&](const RayHit& h) {
    if (!best || h.distance_m < best->distance_m) best = h;
  });
  return best;
}

double ClearanceAt(const Scene& scene, const std::vector<Cylinder>& extra, const Eigen::Vector2d& p,
                   double min_height_m) {
  double best = std::numeric_limits<double>::infinity();
  for (const Wall& w : scene.walls) {
    if (w.height_m > min_height_m && w.bottom_m <= min_height_m) best = std::min(best, SegmentDistance(p, w.a, w.b));
  }
  auto cylinder = [&](const Cylinder& c) {
    if (c.height_m > min_height_m) best = std::min(best, (p - c.center).norm() - c.radius_m);
  };
  for (const Cylinder& c : scene.cylinders) cylinder(c);
  for (const Cylinder& c : extra) cylinder(c);
  return best;
}

}  // namespace snapnav::nav::sim
