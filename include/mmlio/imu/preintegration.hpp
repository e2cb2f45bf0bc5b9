#pragma once
// On-manifold IMU preintegration (Forster et al., VINS-Mono's midpoint discretisation):
// relative motion deltas between two states, independent of the states themselves, with their
// covariance and first-order Jacobians w.r.t. the biases, so a bias update corrects the deltas
// without re-integrating.
//
// Error-state order everywhere: dp(0) dtheta(3) dv(6) dba(9) dbg(12).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/imu/imu_noise.hpp"

namespace mmlio::imu {

using Matrix15d = Eigen::Matrix<double, 15, 15>;
using Vector15d = Eigen::Matrix<double, 15, 1>;

class Preintegration {
 public:
  Preintegration(const ImuBias& bias_lin, const ImuNoise& noise);

  /// One raw measurement taken dt_s after the previous one (VINS-style push): the interval is
  /// integrated with the previous and this measurement at its ends (midpoint rule). Without a
  /// previous measurement this one is held over the interval; pass dt_s = 0 to only record the
  /// measurement at the start of the interval.
  void integrate(double dt_s, const Eigen::Vector3d& acc, const Eigen::Vector3d& gyro);
  /// One interval of dt_s between two raw measurements (midpoint rule).
  void integrate(double dt_s, const Eigen::Vector3d& acc0, const Eigen::Vector3d& gyro0, const Eigen::Vector3d& acc1,
                 const Eigen::Vector3d& gyro1);
  /// Consecutive samples: one interval per pair.
  void integrate(const std::vector<ImuSample>& samples);
  /// Re-integrates the stored measurements around a new linearisation bias.
  void repropagate(const ImuBias& bias_lin);

  double sumDt() const { return sum_dt_; }
  const ImuBias& biasLin() const { return bias_lin_; }
  const Eigen::Quaterniond& deltaQ() const { return dq_; }
  const Eigen::Vector3d& deltaP() const { return dp_; }
  const Eigen::Vector3d& deltaV() const { return dv_; }
  const Matrix15d& covariance() const { return cov_; }
  const Matrix15d& jacobian() const { return jac_; }

  /// Deltas corrected to first order for `bias` (no re-integration).
  void corrected(const ImuBias& bias, Eigen::Quaterniond* dq, Eigen::Vector3d* dv, Eigen::Vector3d* dp) const;
  /// Residual between states i and j (not whitened), g_world e.g. (0, 0, -9.81).
  Vector15d residual(const NavState& i, const NavState& j, const Eigen::Vector3d& g_world) const;
  /// State at i + sumDt() predicted from i (biases of i kept).
  NavState predict(const NavState& i, const Eigen::Vector3d& g_world) const;

 private:
  struct Interval {
    double dt;
    Eigen::Vector3d acc0, gyro0, acc1, gyro1;
  };
  void reset();
  void step(const Interval& m);

  ImuBias bias_lin_;
  ImuNoise noise_;
  std::vector<Interval> measurements_;
  double sum_dt_ = 0.0;
  Eigen::Vector3d dp_, dv_;
  Eigen::Quaterniond dq_;
  Matrix15d cov_, jac_;
  bool has_last_ = false;  // last raw measurement, the start of the next single-sample push
  Eigen::Vector3d last_acc_ = Eigen::Vector3d::Zero(), last_gyro_ = Eigen::Vector3d::Zero();
};

}  // namespace mmlio::imu
