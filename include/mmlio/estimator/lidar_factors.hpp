#pragma once
// LiDAR feature residuals of one body-frame point against the local map (paper eqs. edge_cost,
// plane_cost), on one pose block T_world_body = double[7] {p, q(x,y,z,w)}.
//
//   p_w = R(q) * p_body + t
//   plane: r = weight * (n . p_w + d)                     (1 residual; n unit -> metres)
//   edge:  r = weight * (I - u u^T) (p_w - a)             (3 residuals; u unit line direction,
//          a a point on the line; ||r|| = weight * distance to the line, i.e. the paper's
//          |(p_w - e1) x (p_w - e2)| / |e1 - e2|, but as a vector so that Ceres sees a smooth
//          residual with no singularity at zero distance; the component along u is always 0.)
//
// Jacobians are analytic and follow the estimator convention (right perturbation,
// q <- q * Exp(dtheta)):  d p_w / d dp = I,  d p_w / d dtheta = -R [p_body]x.
// Columns 0-2 = d/d dp, 3-5 = d/d dtheta, column 6 = 0; use with PoseManifold.
// weight is 1/sigma (sigma in metres) for a residual whitened by the point noise.

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

namespace mmlio::estimator {

class PointToPlaneFactor : public ceres::SizedCostFunction<1, 7> {
 public:
  /// n . x + d = 0 is the plane in the world frame; normal_world should be unit length.
  PointToPlaneFactor(const Eigen::Vector3d& p_body, const Eigen::Vector3d& normal_world, double d, double weight = 1.0);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d p_body_;
  Eigen::Vector3d normal_world_;
  double d_;
  double weight_;
};

class PointToEdgeFactor : public ceres::SizedCostFunction<3, 7> {
 public:
  /// line_dir_world need not be unit length (it is normalised here); it must be non-zero.
  PointToEdgeFactor(const Eigen::Vector3d& p_body, const Eigen::Vector3d& line_point_world,
                    const Eigen::Vector3d& line_dir_world, double weight = 1.0);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d p_body_;
  Eigen::Vector3d line_point_world_;
  Eigen::Matrix3d perp_projector_;  // I - u u^T, u the unit line direction
  double weight_;
};

}  // namespace mmlio::estimator
