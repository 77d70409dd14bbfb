#pragma once
// An occupancy grid's cells as ROS's nav_msgs/OccupancyGrid and map_server have them (no MRPT
// here: the bus glue and the localizer take it; occupancy_grid.hpp builds it with MRPT).
#include <cstdint>
#include <vector>

namespace snapnav::nav {

// A cell's occupancy: 0 free .. 100 occupied, -1 unknown (never observed). Row-major from the
// grid's (x_min, y_min) corner, x along a row.
struct OccupancyCells {
  double resolution_m = 0;
  double origin_x_m = 0, origin_y_m = 0;  // the corner of cell (0, 0)
  int width = 0, height = 0;
  std::vector<int8_t> cells;   // width * height
  int occupied = 0, free = 0, unknown = 0;  // by the thresholds it was counted with

  int8_t at(int x, int y) const { return cells[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]; }
  // Recounts occupied / free / unknown by these thresholds (probabilities of being occupied).
  void Count(double occupied_threshold = 0.65, double free_threshold = 0.196) {
    occupied = free = unknown = 0;
    for (const int8_t v : cells) {
      if (v < 0) ++unknown;
      else if (v >= 100.0 * occupied_threshold) ++occupied;
      else if (v <= 100.0 * free_threshold) ++free;
    }
  }
};

}  // namespace snapnav::nav
