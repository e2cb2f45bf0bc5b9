#pragma once
// SO(3) helpers. Conventions: rotation vectors are axis * angle (rad); exp maps
// a rotation vector to a rotation; the right Jacobian follows Forster et al. 2017.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mmlio::so3 {

inline Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

inline Eigen::Quaterniond exp(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-10) return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
}

inline Eigen::Vector3d log(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // shortest path
  const double sin_half = q.vec().norm();
  if (sin_half < 1e-10) return 2.0 * q.vec();
  const double angle = 2.0 * std::atan2(sin_half, q.w());
  return q.vec() * (angle / sin_half);
}

/// Right Jacobian Jr(w): exp(w + dw) ~= exp(w) exp(Jr(w) dw).
inline Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& w) {
  const double a = w.norm();
  const Eigen::Matrix3d W = hat(w);
  if (a < 1e-6) return Eigen::Matrix3d::Identity() - 0.5 * W;
  return Eigen::Matrix3d::Identity() - (1 - std::cos(a)) / (a * a) * W + (a - std::sin(a)) / (a * a * a) * W * W;
}

inline Eigen::Matrix3d rightJacobianInverse(const Eigen::Vector3d& w) {
  const double a = w.norm();
  const Eigen::Matrix3d W = hat(w);
  if (a < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * W;
  return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / (a * a) - (1 + std::cos(a)) / (2 * a * std::sin(a))) * W * W;
}

}  // namespace mmlio::so3
