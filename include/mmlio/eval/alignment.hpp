#pragma once
// Least-squares alignment of estimated positions onto ground truth (Umeyama 1991), the
// standard first step of absolute trajectory error: the estimate's world frame is arbitrary,
// so it is moved (and optionally scaled) onto the GT world frame before errors are measured.

#include <Eigen/Geometry>
#include <vector>

namespace mmlio::eval {

/// p_gt ~= scale * T_gt_est.linear() * p_est + T_gt_est.translation().
struct Alignment {
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();
  double scale = 1.0;  // 1 unless scale estimation was requested

  Eigen::Vector3d apply(const Eigen::Vector3d& p_est) const {
    return scale * (T_gt_est.linear() * p_est) + T_gt_est.translation();
  }
  /// A full pose of the estimate mapped into the GT world (translation scaled, rotation rotated).
  Eigen::Isometry3d apply(const Eigen::Isometry3d& T_est_world_body) const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = T_gt_est.linear() * T_est_world_body.linear();
    T.translation() = apply(Eigen::Vector3d(T_est_world_body.translation()));
    return T;
  }
};

/// Rigid (or similarity, with `with_scale`) transform minimising sum ||p_gt - f(p_est)||^2,
/// via Eigen::umeyama. Requires equal sizes and at least 3 pairs; with fewer the identity is
/// returned. Degenerate configurations (collinear points) leave the rotation about the line
/// unconstrained, which does not change the position errors.
Alignment alignUmeyama(const std::vector<Eigen::Vector3d>& p_gt, const std::vector<Eigen::Vector3d>& p_est,
                       bool with_scale);

}  // namespace mmlio::eval
