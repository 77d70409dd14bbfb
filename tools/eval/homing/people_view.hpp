#pragma once
// Where the simulated people are in a view: how near the camera, how much of the panorama they
// cover, and whether a given panorama pixel (a landmark) shows a person. For the diagnosis of
// homing among people (eval-homing --people-diagnosis).

#include <vector>

#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::eval {

struct PeopleInView {
  int people = 0;
  double nearest_surface_m = 0;   // camera to the nearest person's surface; negative: the camera is inside one
  int inside = 0;                 // people the camera stands inside
  double occluded_fraction = 0;   // share of the panorama (pixels) showing a person
};

class PeopleView {
 public:
  PeopleView(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera) : scene_(scene), camera_(camera) {}
  // The index of the person seen at panorama pixel (column, row) from robot pose `pose`, or -1.
  int PersonAt(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, double column_px,
               double row_px) const;
  // Whether a person is seen within `margin_px` columns of (column, row) on the same row.
  bool NearPerson(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, double column_px, double row_px,
                  double margin_px) const;
  // `rows_step`, `cols_step`: sampling of the panorama for the occluded fraction.
  PeopleInView Measure(const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, int cols_step = 2,
                       int rows_step = 4) const;

 private:
  const nav::sim::Scene& scene_;
  nav::sim::OmniCameraOptions camera_;
};

}  // namespace snapnav::eval
