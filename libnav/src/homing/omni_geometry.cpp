#include "snapnav/nav/homing/omni_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

void MirrorModel::Validate() const {
  // The messages name the calibration's keys (angles in degrees there).
  const std::pair<double, const char*> values[] = {{center_x_px, "center_x_px"},
                                                   {center_y_px, "center_y_px"},
                                                   {inner_radius_px, "inner_radius_px"},
                                                   {outer_radius_px, "outer_radius_px"},
                                                   {elevation_inner_rad, "elevation_inner_deg"},
                                                   {elevation_outer_rad, "elevation_outer_deg"}};
  for (const auto& [v, name] : values) {
    if (!std::isfinite(v)) throw std::invalid_argument(std::string("mirror: ") + name + " must be a finite number");
  }
  if (center_x_px < 0 || center_y_px < 0) {
    throw std::invalid_argument("mirror: the centre center_x_px, center_y_px (" + std::to_string(center_x_px) + ", " +
                                std::to_string(center_y_px) + ") must not be negative");
  }
  if (!(inner_radius_px >= 0) || !(outer_radius_px > inner_radius_px)) {
    throw std::invalid_argument("mirror: need 0 <= inner_radius_px < outer_radius_px");
  }
  if (!(elevation_outer_rad != elevation_inner_rad) || std::abs(elevation_inner_rad) >= M_PI / 2 ||
      std::abs(elevation_outer_rad) >= M_PI / 2) {
    throw std::invalid_argument(
        "mirror: elevation_inner_deg and elevation_outer_deg must differ and lie within (-90, 90)");
  }
}

void PanoramaModel::Validate() const {
  if (width_px < 8 || height_px < 2) throw std::invalid_argument("panorama: need width_px >= 8 and height_px >= 2");
  if (!(elevation_top_rad > elevation_bottom_rad) || std::abs(elevation_top_rad) >= M_PI / 2 ||
      std::abs(elevation_bottom_rad) >= M_PI / 2) {
    throw std::invalid_argument("panorama: need -90 < elevation_bottom_deg < elevation_top_deg < 90");
  }
}

double PanoramaModel::BearingOfColumn(double col) const {
  return WrapAngle(bearing_col0_rad - col * 2.0 * M_PI / width_px);
}

double PanoramaModel::ColumnOfBearing(double bearing_rad) const {
  double c = (bearing_col0_rad - bearing_rad) * width_px / (2.0 * M_PI);
  c = std::fmod(c, static_cast<double>(width_px));
  if (c < 0) c += width_px;
  return c;
}

double PanoramaModel::ElevationOfRow(double row) const {
  return elevation_top_rad + row * (elevation_bottom_rad - elevation_top_rad) / (height_px - 1);
}

double PanoramaModel::RowOfElevation(double elevation_rad) const {
  return (elevation_rad - elevation_top_rad) * (height_px - 1) / (elevation_bottom_rad - elevation_top_rad);
}

void MirrorProfile::Validate() const {
  if (!std::isfinite(elevation_rim_rad) || !std::isfinite(elevation_centre_rad) ||
      std::abs(elevation_rim_rad) >= M_PI / 2 || std::abs(elevation_centre_rad) >= M_PI / 2 ||
      elevation_rim_rad == elevation_centre_rad) {
    throw std::invalid_argument("mirror profile: elevations at the rim and the centre must differ and lie within (-90, 90) deg");
  }
}

MirrorProfile MirrorProfile::FromMirror(const MirrorModel& m) {
  m.Validate();
  MirrorProfile p;
  const double rho = m.inner_radius_px / m.outer_radius_px;
  p.elevation_rim_rad = m.elevation_outer_rad;
  p.elevation_centre_rad = m.elevation_outer_rad - (m.elevation_outer_rad - m.elevation_inner_rad) / (1.0 - rho);
  // Kept inside (-90, 90) for the model's validity: a steep profile extrapolated to the centre.
  p.elevation_centre_rad = std::clamp(p.elevation_centre_rad, -89.9 * M_PI / 180, 89.9 * M_PI / 180);
  return p;
}

MirrorModel MirrorWithRadii(double cx, double cy, double inner, double outer, const MirrorProfile& profile) {
  MirrorModel m;
  m.center_x_px = cx;
  m.center_y_px = cy;
  m.inner_radius_px = inner;
  m.outer_radius_px = outer;
  m.elevation_inner_rad = profile.ElevationAt(outer > 0 ? inner / outer : 0);
  m.elevation_outer_rad = profile.ElevationAt(1.0);
  return m;
}

std::optional<Eigen::Vector2d> MirrorPixel(const MirrorModel& m, double bearing_rad, double elevation_rad) {
  const double f = (elevation_rad - m.elevation_inner_rad) / (m.elevation_outer_rad - m.elevation_inner_rad);
  if (f < 0 || f > 1) return std::nullopt;
  const double r = m.inner_radius_px + f * (m.outer_radius_px - m.inner_radius_px);
  return Eigen::Vector2d(m.center_x_px - r * std::sin(bearing_rad), m.center_y_px - r * std::cos(bearing_rad));
}

std::optional<Eigen::Vector2d> MirrorDirection(const MirrorModel& m, double u_px, double v_px) {
  const double dx = m.center_x_px - u_px, dy = m.center_y_px - v_px;
  const double r = std::hypot(dx, dy);
  if (r < m.inner_radius_px || r > m.outer_radius_px) return std::nullopt;
  const double f = (r - m.inner_radius_px) / (m.outer_radius_px - m.inner_radius_px);
  return Eigen::Vector2d(std::atan2(dx, dy), m.elevation_inner_rad + f * (m.elevation_outer_rad - m.elevation_inner_rad));
}

}  // namespace snapnav::nav
