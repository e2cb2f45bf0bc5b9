#pragma once
// Plane and line fits to a few neighbours, by the eigen-decomposition of their scatter matrix:
// the map-side half of point-to-plane and point-to-edge residuals.

#include <Eigen/Core>
#include <vector>

namespace mmlio::map {

struct PlaneFit {
  bool ok = false;                                  // >= 3 non-collinear points, all within max_residual_m
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
  double d = 0;                                     // n.x + d = 0
  double max_residual_m = 0;                        // largest |n.x + d| over the points
};
/// Total least squares plane through pts (normal = smallest-eigenvalue eigenvector).
PlaneFit fitPlane(const std::vector<Eigen::Vector3d>& pts, double max_residual_m = 0.1);

struct LineFit {
  bool ok = false;                                        // >= 2 points, largest eigenvalue > ratio * second
  Eigen::Vector3d point = Eigen::Vector3d::Zero();        // centroid, on the line
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();   // unit
};
/// Principal axis of pts; ok only when elongated: lambda_max > min_eigen_ratio * lambda_mid.
LineFit fitLine(const std::vector<Eigen::Vector3d>& pts, double min_eigen_ratio = 3.0);

}  // namespace mmlio::map
