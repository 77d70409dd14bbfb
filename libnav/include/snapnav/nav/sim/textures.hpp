#pragma once
// Procedural wall, floor and object patterns for the simulated lab.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace snapnav::nav::sim {

// Names accepted by MakePattern.
const std::vector<std::string>& PatternKinds();

// A deterministic BGR pattern of `kind` (bricks, tiles, stripes, panels, cabinet,
// window, noise, plain, checker, bark) in `color`, `size_px` wide and high,
// varied by `seed`. Throws std::invalid_argument for an unknown kind or size.
cv::Mat MakePattern(const std::string& kind, const cv::Vec3b& color, cv::Size size_px, uint64_t seed);

}  // namespace snapnav::nav::sim
