#pragma once
// Geometry of omnidirectional images (conventions of snapnav::omni_frame_t).
//
// Raw catadioptric image: bearing theta (robot frame, counter-clockwise, 0 =
// forward) appears at u = cx - r sin(theta), v = cy - r cos(theta); the
// elevation grows linearly with r from elevation_inner_rad to elevation_outer_rad.
// Panorama: column c looks at bearing_col0_rad - c * 2 pi / width_px; row 0 at
// elevation_top_rad, the last row at elevation_bottom_rad.

#include <optional>

#include <Eigen/Core>

namespace snapnav::nav {

struct MirrorModel {
  double center_x_px = 320;
  double center_y_px = 240;
  double inner_radius_px = 40;
  double outer_radius_px = 230;
  double elevation_inner_rad = -0.70;  // looking down at the floor near the robot
  double elevation_outer_rad = 0.35;   // looking up above the horizon
  void Validate() const;               // throws std::invalid_argument
};

struct PanoramaModel {
  int width_px = 720;
  int height_px = 120;
  double bearing_col0_rad = 3.14159265358979323846;  // column width/2 looks forward
  double elevation_top_rad = 0.35;
  double elevation_bottom_rad = -0.35;
  void Validate() const;  // throws std::invalid_argument

  double BearingOfColumn(double col) const;
  // Column (fractional, in [0, width)) that looks at `bearing_rad`.
  double ColumnOfBearing(double bearing_rad) const;
  double ElevationOfRow(double row) const;
  double RowOfElevation(double elevation_rad) const;
};

// The mirror's elevation profile, scale-free: the stack's model is linear in the radius
// (omni_geometry.hpp), e(rho) = elevation_centre + rho * (elevation_rim - elevation_centre) with
// rho = r / rim radius. docs/calibration.md derives the two numbers from a mirror's datasheet
// or its profile (equiangular, hyperbolic).
struct MirrorProfile {
  double elevation_rim_rad = 20 * 3.14159265358979323846 / 180;      // seen at the rim
  double elevation_centre_rad = -52.63 * 3.14159265358979323846 / 180;  // the line extended to rho = 0
  void Validate() const;  // throws std::invalid_argument
  double ElevationAt(double rho) const { return elevation_centre_rad + rho * (elevation_rim_rad - elevation_centre_rad); }
  // The profile a calibration implies (its elevations at its inner and outer radius), with the
  // outer radius as the rim.
  static MirrorProfile FromMirror(const MirrorModel& mirror);
};

// A calibration with another inner radius: the elevation at it from the profile.
MirrorModel MirrorWithRadii(double center_x_px, double center_y_px, double inner_radius_px, double outer_radius_px,
                            const MirrorProfile& profile);

// Pixel (u, v) of the raw image that sees (bearing, elevation); nullopt outside the mirror ring.
std::optional<Eigen::Vector2d> MirrorPixel(const MirrorModel& mirror, double bearing_rad, double elevation_rad);
// Bearing and elevation seen by raw pixel (u, v); nullopt outside the mirror ring.
std::optional<Eigen::Vector2d> MirrorDirection(const MirrorModel& mirror, double u_px, double v_px);

}  // namespace snapnav::nav
