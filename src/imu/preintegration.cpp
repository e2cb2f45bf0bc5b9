#include "mmlio/imu/preintegration.hpp"

#include "mmlio/core/so3.hpp"

namespace mmlio::imu {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Eigen::Quaterniond smallRotation(const Vector3d& theta) {
  return Eigen::Quaterniond(1.0, 0.5 * theta.x(), 0.5 * theta.y(), 0.5 * theta.z()).normalized();
}

}  // namespace

Preintegration::Preintegration(const ImuBias& bias_lin, const ImuNoise& noise) : bias_lin_(bias_lin), noise_(noise) {
  reset();
}

void Preintegration::reset() {
  sum_dt_ = 0.0;
  dp_.setZero();
  dv_.setZero();
  dq_.setIdentity();
  cov_.setZero();
  jac_.setIdentity();
}

void Preintegration::integrate(double dt_s, const Vector3d& acc, const Vector3d& gyro) {
  const Vector3d acc0 = has_last_ ? last_acc_ : acc, gyro0 = has_last_ ? last_gyro_ : gyro;
  integrate(dt_s, acc0, gyro0, acc, gyro);  // also records (acc, gyro) as the last measurement
}

void Preintegration::integrate(double dt_s, const Vector3d& acc0, const Vector3d& gyro0, const Vector3d& acc1,
                               const Vector3d& gyro1) {
  has_last_ = true;
  last_acc_ = acc1;
  last_gyro_ = gyro1;
  if (!(dt_s > 0.0)) return;
  measurements_.push_back({dt_s, acc0, gyro0, acc1, gyro1});
  step(measurements_.back());
}

void Preintegration::integrate(const std::vector<ImuSample>& samples) {
  for (std::size_t i = 1; i < samples.size(); ++i) {
    integrate(toSec(samples[i].stamp_ns - samples[i - 1].stamp_ns), samples[i - 1].acc_m_s2, samples[i - 1].gyro_rad_s,
              samples[i].acc_m_s2, samples[i].gyro_rad_s);
  }
}

void Preintegration::repropagate(const ImuBias& bias_lin) {
  bias_lin_ = bias_lin;
  reset();
  for (const Interval& m : measurements_) step(m);
}

void Preintegration::step(const Interval& m) {
  const double dt = m.dt;
  const Vector3d& ba = bias_lin_.acc_m_s2;
  const Vector3d& bg = bias_lin_.gyro_rad_s;
  const Vector3d w = 0.5 * (m.gyro0 + m.gyro1) - bg;
  const Vector3d a0 = m.acc0 - ba, a1 = m.acc1 - ba;
  const Eigen::Quaterniond q1 = (dq_ * so3::exp(w * dt)).normalized();
  const Matrix3d R0 = dq_.toRotationMatrix(), R1 = q1.toRotationMatrix();
  const Vector3d acc_mid = 0.5 * (R0 * a0 + R1 * a1);

  // Error-state transition F and noise input V of the midpoint step (VINS-Mono, Forster), with
  // the step rotation's exact derivatives: q1 = q0 Exp(w dt) moves an error dtheta0 to
  // Exp(w dt)^T dtheta0 and a gyro bias change dbg by -Jr(w dt) dt dbg. VINS's first-order
  // (I - [w]x dt) and -I dt drift by ~(w dt)^2 per step, ~0.2% of d(delta)/d(bg) over a second.
  const Matrix3d I = Matrix3d::Identity();
  const Matrix3d A0x = so3::hat(a0), A1x = so3::hat(a1);
  const Matrix3d step_T = so3::exp(w * dt).toRotationMatrix().transpose();  // Exp(w dt)^T
  const Matrix3d Jr_dt = so3::rightJacobian(w * dt) * dt;                   // d(angle)/d(-bg)
  const double dt2 = dt * dt;
  Eigen::Matrix<double, 15, 15> F = Eigen::Matrix<double, 15, 15>::Zero();
  F.block<3, 3>(0, 0) = I;
  F.block<3, 3>(0, 3) = -0.25 * R0 * A0x * dt2 - 0.25 * R1 * A1x * step_T * dt2;
  F.block<3, 3>(0, 6) = I * dt;
  F.block<3, 3>(0, 9) = -0.25 * (R0 + R1) * dt2;
  F.block<3, 3>(0, 12) = 0.25 * R1 * A1x * Jr_dt * dt2;
  F.block<3, 3>(3, 3) = step_T;
  F.block<3, 3>(3, 12) = -Jr_dt;
  F.block<3, 3>(6, 3) = -0.5 * R0 * A0x * dt - 0.5 * R1 * A1x * step_T * dt;
  F.block<3, 3>(6, 6) = I;
  F.block<3, 3>(6, 9) = -0.5 * (R0 + R1) * dt;
  F.block<3, 3>(6, 12) = 0.5 * R1 * A1x * Jr_dt * dt;
  F.block<3, 3>(9, 9) = I;
  F.block<3, 3>(12, 12) = I;

  // Inputs: acc0, gyro0, acc1, gyro1 white noise; acc and gyro bias random walks. A gyro noise
  // sample enters like a bias change of opposite sign, halved by the midpoint average.
  Eigen::Matrix<double, 15, 18> V = Eigen::Matrix<double, 15, 18>::Zero();
  V.block<3, 3>(0, 0) = 0.25 * R0 * dt2;
  V.block<3, 3>(0, 3) = -0.125 * R1 * A1x * Jr_dt * dt2;
  V.block<3, 3>(0, 6) = 0.25 * R1 * dt2;
  V.block<3, 3>(0, 9) = V.block<3, 3>(0, 3);
  V.block<3, 3>(3, 3) = 0.5 * Jr_dt;
  V.block<3, 3>(3, 9) = 0.5 * Jr_dt;
  V.block<3, 3>(6, 0) = 0.5 * R0 * dt;
  V.block<3, 3>(6, 3) = -0.25 * R1 * A1x * Jr_dt * dt;
  V.block<3, 3>(6, 6) = 0.5 * R1 * dt;
  V.block<3, 3>(6, 9) = V.block<3, 3>(6, 3);
  V.block<3, 3>(9, 12) = I * dt;
  V.block<3, 3>(12, 15) = I * dt;

  // Continuous densities -> discrete variances over dt (sigma^2 / dt for every input).
  Eigen::Matrix<double, 18, 1> q;
  const double na = noise_.acc_noise_density * noise_.acc_noise_density / dt;
  const double ng = noise_.gyro_noise_density * noise_.gyro_noise_density / dt;
  const double wa = noise_.acc_bias_random_walk * noise_.acc_bias_random_walk / dt;
  const double wg = noise_.gyro_bias_random_walk * noise_.gyro_bias_random_walk / dt;
  q << Vector3d::Constant(na), Vector3d::Constant(ng), Vector3d::Constant(na), Vector3d::Constant(ng),
      Vector3d::Constant(wa), Vector3d::Constant(wg);

  jac_ = F * jac_;
  cov_ = F * cov_ * F.transpose() + V * q.asDiagonal() * V.transpose();
  cov_ = 0.5 * (cov_ + cov_.transpose());

  dp_ += dv_ * dt + 0.5 * acc_mid * dt2;
  dv_ += acc_mid * dt;
  dq_ = q1;
  sum_dt_ += dt;
}

