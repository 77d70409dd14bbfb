#pragma once
// Occupancy grid maps from laser scans at known poses (issue 22, "maps out"): MRPT's
// COccupancyGridMap2D (log-odds cells, each beam's free cells and its hit) and its CSimpleMap of
// (pose, scan) keyframes, so that MRPT's apps and ROS's map_server read the maps snapnav makes.
// Pure: the caller writes files (tools/map).
#include <cstdint>
#include <string>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimpleMap.h>

#include "snapnav/nav/slam/grid_scan.hpp"
#include "snapnav/nav/slam/occupancy_cells.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

struct OccupancyGridOptions {
  double resolution_m = 0.05;    // cell size [m]
  double max_range_m = 0;        // beams longer than this insert only their free cells up to it [m, 0: the laser's range]
  // A beam with no return clears nothing (MRPT's considerInvalidRangesAsFreeSpace is off: MRPT 2.5
  // crashes in COccupancyGridMap2D::resizeGrid when a scan with few returns is inserted with it on,
  // measured with 1 of 361 beams returning).
  double occupied_threshold = 0.65;  // exported as occupied at or above this probability (ROS's default)
  double free_threshold = 0.196;     // ... as free at or below it (ROS's default)
  // OccupancyGridBuilder::Insert skips a scan that would grow the grid beyond this many cells (a
  // live process's memory bound against absurd poses or ranges; 0: no limit).
  int64_t max_cells = 0;
  void Validate() const;          // throws std::invalid_argument naming the bad option
};

// MRPT's range scan of `scan` (its beams symmetric about the sensor's axis, as MRPT wants them:
// the sensor's heading turned so that its first beam has the scan's first bearing). MRPT's
// documented beam spacing (CObservation2DRangeScan::getScanAngle, point maps) is aperture / (N - 1);
// its occupancy grid's insertion (MRPT 2.5) spaces N beams by aperture / N from -aperture / 2
// (measured: the last of 5 beams 0.1 rad apart landed 0.083 rad short). `for_grid` sets the
// aperture so that the grid puts every beam at its bearing.
mrpt::obs::CObservation2DRangeScan ToMrptScan(const GridScan& scan, double max_range_m = 0, bool for_grid = false);

// The grid of every scan inserted at its pose; it grows to hold them. Throws std::invalid_argument
// on bad options or a scan with fewer than 2 beams.
mrpt::maps::COccupancyGridMap2D BuildOccupancyGrid(const std::vector<GridScan>& scans,
                                                   const OccupancyGridOptions& options);

// MRPT's simple map: each scan with its pose (a keyframe), the input of MRPT's map building apps.
mrpt::maps::CSimpleMap BuildSimpleMap(const std::vector<GridScan>& scans, double max_range_m = 0);

// The cells of `grid` (ROS's -1 / 0..100), counted by options' thresholds.
OccupancyCells ToOccupancyCells(const mrpt::maps::COccupancyGridMap2D& grid, const OccupancyGridOptions& options);
// The MRPT grid of `cells` (each known cell's probability of being free is 1 - occupancy / 100,
// unknown ones 0.5): a map read from a file or a message, for MRPT's tools (.gridmap).
mrpt::maps::COccupancyGridMap2D FromOccupancyCells(const OccupancyCells& cells);

// The grid built scan by scan (laser-slam's live map; BuildOccupancyGrid is this over a batch):
// each scan inserted at its pose as BuildOccupancyGrid does, the grid grown to hold it.
class OccupancyGridBuilder {
 public:
  explicit OccupancyGridBuilder(const OccupancyGridOptions& options);
  // Throws std::invalid_argument on a scan with fewer than 2 beams. False when the scan was not
  // inserted: no beam returned, or the grid would grow beyond options' max_cells.
  bool Insert(const GridScan& scan);
  // Makes the grid cover [x0, x1] x [y0, y1] (plus a margin) before inserting (one allocation).
  void Reserve(double x0, double x1, double y0, double y1);
  const mrpt::maps::COccupancyGridMap2D& grid() const { return grid_; }
  OccupancyCells Cells() const { return ToOccupancyCells(grid_, options_); }
  int64_t inserted() const { return inserted_; }
  int64_t too_large() const { return too_large_; }  // scans skipped for max_cells
  const OccupancyGridOptions& options() const { return options_; }

 private:
  OccupancyGridOptions options_;
  mrpt::maps::COccupancyGridMap2D grid_;
  bool sized_ = false;
  int64_t inserted_ = 0, too_large_ = 0;
};

}  // namespace snapnav::nav
