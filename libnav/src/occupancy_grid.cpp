#include "snapnav/nav/occupancy_grid.hpp"

#include <cmath>
#include <stdexcept>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

namespace snapnav::nav {

void OccupancyGridOptions::Validate() const {
  if (!(resolution_m > 0.005 && resolution_m <= 10)) throw std::invalid_argument("occupancy grid: resolution_m must be in (0.005, 10] m");
  if (!(max_range_m >= 0)) throw std::invalid_argument("occupancy grid: max_range_m must be >= 0");
  if (!(free_threshold >= 0 && free_threshold < occupied_threshold && occupied_threshold <= 1))
    throw std::invalid_argument("occupancy grid: need 0 <= free_threshold < occupied_threshold <= 1");
}

namespace {
mrpt::poses::CPose3D Pose3(const Pose2& p) { return mrpt::poses::CPose3D(p.x_m, p.y_m, 0, p.theta_rad, 0, 0); }
}  // namespace

mrpt::obs::CObservation2DRangeScan ToMrptScan(const GridScan& scan, double max_range_m, bool for_grid) {
  const size_t n = scan.ranges_m.size();
  if (n < 2) throw std::invalid_argument("occupancy grid: a scan needs at least 2 beams");
  mrpt::obs::CObservation2DRangeScan obs;
  obs.timestamp = mrpt::Clock::fromDouble(static_cast<double>(scan.utime) * 1e-6);
  const double spans = static_cast<double>(for_grid ? n : n - 1);  // see the header
  const double aperture = std::abs(scan.angle_increment_rad) * spans;
  obs.aperture = static_cast<float>(aperture);
  obs.rightToLeft = scan.angle_increment_rad >= 0;
  const float limit = max_range_m > 0 ? static_cast<float>(std::min<double>(max_range_m, scan.range_max_m)) : scan.range_max_m;
  obs.maxRange = limit;
  // MRPT's beams run from -aperture / 2 to +aperture / 2 about the sensor's axis: turn the sensor
  // so that its first beam has the scan's bearing.
  const double centre = scan.angle_min_rad + (obs.rightToLeft ? 0.5 : -0.5) * aperture;
  const Pose2 sensor{scan.sensor_on_robot.x_m, scan.sensor_on_robot.y_m, scan.sensor_on_robot.theta_rad + centre};
  obs.sensorPose = Pose3(sensor);
  obs.resizeScan(n);
  for (size_t i = 0; i < n; ++i) {
    const float r = scan.ranges_m[i];
    const bool valid = std::isfinite(r) && r >= scan.range_min_m && r < scan.range_max_m && r < limit;
    obs.setScanRange(i, valid ? r : limit);
    obs.setScanRangeValidity(i, valid);
  }
  return obs;
}

mrpt::maps::COccupancyGridMap2D BuildOccupancyGrid(const std::vector<GridScan>& scans,
                                                   const OccupancyGridOptions& options) {
  options.Validate();
  const float res = static_cast<float>(options.resolution_m);
  // The grid sized once to hold every beam's end (one allocation, no resizing as scans arrive).
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  bool any = false;
  for (const GridScan& scan : scans) {
    const Pose2 sensor = scan.robot_pose.Compose(scan.sensor_on_robot);
    const double limit = options.max_range_m > 0 ? std::min<double>(options.max_range_m, scan.range_max_m) : scan.range_max_m;
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      const float r = scan.ranges_m[i];
      const bool valid = std::isfinite(r) && r >= scan.range_min_m && r < scan.range_max_m && r < limit;
      if (!valid) continue;
      const double range = r;
      const double a = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
      const Eigen::Vector2d end = sensor.Transform(Eigen::Vector2d(range * std::cos(a), range * std::sin(a)));
      if (!any) {
        x0 = x1 = end.x();
        y0 = y1 = end.y();
        any = true;
      }
      x0 = std::min({x0, end.x(), sensor.x_m});
      x1 = std::max({x1, end.x(), sensor.x_m});
      y0 = std::min({y0, end.y(), sensor.y_m});
      y1 = std::max({y1, end.y(), sensor.y_m});
    }
  }
  constexpr double kMargin = 1.0;
  mrpt::maps::COccupancyGridMap2D grid(static_cast<float>(x0 - kMargin), static_cast<float>(x1 + kMargin),
                                       static_cast<float>(y0 - kMargin), static_cast<float>(y1 + kMargin), res);
  grid.insertionOptions.considerInvalidRangesAsFreeSpace = false;  // see the header
  grid.insertionOptions.maxDistanceInsertion = 1e4f;  // the scans' own limits (ToMrptScan) apply
  for (const GridScan& scan : scans) {
    const mrpt::obs::CObservation2DRangeScan obs = ToMrptScan(scan, options.max_range_m, true);
    grid.insertObservation(obs, Pose3(scan.robot_pose));
  }
  return grid;
}

mrpt::maps::CSimpleMap BuildSimpleMap(const std::vector<GridScan>& scans, double max_range_m) {
  mrpt::maps::CSimpleMap map;
  for (const GridScan& scan : scans) {
    auto sf = mrpt::obs::CSensoryFrame::Create();
    sf->insert(mrpt::obs::CObservation2DRangeScan::Create(ToMrptScan(scan, max_range_m)));
    auto pose = mrpt::poses::CPose3DPDFGaussian::Create();
    pose->mean = Pose3(scan.robot_pose);
    map.insert(pose, sf);
  }
  return map;
}

OccupancyCells ToOccupancyCells(const mrpt::maps::COccupancyGridMap2D& grid, const OccupancyGridOptions& options) {
  OccupancyCells c;
  c.resolution_m = grid.getResolution();
  c.origin_x_m = grid.getXMin();
  c.origin_y_m = grid.getYMin();
  c.width = static_cast<int>(grid.getSizeX());
  c.height = static_cast<int>(grid.getSizeY());
  c.cells.resize(static_cast<size_t>(c.width) * static_cast<size_t>(c.height));
  for (int y = 0; y < c.height; ++y) {
    for (int x = 0; x < c.width; ++x) {
      // MRPT's cell value is the probability of the cell being free; 0.5 exactly: never observed.
      const float free_p = grid.getCell(x, y);
      int8_t v;
      if (free_p == 0.5f) {
        v = -1;
        ++c.unknown;
      } else {
        const double occ = 1.0 - free_p;
        v = static_cast<int8_t>(std::lround(100.0 * occ));
        if (occ >= options.occupied_threshold) ++c.occupied;
        else if (occ <= options.free_threshold) ++c.free;
      }
      c.cells[static_cast<size_t>(y) * static_cast<size_t>(c.width) + static_cast<size_t>(x)] = v;
    }
  }
  return c;
}

}  // namespace snapnav::nav
