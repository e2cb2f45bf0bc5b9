#pragma once
// IMU preintegration residual between two keyframe states (VINS-Mono style), whitened by the
// preintegrated covariance, with analytic Jacobians per the estimator convention (pose blocks:
// 7 columns, the first 6 = d r / d(dp, dtheta) for a right perturbation, the last zero).
// Blocks: pose_i[7], speed_bias_i[9] = {v, ba, bg}, pose_j[7], speed_bias_j[9].
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>

#include "mmlio/imu/preintegration.hpp"

namespace mmlio::estimator {

class ImuFactor : public ceres::SizedCostFunction<15, 7, 9, 7, 9> {
 public:
  ImuFactor(std::shared_ptr<const imu::Preintegration> pre, const Eigen::Vector3d& g_world);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  std::shared_ptr<const imu::Preintegration> pre_;
  Eigen::Vector3d g_world_;
  Eigen::Matrix<double, 15, 15> sqrt_info_;
};

}  // namespace mmlio::estimator
