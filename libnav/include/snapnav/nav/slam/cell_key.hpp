#pragma once
// The key of a grid cell in a hash set or map: x index in the high 32 bits, y in the low ones
// (negative indices in two's complement: cells within +-2^31 of the origin have distinct keys).
#include <cmath>
#include <cstdint>

#include <Eigen/Core>

namespace snapnav::nav {

constexpr uint64_t CellKey(int64_t ix, int64_t iy) {
  return (static_cast<uint64_t>(ix) << 32) ^ (static_cast<uint64_t>(iy) & 0xffffffffULL);
}

// The key of the cell of side cell_m that holds p (cells from floor(x / cell_m), floor(y / cell_m)).
inline uint64_t CellKey(const Eigen::Vector2d& p, double cell_m) {
  return CellKey(static_cast<int64_t>(std::floor(p.x() / cell_m)), static_cast<int64_t>(std::floor(p.y() / cell_m)));
}

}  // namespace snapnav::nav
