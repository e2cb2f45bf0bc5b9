#include "mmlio/estimator/imu_factor.hpp"

#include "mmlio/core/so3.hpp"

namespace mmlio::estimator {
namespace {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

// Left / right quaternion-product matrices in (w, x, y, z) order: q * p = L(q) p = R(p) q.
Eigen::Matrix4d qLeft(const Quaterniond& q) {
  Eigen::Matrix4d m;
  m(0, 0) = q.w();
  m.block<1, 3>(0, 1) = -q.vec().transpose();
  m.block<3, 1>(1, 0) = q.vec();
  m.block<3, 3>(1, 1) = q.w() * Matrix3d::Identity() + so3::hat(q.vec());
  return m;
}
Eigen::Matrix4d qRight(const Quaterniond& q) {
  Eigen::Matrix4d m;
  m(0, 0) = q.w();
  m.block<1, 3>(0, 1) = -q.vec().transpose();
  m.block<3, 1>(1, 0) = q.vec();
  m.block<3, 3>(1, 1) = q.w() * Matrix3d::Identity() - so3::hat(q.vec());
  return m;
}

// d(2 vec(e)) / dx for e = c^-1 * dq^-1 * q_ij with c = normalize(1, x/2), x = dq_dbg (bg - bg_lin):
// the exact derivative of the first-order bias correction Preintegration::corrected() applies
// (chain with dx/dbg = dq_dbg).
Matrix3d rotationResidualByGyroBias(const Quaterniond& dq, const Quaterniond& q_ij, const Vector3d& x) {
  // c^-1 = u / |u| with u = (1, -x/2) in (w, x, y, z) order.
  const Eigen::Vector4d u(1.0, -0.5 * x.x(), -0.5 * x.y(), -0.5 * x.z());
  const double n = u.norm();
  Eigen::Matrix<double, 4, 3> du_dx = Eigen::Matrix<double, 4, 3>::Zero();
  du_dx.bottomRows<3>() = -0.5 * Matrix3d::Identity();
  const Eigen::Matrix4d dnormalized = (Eigen::Matrix4d::Identity() - u * u.transpose() / (n * n)) / n;
  return 2.0 * (qRight(dq.inverse() * q_ij) * dnormalized * du_dx).bottomRows<3>();
}

constexpr int kP = 0, kR = 3, kV = 6, kBa = 9, kBg = 12;

}  // namespace

ImuFactor::ImuFactor(std::shared_ptr<const imu::Preintegration> pre, const Vector3d& g_world)
    : pre_(std::move(pre)), g_world_(g_world) {
  // A tiny floor keeps the information finite for very short or bias-only intervals.
  const Eigen::Matrix<double, 15, 15> info =
      (pre_->covariance() + 1e-12 * Eigen::Matrix<double, 15, 15>::Identity()).inverse();
  sqrt_info_ = Eigen::LLT<Eigen::Matrix<double, 15, 15>>(0.5 * (info + info.transpose())).matrixL().transpose();
}

bool ImuFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Vector3d Pi(parameters[0]), Pj(parameters[2]);
  const Quaterniond Qi = Eigen::Map<const Quaterniond>(parameters[0] + 3).normalized();
  const Quaterniond Qj = Eigen::Map<const Quaterniond>(parameters[2] + 3).normalized();
  const Vector3d Vi(parameters[1]), Bai(parameters[1] + 3), Bgi(parameters[1] + 6);
  const Vector3d Vj(parameters[3]), Baj(parameters[3] + 3), Bgj(parameters[3] + 6);

  const auto& J = pre_->jacobian();
  const Matrix3d dp_dba = J.block<3, 3>(kP, kBa), dp_dbg = J.block<3, 3>(kP, kBg);
  const Matrix3d dq_dbg = J.block<3, 3>(kR, kBg);
  const Matrix3d dv_dba = J.block<3, 3>(kV, kBa), dv_dbg = J.block<3, 3>(kV, kBg);
  const Vector3d bg_lin = pre_->biasLin().gyro_rad_s;

