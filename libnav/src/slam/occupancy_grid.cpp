#include "snapnav/nav/slam/occupancy_grid.hpp"

#include <cmath>
#include <limits>
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
  if (max_cells < 0) throw std::invalid_argument("occupancy grid: max_cells must be >= 0");
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

namespace {
// The corners of what `scan` covers at its pose (its sensor and every valid beam's end); false
// when no beam returned.
bool ScanBounds(const GridScan& scan, const OccupancyGridOptions& options, double* x0, double* x1, double* y0,
                double* y1) {
  const Pose2 sensor = scan.robot_pose.Compose(scan.sensor_on_robot);
  const double limit = options.max_range_m > 0 ? std::min<double>(options.max_range_m, scan.range_max_m) : scan.range_max_m;
  bool any = false;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const float r = scan.ranges_m[i];
    const bool valid = std::isfinite(r) && r >= scan.range_min_m && r < scan.range_max_m && r < limit;
    if (!valid) continue;
    const double range = r;
    const double a = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const Eigen::Vector2d end = sensor.Transform(Eigen::Vector2d(range * std::cos(a), range * std::sin(a)));
    if (!any) {
      *x0 = *x1 = end.x();
      *y0 = *y1 = end.y();
      any = true;
    }
    *x0 = std::min({*x0, end.x(), sensor.x_m});
    *x1 = std::max({*x1, end.x(), sensor.x_m});
    *y0 = std::min({*y0, end.y(), sensor.y_m});
    *y1 = std::max({*y1, end.y(), sensor.y_m});
  }
  return any;
}
constexpr double kMargin = 1.0;
}  // namespace

OccupancyGridBuilder::OccupancyGridBuilder(const OccupancyGridOptions& options) : options_(options) {
  options_.Validate();
  grid_.insertionOptions.considerInvalidRangesAsFreeSpace = false;  // see the header
  grid_.insertionOptions.maxDistanceInsertion = 1e4f;  // the scans' own limits (ToMrptScan) apply
}

void OccupancyGridBuilder::Reserve(double x0, double x1, double y0, double y1) {
  const float res = static_cast<float>(options_.resolution_m);
  if (!sized_) {
    grid_.setSize(static_cast<float>(x0 - kMargin), static_cast<float>(x1 + kMargin), static_cast<float>(y0 - kMargin),
                  static_cast<float>(y1 + kMargin), res);
    sized_ = true;
    return;
  }
  if (x0 >= grid_.getXMin() && x1 <= grid_.getXMax() && y0 >= grid_.getYMin() && y1 <= grid_.getYMax()) return;
  // Grown with a margin of its own, so that a robot exploring does not resize on every scan.
  grid_.resizeGrid(static_cast<float>(std::min<double>(x0 - kMargin, grid_.getXMin())),
                   static_cast<float>(std::max<double>(x1 + kMargin, grid_.getXMax())),
                   static_cast<float>(std::min<double>(y0 - kMargin, grid_.getYMin())),
                   static_cast<float>(std::max<double>(y1 + kMargin, grid_.getYMax())), 0.5f, true);
}

bool OccupancyGridBuilder::Insert(const GridScan& scan) {
  double x0, x1, y0, y1;
  const mrpt::obs::CObservation2DRangeScan obs = ToMrptScan(scan, options_.max_range_m, true);  // throws on < 2 beams
  if (!ScanBounds(scan, options_, &x0, &x1, &y0, &y1)) return false;  // no return: nothing to insert (no beam clears)
  if (options_.max_cells > 0) {
    if (sized_) {
      x0 = std::min<double>(x0, grid_.getXMin()), x1 = std::max<double>(x1, grid_.getXMax());
      y0 = std::min<double>(y0, grid_.getYMin()), y1 = std::max<double>(y1, grid_.getYMax());
    }
    const double cells = (x1 - x0 + 2 * kMargin) / options_.resolution_m * ((y1 - y0 + 2 * kMargin) / options_.resolution_m);
    if (!(cells <= static_cast<double>(options_.max_cells))) {
      ++too_large_;
      return false;
    }
  }
  Reserve(x0, x1, y0, y1);
  grid_.insertObservation(obs, Pose3(scan.robot_pose));
  ++inserted_;
  return true;
}

