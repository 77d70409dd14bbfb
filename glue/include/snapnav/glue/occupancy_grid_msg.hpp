#pragma once
// occupancy_grid_t <-> nav::OccupancyCells, and the checks of a received grid: a malformed grid
// (a size that does not match its cells, a bad resolution or origin, a cell outside -1..100) is
// counted with its reason by whoever takes it (the viewer, map-export --live), never a crash.
#include <cstdint>
#include <optional>
#include <string>

#include "snapnav/nav/slam/occupancy_cells.hpp"
#include "snapnav/occupancy_grid_t.hpp"

namespace snapnav::glue {

// Grids with more cells than this are rejected as garbage (10^8: 500 m x 500 m at 5 cm).
inline constexpr int64_t kMaxGridCells = 100'000'000;

struct GridProblem {
  std::string reason;  // "bad grid size", "bad resolution", "bad origin", "bad cell value"
  std::string detail;  // the values at fault
};
// The first problem of a malformed grid, or nullopt.
std::optional<GridProblem> CheckOccupancyGrid(const occupancy_grid_t& msg);

occupancy_grid_t ToOccupancyGridMsg(const nav::OccupancyCells& cells, int64_t utime, const std::string& frame,
                                    const std::string& source);
// The cells of a checked grid (origin_theta_rad is not part of OccupancyCells: the caller looks
// at it), counted with these thresholds.
nav::OccupancyCells FromOccupancyGridMsg(const occupancy_grid_t& msg, double occupied_threshold = 0.65,
                                         double free_threshold = 0.196);

}  // namespace snapnav::glue
