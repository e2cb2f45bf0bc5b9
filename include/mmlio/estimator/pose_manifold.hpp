#pragma once
// Manifold of a pose parameter block T_world_body stored as double[7] = {px,py,pz,qx,qy,qz,qw}.
//
// Tangent (size 6) = {dp, dtheta}; the perturbation is on the right of the rotation:
//   Plus:  p <- p + dp,  q <- q * Exp(dtheta)   (q re-normalised)
//   Minus: dp = p_y - p_x,  dtheta = Log(q_x^-1 * q_y)   (so Minus(Plus(x, d), x) == d)
// VINS-Mono convention: every cost function evaluated on a pose block returns a 7-column
// Jacobian whose first 6 columns already hold d r / d(dp, dtheta) and whose last column is
// zero, so PlusJacobian is the selector [I6; 0] (7x6) and MinusJacobian is [I6 0] (6x7).
// Only use this manifold with cost functions that follow that convention.

#include <ceres/manifold.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mmlio::estimator {

class PoseManifold : public ceres::Manifold {
 public:
  static constexpr int kAmbientSize = 7;
  static constexpr int kTangentSize = 6;

  int AmbientSize() const override { return kAmbientSize; }
  int TangentSize() const override { return kTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  /// Row-major 7x6 [I6; 0].
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  /// Row-major 6x7 [I6 0].
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

/// Pose block helpers (views into a double[7]).
inline Eigen::Map<const Eigen::Vector3d> poseTranslation(const double* pose) {
  return Eigen::Map<const Eigen::Vector3d>(pose);
}
inline Eigen::Map<const Eigen::Quaterniond> poseRotation(const double* pose) {
  return Eigen::Map<const Eigen::Quaterniond>(pose + 3);
}
/// Writes T (rotation taken as a quaternion) into a double[7] pose block.
void poseToBlock(const Eigen::Isometry3d& T_world_body, double* pose);
/// Reads a double[7] pose block (quaternion normalised) into an isometry.
Eigen::Isometry3d blockToPose(const double* pose);

}  // namespace mmlio::estimator
