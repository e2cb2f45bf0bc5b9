#pragma once
// Gaussian prior on a Euclidean parameter block: r = sqrt_info (x - x0). Used to let the
// previous sweep's velocity and biases move during scan-to-map registration (so position
// corrections also correct the velocity) without letting them wander.
#include <ceres/ceres.h>

#include <Eigen/Core>

namespace mmlio::estimator {

class SpeedBiasPrior : public ceres::SizedCostFunction<9, 9> {
 public:
  /// Standard deviations of velocity (m/s), accelerometer bias (m/s^2) and gyroscope bias (rad/s).
  SpeedBiasPrior(const double* speed_bias0, double sigma_v, double sigma_ba, double sigma_bg) {
    x0_ = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(speed_bias0);
    w_ << Eigen::Vector3d::Constant(1.0 / sigma_v), Eigen::Vector3d::Constant(1.0 / sigma_ba),
        Eigen::Vector3d::Constant(1.0 / sigma_bg);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Matrix<double, 9, 1>> x(parameters[0]);
    Eigen::Map<Eigen::Matrix<double, 9, 1>> r(residuals);
    r = w_.cwiseProduct(x - x0_);
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 9, 9, Eigen::RowMajor>> j(jacobians[0]);
      j = w_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Matrix<double, 9, 1> x0_, w_;
};

}  // namespace mmlio::estimator