void Preintegration::corrected(const ImuBias& bias, Eigen::Quaterniond* dq, Vector3d* dv, Vector3d* dp) const {
  const Vector3d dba = bias.acc_m_s2 - bias_lin_.acc_m_s2;
  const Vector3d dbg = bias.gyro_rad_s - bias_lin_.gyro_rad_s;
  *dq = (dq_ * smallRotation(jac_.block<3, 3>(3, 12) * dbg)).normalized();
  *dv = dv_ + jac_.block<3, 3>(6, 9) * dba + jac_.block<3, 3>(6, 12) * dbg;
  *dp = dp_ + jac_.block<3, 3>(0, 9) * dba + jac_.block<3, 3>(0, 12) * dbg;
}

Vector15d Preintegration::residual(const NavState& i, const NavState& j, const Vector3d& g_world) const {
  Eigen::Quaterniond cq;
  Vector3d cv, cp;
  corrected(i.bias, &cq, &cv, &cp);
  const double T = sum_dt_;
  const Eigen::Quaterniond qi_inv = i.q_world_body.inverse();
  Vector15d r;
  r.segment<3>(0) = qi_inv * (j.p_world - i.p_world - i.v_world * T - 0.5 * g_world * T * T) - cp;
  r.segment<3>(3) = 2.0 * (cq.inverse() * (qi_inv * j.q_world_body)).vec();
  r.segment<3>(6) = qi_inv * (j.v_world - i.v_world - g_world * T) - cv;
  r.segment<3>(9) = j.bias.acc_m_s2 - i.bias.acc_m_s2;
  r.segment<3>(12) = j.bias.gyro_rad_s - i.bias.gyro_rad_s;
  return r;
}

NavState Preintegration::predict(const NavState& i, const Vector3d& g_world) const {
  Eigen::Quaterniond cq;
  Vector3d cv, cp;
  corrected(i.bias, &cq, &cv, &cp);
  const double T = sum_dt_;
  NavState j = i;
  j.stamp_ns = i.stamp_ns + fromSec(T);
  j.p_world = i.p_world + i.v_world * T + 0.5 * g_world * T * T + i.q_world_body * cp;
  j.v_world = i.v_world + g_world * T + i.q_world_body * cv;
  j.q_world_body = (i.q_world_body * cq).normalized();
  return j;
}

}  // namespace mmlio::imu
