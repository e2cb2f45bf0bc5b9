#pragma once
// Plane and line fits to a few neighbours, by the eigen-decomposition of their scatter matrix:
// the map-side half of point-to-plane and point-to-edge residuals.

#include <Eigen/Core>
#include <limits>
#include <vector>

namespace mmlio::map {

struct PlaneFit {
  bool ok = false;                                    // a 2-D patch (see fitPlane), all points within max_residual_m
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
  double d = 0;                                       // n.x + d = 0
  double max_residual_m = 0;                          // largest |n.x + d| over the points
};
/// Total least squares plane through pts (normal = smallest-eigenvalue eigenvector). The points
/// must span two directions: lambda_mid >= min_spread_ratio * lambda_max. Neighbours taken from a
/// single LiDAR ring (a floor or ceiling seen by one ring of a spinning LiDAR) are a noisy line
/// whose fitted "normal" may tilt freely about it; residuals against such planes tilted the hall
/// run by 20 mrad during a turn (0.01 = the cross spread's std-dev at least 10 % of the long one).
PlaneFit fitPlane(const std::vector<Eigen::Vector3d>& pts, double max_residual_m = 0.1, double min_spread_ratio = 0.01);

struct LineFit {
  bool ok = false;                                       // elongated and every point near the line (below)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       // centroid, on the line
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // unit
  double max_residual_m = 0.0;                           // farthest point from the line
};
/// Principal axis of pts; ok only when elongated (lambda_max > min_eigen_ratio * lambda_mid) and no
/// point lies farther than max_residual_m from the line. Elongation alone also accepts points of
/// two parallel edges (stair nosings 0.3 m apart): their axis runs between the edges, on neither.
LineFit fitLine(const std::vector<Eigen::Vector3d>& pts, double min_eigen_ratio = 3.0,
                double max_residual_m = std::numeric_limits<double>::infinity());

}  // namespace mmlio::map
