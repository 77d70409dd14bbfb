#pragma once
// Eigen decompositions of small symmetric matrices (covariances, scatter matrices), compiled once.
// Eigen's SelfAdjointEigenSolver for a 2x2 matrix costs about 5 s of compile time in every source
// that instantiates it (docs/testing_and_benchmarks.md, "Build time"); these wrap the same solver.

#include <Eigen/Core>

namespace snapnav::nav {

struct SymmetricEigen2 {
  Eigen::Vector2d values;   // ascending
  Eigen::Matrix2d vectors;  // column i: the unit eigenvector of values(i)
};

// Eigen::SelfAdjointEigenSolver of `m` (its lower triangle is read).
SymmetricEigen2 EigenOfSymmetric(const Eigen::Matrix2d& m);

// The standard deviation of a pose's position along its worst direction: the square root of the
// largest eigenvalue of the covariance's x-y block (0 where rounding makes it negative).
double PositionSigmaM(const Eigen::Matrix3d& covariance);

}  // namespace snapnav::nav
