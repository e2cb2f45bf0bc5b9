#include "mmlio/estimator/lidar_factors.hpp"

#include <Eigen/Geometry>

#include "mmlio/core/so3.hpp"

namespace mmlio::estimator {

PointToPlaneFactor::PointToPlaneFactor(const Eigen::Vector3d& p_body, const Eigen::Vector3d& normal_world, double d,
                                       double weight)
    : p_body_(p_body), normal_world_(normal_world), d_(d), weight_(weight) {}

bool PointToPlaneFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
  const Eigen::Quaterniond q = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Matrix3d R = q.toRotationMatrix();
  const Eigen::Vector3d p_world = R * p_body_ + t;
  residuals[0] = weight_ * (normal_world_.dot(p_world) + d_);
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 1, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    J.leftCols<3>() = weight_ * normal_world_.transpose();
    J.block<1, 3>(0, 3) = -weight_ * normal_world_.transpose() * R * so3::hat(p_body_);
  }
  return true;
}

PointToEdgeFactor::PointToEdgeFactor(const Eigen::Vector3d& p_body, const Eigen::Vector3d& line_point_world,
                                     const Eigen::Vector3d& line_dir_world, double weight)
    : p_body_(p_body), line_point_world_(line_point_world), weight_(weight) {
  const Eigen::Vector3d u = line_dir_world.normalized();
  perp_projector_ = Eigen::Matrix3d::Identity() - u * u.transpose();
}

bool PointToEdgeFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
  const Eigen::Quaterniond q = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Matrix3d R = q.toRotationMatrix();
  const Eigen::Vector3d p_world = R * p_body_ + t;
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = weight_ * perp_projector_ * (p_world - line_point_world_);
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 3, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    J.leftCols<3>() = weight_ * perp_projector_;
    J.block<3, 3>(0, 3) = -weight_ * perp_projector_ * R * so3::hat(p_body_);
  }
  return true;
}

}  // namespace mmlio::estimator
