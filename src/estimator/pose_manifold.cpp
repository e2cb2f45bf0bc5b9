#include "mmlio/estimator/pose_manifold.hpp"

#include "mmlio/core/so3.hpp"

namespace mmlio::estimator {

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  Eigen::Map<const Eigen::Vector3d> p(x), dp(delta), dtheta(delta + 3);
  Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  Eigen::Map<Eigen::Vector3d> p_out(x_plus_delta);
  Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta + 3);
  p_out = p + dp;
  q_out = (q * so3::exp(dtheta)).normalized();
  return true;
}

bool PoseManifold::PlusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topRows<6>().setIdentity();
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<const Eigen::Vector3d> p_y(y), p_x(x);
  Eigen::Map<const Eigen::Quaterniond> q_y(y + 3), q_x(x + 3);
  Eigen::Map<Eigen::Vector3d> dp(y_minus_x), dtheta(y_minus_x + 3);
  dp = p_y - p_x;
  dtheta = so3::log(q_x.conjugate() * q_y);
  return true;
}

bool PoseManifold::MinusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.leftCols<6>().setIdentity();
  return true;
}

void poseToBlock(const Eigen::Isometry3d& T_world_body, double* pose) {
  Eigen::Map<Eigen::Vector3d> p(pose);
  Eigen::Map<Eigen::Quaterniond> q(pose + 3);
  p = T_world_body.translation();
  q = Eigen::Quaterniond(T_world_body.rotation()).normalized();
}

Eigen::Isometry3d blockToPose(const double* pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = poseRotation(pose).normalized().toRotationMatrix();
  T.translation() = poseTranslation(pose);
  return T;
}

}  // namespace mmlio::estimator