  ImuBias bi;
  bi.acc_m_s2 = Bai;
  bi.gyro_rad_s = Bgi;
  Quaterniond cq;
  Vector3d cv, cp;
  pre_->corrected(bi, &cq, &cv, &cp);
  const double T = pre_->sumDt();
  const Matrix3d Ri_inv = Qi.inverse().toRotationMatrix();
  const Vector3d dpos = Pj - Pi - Vi * T - 0.5 * g_world_ * T * T;
  const Vector3d dvel = Vj - Vi - g_world_ * T;

  Eigen::Map<Eigen::Matrix<double, 15, 1>> r(residuals);
  r.segment<3>(kP) = Ri_inv * dpos - cp;
  r.segment<3>(kR) = 2.0 * (cq.inverse() * (Qi.inverse() * Qj)).vec();
  r.segment<3>(kV) = Ri_inv * dvel - cv;
  r.segment<3>(kBa) = Baj - Bai;
  r.segment<3>(kBg) = Bgj - Bgi;
  r = sqrt_info_ * r;
  if (!jacobians) return true;

  if (jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 15, 7, Eigen::RowMajor>> j(jacobians[0]);
    j.setZero();
    j.block<3, 3>(kP, 0) = -Ri_inv;
    j.block<3, 3>(kP, 3) = so3::hat(Ri_inv * dpos);
    // e(theta) = cq^-1 * Exp(-theta) * Qi^-1 * Qj, differentiated directly (same value as VINS's
    // -[L(Qj^-1 Qi) R(cq)] form, which uses vec(e) = -vec(e^-1)).
    j.block<3, 3>(kR, 3) = -(qLeft(cq.inverse()) * qRight(Qi.inverse() * Qj)).bottomRightCorner<3, 3>();
    j.block<3, 3>(kV, 3) = so3::hat(Ri_inv * dvel);
    j = sqrt_info_ * j;
  }
  if (jacobians[1]) {
    Eigen::Map<Eigen::Matrix<double, 15, 9, Eigen::RowMajor>> j(jacobians[1]);
    j.setZero();
    j.block<3, 3>(kP, 0) = -Ri_inv * T;
    j.block<3, 3>(kP, 3) = -dp_dba;
    j.block<3, 3>(kP, 6) = -dp_dbg;
    j.block<3, 3>(kR, 6) =
        rotationResidualByGyroBias(pre_->deltaQ(), Qi.inverse() * Qj, dq_dbg * (Bgi - bg_lin)) * dq_dbg;
    j.block<3, 3>(kV, 0) = -Ri_inv;
    j.block<3, 3>(kV, 3) = -dv_dba;
    j.block<3, 3>(kV, 6) = -dv_dbg;
    j.block<3, 3>(kBa, 3) = -Matrix3d::Identity();
    j.block<3, 3>(kBg, 6) = -Matrix3d::Identity();
    j = sqrt_info_ * j;
  }
  if (jacobians[2]) {
    Eigen::Map<Eigen::Matrix<double, 15, 7, Eigen::RowMajor>> j(jacobians[2]);
    j.setZero();
    j.block<3, 3>(kP, 0) = Ri_inv;
    j.block<3, 3>(kR, 3) = qLeft(cq.inverse() * Qi.inverse() * Qj).bottomRightCorner<3, 3>();
    j = sqrt_info_ * j;
  }
  if (jacobians[3]) {
    Eigen::Map<Eigen::Matrix<double, 15, 9, Eigen::RowMajor>> j(jacobians[3]);
    j.setZero();
    j.block<3, 3>(kV, 0) = Ri_inv;
    j.block<3, 3>(kBa, 3) = Matrix3d::Identity();
    j.block<3, 3>(kBg, 6) = Matrix3d::Identity();
    j = sqrt_info_ * j;
  }
  return true;
}

}  // namespace mmlio::estimator
