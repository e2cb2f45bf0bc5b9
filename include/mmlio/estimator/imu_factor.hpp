#pragma once
// IMU preintegration residual between two keyframe states (VINS-Mono style), whitened by the
// preintegrated covariance, with analytic Jacobians per the estimator convention (pose blocks:
// 7 columns, the first 6 = d r / d(dp, dtheta) for a right perturbation, the last zero).
// Blocks: pose_i[7], speed_bias_i[9] = {v, ba, bg}, pose_j[7], speed_bias_j[9].
//
// With (dq, dv, dp) = pre.corrected(bias_i) and T = pre.sumDt(), the raw residual is
//   r_p  = Ri^T (pj - pi - vi T - g T^2 / 2) - dp
//   r_th = 2 vec(dq^-1 Ri^T Rj)               (~ Log of the rotation error)
//   r_v  = Ri^T (vj - vi - g T) - dv
//   r_ba = ba_j - ba_i,  r_bg = bg_j - bg_i
// and the cost is L^T r with L L^T = covariance^-1 (whitened). The Jacobians are exact
// derivatives of this residual at any residual (incl. the normalisation in the gyro-bias correction), checked against
// numeric differences.
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
