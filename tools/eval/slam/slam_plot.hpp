#pragma once
// Figures of the laser SLAM evaluations (eval-slam, slam-sim-eval): trajectories over the
// point map.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::eval {

// The tracks (one colour each, named in a legend at the top right) over the map points (grey),
// scaled to fit a 900 x 900 px square under a title line, with a 5 m scale bar. `names` has
// one entry per track.
cv::Mat DrawRun(const std::vector<std::vector<nav::Pose2>>& tracks, const std::vector<std::string>& names,
                const std::vector<Eigen::Vector2d>& map, const std::string& title);

}  // namespace snapnav::eval