mrpt::maps::COccupancyGridMap2D BuildOccupancyGrid(const std::vector<GridScan>& scans,
                                                   const OccupancyGridOptions& options) {
  OccupancyGridBuilder builder(options);
  // The grid sized once to hold every beam's end (one allocation, no resizing as scans arrive).
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  bool any = false;
  for (const GridScan& scan : scans) {
    double a0, a1, b0, b1;
    if (!ScanBounds(scan, options, &a0, &a1, &b0, &b1)) continue;
    if (!any) {
      x0 = a0, x1 = a1, y0 = b0, y1 = b1;
      any = true;
    }
    x0 = std::min(x0, a0), x1 = std::max(x1, a1), y0 = std::min(y0, b0), y1 = std::max(y1, b1);
  }
  builder.Reserve(x0, x1, y0, y1);
  for (const GridScan& scan : scans) builder.Insert(scan);
  return builder.grid();
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
  using Grid = mrpt::maps::COccupancyGridMap2D;
  using LogOdds = Grid::cellType;
  constexpr int kMin = std::numeric_limits<LogOdds>::min(), kMax = std::numeric_limits<LogOdds>::max();
  OccupancyCells c;
  c.resolution_m = grid.getResolution();
  c.origin_x_m = grid.getXMin();
  c.origin_y_m = grid.getYMin();
  c.width = static_cast<int>(grid.getSizeX());
  c.height = static_cast<int>(grid.getSizeY());
  const size_t n = static_cast<size_t>(c.width) * static_cast<size_t>(c.height);
  const std::vector<LogOdds>& raw = grid.getRawMap();  // row-major, getCell(x, y) = l2p(raw[x + y * width])
  if (raw.size() != n) throw std::logic_error("occupancy grid: MRPT's cell buffer does not match its size");
  // A cell's value depends only on its log-odds: the value of every log-odds once (what getCell
  // gives, as a probability of the cell being free; 0.5 exactly: never observed), then one table
  // lookup per cell (10 million cells: 15 ms, against 25-80 ms with getCell per cell; on the scan thread).
  std::vector<int8_t> value(static_cast<size_t>(kMax - kMin + 1));
  std::vector<uint8_t> kind(value.size());  // 0 unknown, 1 occupied, 2 free, 3 neither (by the thresholds)
  for (int l = kMin; l <= kMax; ++l) {
    const size_t k = static_cast<size_t>(l - kMin);
    const float free_p = Grid::l2p(static_cast<LogOdds>(l));
    const double occ = 1.0 - free_p;
    value[k] = free_p == 0.5f ? int8_t{-1} : static_cast<int8_t>(std::lround(100.0 * occ));
    kind[k] = free_p == 0.5f ? 0 : occ >= options.occupied_threshold ? 1 : occ <= options.free_threshold ? 2 : 3;
  }
  c.cells.resize(n);
  int64_t unknown = 0, occupied = 0, free = 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t k = static_cast<size_t>(static_cast<int>(raw[i]) - kMin);
    c.cells[i] = value[k];
    const uint8_t t = kind[k];
    unknown += t == 0;
    occupied += t == 1;
    free += t == 2;
  }
  c.unknown = static_cast<int>(unknown);
  c.occupied = static_cast<int>(occupied);
  c.free = static_cast<int>(free);
  return c;
}

mrpt::maps::COccupancyGridMap2D FromOccupancyCells(const OccupancyCells& cells) {
  if (!(cells.resolution_m > 0) || cells.width <= 0 || cells.height <= 0 ||
      cells.cells.size() != static_cast<size_t>(cells.width) * static_cast<size_t>(cells.height)) {
    throw std::invalid_argument("occupancy grid: cells of a bad size or resolution");
  }
  const double res = cells.resolution_m;
  mrpt::maps::COccupancyGridMap2D grid(static_cast<float>(cells.origin_x_m), static_cast<float>(cells.origin_x_m + cells.width * res),
                                       static_cast<float>(cells.origin_y_m), static_cast<float>(cells.origin_y_m + cells.height * res),
                                       static_cast<float>(res));
  const int w = std::min<int>(cells.width, static_cast<int>(grid.getSizeX()));
  const int h = std::min<int>(cells.height, static_cast<int>(grid.getSizeY()));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int8_t v = cells.at(x, y);
      grid.setCell(x, y, v < 0 ? 0.5f : static_cast<float>(1.0 - std::min<int>(v, 100) / 100.0));
    }
  }
  return grid;
}

}  // namespace snapnav::nav
