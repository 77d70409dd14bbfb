#include "snapnav/nav/covariance.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace snapnav::nav {

SymmetricEigen2 EigenOfSymmetric(const Eigen::Matrix2d& m) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(m);
  return {eig.eigenvalues(), eig.eigenvectors()};
}

double PositionSigmaM(const Eigen::Matrix3d& covariance) {
  return std::sqrt(std::max(0.0, EigenOfSymmetric(covariance.topLeftCorner<2, 2>()).values.maxCoeff()));
}

}  // namespace snapnav::nav
