#include "mmlio/eval/alignment.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace mmlio::eval {

Alignment alignUmeyama(const std::vector<Eigen::Vector3d>& p_gt, const std::vector<Eigen::Vector3d>& p_est,
                       bool with_scale) {
  Alignment alignment;
  if (p_gt.size() != p_est.size() || p_gt.size() < 3) return alignment;
  const Eigen::Index n = static_cast<Eigen::Index>(p_gt.size());
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    src.col(i) = p_est[static_cast<size_t>(i)];
    dst.col(i) = p_gt[static_cast<size_t>(i)];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, with_scale);
  // umeyama returns [s R | t]; split the scale out of the linear block so T_gt_est stays rigid.
  const Eigen::Matrix3d sR = T.topLeftCorner<3, 3>();
  alignment.scale = with_scale ? std::cbrt(sR.determinant()) : 1.0;
  alignment.T_gt_est.linear() = sR / alignment.scale;
  alignment.T_gt_est.translation() = T.topRightCorner<3, 1>();
  return alignment;
}

}  // namespace mmlio::eval
