#pragma once
// Map files from an occupancy grid: ROS map_server's PGM + YAML, MRPT's .gridmap and .simplemap,
// and a PNG with the trajectory to look at (./snapnav map export).
#include <string>
#include <vector>

#include "snapnav/nav/slam/occupancy_grid.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::map {

// DIR/NAME.pgm (binary P5, row 0 the top: the largest y) and DIR/NAME.yaml (image, resolution,
// origin [x, y, yaw] of the lower-left pixel, negate, occupied_thresh, free_thresh, mode trinary):
// occupied 0, free 254, unknown 205, as ROS's map_saver writes them. Throws std::runtime_error
// naming the file when it cannot be written.
void WriteRosMap(const nav::OccupancyCells& cells, const nav::OccupancyGridOptions& options, const std::string& dir,
                 const std::string& name = "map");

// MRPT's files, gzip-compressed serializations as MRPT's apps write and read them.
void WriteGridmap(const mrpt::maps::COccupancyGridMap2D& grid, const std::string& path);
void WriteSimplemap(const mrpt::maps::CSimpleMap& map, const std::string& path);
// Reads a .gridmap back (MRPT's own reader); throws std::runtime_error naming the file.
mrpt::maps::COccupancyGridMap2D ReadGridmap(const std::string& path);

// The occupancy grid of MRPT's keyframes (.simplemap[.gz]: icp-slam's and map-export's output):
// each 2D laser scan inserted at its pose, at `options`' resolution, as map-export builds its grids.
// Throws std::runtime_error naming the file when it is not a simple map or holds no keyframe
// (ReadMapFile also refuses one whose grid has no wall or no free cell: no 2D laser scan).
mrpt::maps::COccupancyGridMap2D GridFromSimplemap(const std::string& path, const nav::OccupancyGridOptions& options = {});

// A saved map as cells: PATH.yaml (ROS map_server's YAML and the image it names, PGM or PNG:
// occupancy = (255 - pixel) / 255, or pixel / 255 with negate: 1; trinary mode: above
// occupied_thresh 100, below free_thresh 0, else unknown; scale mode: in between scaled),
// PATH.gridmap[.gz] (MRPT's, cells counted with `options`' thresholds) or PATH.simplemap[.gz] (MRPT's
// keyframes, GridFromSimplemap). The origin's yaw must be 0.
// Throws std::runtime_error naming the file and what is wrong.
nav::OccupancyCells ReadMapFile(const std::string& path, const nav::OccupancyGridOptions& options = {});

// A PNG of the trinary map with `trajectory` drawn over it (red), one pixel per cell.
void WriteMapPng(const nav::OccupancyCells& cells, const nav::OccupancyGridOptions& options,
                 const std::vector<nav::Pose2>& trajectory, const std::string& path);

}  // namespace snapnav::map
