#include "snapnav/glue/occupancy_grid_msg.hpp"

#include <cmath>

namespace snapnav::glue {

std::optional<GridProblem> CheckOccupancyGrid(const occupancy_grid_t& msg) {
  const int64_t n = static_cast<int64_t>(msg.width) * static_cast<int64_t>(msg.height);
  if (msg.width <= 0 || msg.height <= 0 || n > kMaxGridCells || msg.ncells != n ||
      static_cast<int64_t>(msg.cells.size()) != n) {
    return GridProblem{"bad grid size", std::to_string(msg.width) + " x " + std::to_string(msg.height) + ", " +
                                            std::to_string(msg.ncells) + " cells"};
  }
  if (!std::isfinite(msg.resolution_m) || !(msg.resolution_m >= 0.001f) || !(msg.resolution_m <= 100.0f)) {
    return GridProblem{"bad resolution", std::to_string(msg.resolution_m) + " m"};
  }
  if (!std::isfinite(msg.origin_x_m) || !std::isfinite(msg.origin_y_m) || !std::isfinite(msg.origin_theta_rad) ||
      std::abs(msg.origin_x_m) > 1e7 || std::abs(msg.origin_y_m) > 1e7) {
    return GridProblem{"bad origin", std::to_string(msg.origin_x_m) + ", " + std::to_string(msg.origin_y_m) + ", " +
                                         std::to_string(msg.origin_theta_rad)};
  }
  for (size_t i = 0; i < msg.cells.size(); ++i) {
    if (msg.cells[i] < -1 || msg.cells[i] > 100) {
      return GridProblem{"bad cell value", "cell " + std::to_string(i) + " = " + std::to_string(msg.cells[i])};
    }
  }
  return std::nullopt;
}

occupancy_grid_t ToOccupancyGridMsg(const nav::OccupancyCells& cells, int64_t utime, const std::string& frame,
                                    const std::string& source) {
  occupancy_grid_t m{};
  m.utime = utime;
  m.frame = frame;
  m.source = source;
  m.resolution_m = static_cast<float>(cells.resolution_m);
  m.origin_x_m = cells.origin_x_m;
  m.origin_y_m = cells.origin_y_m;
  m.origin_theta_rad = 0;
  m.width = cells.width;
  m.height = cells.height;
  m.ncells = static_cast<int32_t>(cells.cells.size());
  m.cells = cells.cells;
  return m;
}

nav::OccupancyCells FromOccupancyGridMsg(const occupancy_grid_t& msg, double occupied_threshold, double free_threshold) {
  nav::OccupancyCells c;
  c.resolution_m = msg.resolution_m;
  c.origin_x_m = msg.origin_x_m;
  c.origin_y_m = msg.origin_y_m;
  c.width = msg.width;
  c.height = msg.height;
  c.cells = msg.cells;
  c.Count(occupied_threshold, free_threshold);
  return c;
}

}  // namespace snapnav::glue
