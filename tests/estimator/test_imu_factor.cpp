#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <memory>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/imu_factor.hpp"

namespace mmlio::estimator {
namespace {

const Eigen::Vector3d kG(0, 0, -9.81);

std::shared_ptr<imu::Preintegration> somePreintegration() {
  ImuBias lin;
  lin.acc_m_s2 = {0.01, -0.02, 0.015};
  lin.gyro_rad_s = {0.001, 0.002, -0.001};
  auto pre = std::make_shared<imu::Preintegration>(lin, imu::ImuNoise{});
  auto acc = [](double t) { return Eigen::Vector3d(0.5 * std::sin(t), 0.2, 9.81 + 0.3 * std::cos(2 * t)); };
  auto gyro = [](double t) { return Eigen::Vector3d(0.1, -0.3 * t, 0.8); };
  pre->integrate(0.0, acc(0.0), gyro(0.0));
  for (int i = 1; i <= 40; ++i) pre->integrate(0.005, acc(i * 0.005), gyro(i * 0.005));
  return pre;
}

// Parameter blocks per the estimator convention, written here without the estimator's manifold.
struct Blocks {
  double pose_i[7], sb_i[9], pose_j[7], sb_j[9];
};

void writePose(const NavState& s, double* pose) {
  Eigen::Map<Eigen::Vector3d>{pose} = s.p_world;
  Eigen::Map<Eigen::Quaterniond>{pose + 3} = s.q_world_body.normalized();
}
void writeSpeedBias(const NavState& s, double* sb) {
  Eigen::Map<Eigen::Matrix<double, 9, 1>>(sb) << s.v_world, s.bias.acc_m_s2, s.bias.gyro_rad_s;
}
Blocks toBlocks(const NavState& i, const NavState& j) {
  Blocks b;
  writePose(i, b.pose_i);
  writeSpeedBias(i, b.sb_i);
  writePose(j, b.pose_j);
  writeSpeedBias(j, b.sb_j);
  return b;
}

// Right perturbation of a pose block: p + dp, q * Exp(dtheta).
void posePlus(const double* x, const double* delta, double* out) {
  Eigen::Map<Eigen::Vector3d>{out} = Eigen::Map<const Eigen::Vector3d>(x) + Eigen::Map<const Eigen::Vector3d>(delta);
  Eigen::Map<Eigen::Quaterniond>{out + 3} =
      (Eigen::Map<const Eigen::Quaterniond>(x + 3) * so3::exp(Eigen::Map<const Eigen::Vector3d>(delta + 3)))
          .normalized();
}

NavState someStateI() {
  NavState i;
  i.p_world = {1, 2, 0.5};
  i.q_world_body = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  i.v_world = {0.4, -0.2, 0.1};
  i.bias.acc_m_s2 = {0.05, -0.03, 0.04};
  i.bias.gyro_rad_s = {0.01, -0.008, 0.012};  // far from the linearisation point: a visible correction
  return i;
}

TEST(ImuFactor, ResidualVanishesForStatesConsistentWithThePreintegration) {
  auto pre = somePreintegration();
  for (const bool at_lin : {true, false}) {
    NavState i = someStateI();
    if (at_lin) i.bias = pre->biasLin();
    const NavState j = pre->predict(i, kG);
    Blocks b = toBlocks(i, j);
    ImuFactor factor(pre, kG);
    const double* params[] = {b.pose_i, b.sb_i, b.pose_j, b.sb_j};
    Eigen::Matrix<double, 15, 1> r;
    ASSERT_TRUE(factor.Evaluate(params, r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-5) << "bias at linearisation point: " << at_lin;
    // A 2 cm offset of j is several sigmas of 0.2 s of preintegrated IMU noise.
    b.pose_j[0] += 0.02;
    ASSERT_TRUE(factor.Evaluate(params, r.data(), nullptr));
    EXPECT_GT(r.norm(), 3.0);
  }
}

TEST(ImuFactor, AnalyticJacobiansMatchNumericTangentDifferencesAwayFromTheOptimum) {
  auto pre = somePreintegration();
  const NavState i = someStateI();
  NavState j = pre->predict(i, kG);
  // Well off the consistent solution, so every residual row is exercised and approximations
  // that only hold at zero residual would show.
  j.p_world += Eigen::Vector3d(0.05, -0.08, 0.03);
  j.q_world_body = j.q_world_body * so3::exp(Eigen::Vector3d(0.05, 0.02, -0.08));
  j.v_world += Eigen::Vector3d(-0.05, 0.02, 0.1);
  j.bias.acc_m_s2 += Eigen::Vector3d(0.01, 0, -0.02);
  j.bias.gyro_rad_s += Eigen::Vector3d(0, 0.003, 0.001);
  Blocks b = toBlocks(i, j);

  ImuFactor factor(pre, kG);
  double* blocks[] = {b.pose_i, b.sb_i, b.pose_j, b.sb_j};
  const int sizes[] = {7, 9, 7, 9};
  Eigen::Matrix<double, 15, 7, Eigen::RowMajor> J0, J2;
  Eigen::Matrix<double, 15, 9, Eigen::RowMajor> J1, J3;
  J0.setConstant(7.0);  // the pose blocks' 7th columns must be overwritten with zeros
  J2.setConstant(7.0);
  double* jac[] = {J0.data(), J1.data(), J2.data(), J3.data()};
  Eigen::Matrix<double, 15, 1> r0;
  ASSERT_TRUE(factor.Evaluate(blocks, r0.data(), jac));
  ASSERT_GT(r0.norm(), 100.0);

  // The factor's whitening, computed the same way (sqrt_info = L^T, L L^T = covariance^-1).
  const Eigen::Matrix<double, 15, 15> info =
      (pre->covariance() + 1e-12 * Eigen::Matrix<double, 15, 15>::Identity()).inverse();
  const Eigen::Matrix<double, 15, 15> sqrt_info =
      Eigen::LLT<Eigen::Matrix<double, 15, 15>>(0.5 * (info + info.transpose())).matrixL().transpose();
  const Eigen::PartialPivLU<Eigen::Matrix<double, 15, 15>> unwhiten(sqrt_info);
  Eigen::Matrix<double, 15, 1> raw;
  const double* cparams[] = {b.pose_i, b.sb_i, b.pose_j, b.sb_j};
  ASSERT_TRUE(factor.Evaluate(cparams, raw.data(), nullptr));
  raw = unwhiten.solve(raw);
  EXPECT_LT((raw - pre->residual(i, j, kG)).norm(), 1e-9) << "whitening is sqrt_info * r";

  const double h = 1e-6;
  for (int k = 0; k < 4; ++k) {
    const int tangent = sizes[k] == 7 ? 6 : 9;
    for (int d = 0; d < tangent; ++d) {
      double saved[9];
      std::copy(blocks[k], blocks[k] + sizes[k], saved);
      Eigen::Matrix<double, 15, 1> rp, rm;
      for (int sign : {1, -1}) {
        double delta[9] = {0};
        delta[d] = sign * h;
        if (sizes[k] == 7) {
          posePlus(saved, delta, blocks[k]);
        } else {
          for (int e = 0; e < 9; ++e) blocks[k][e] = saved[e] + delta[e];
        }
        factor.Evaluate(blocks, (sign > 0 ? rp : rm).data(), nullptr);
      }
      std::copy(saved, saved + sizes[k], blocks[k]);
      // Compared un-whitened: whitening weights position rows ~1e3 times more than rotation
      // rows, which would hide a wrong rotation block inside the column norm.
      const Eigen::Matrix<double, 15, 1> numeric = unwhiten.solve((rp - rm) / (2 * h));
      Eigen::Matrix<double, 15, 1> analytic;
      for (int row = 0; row < 15; ++row) analytic[row] = jac[k][row * sizes[k] + d];
      analytic = unwhiten.solve(analytic);
      EXPECT_LT((numeric - analytic).norm(), 1e-4 * std::max(1.0, numeric.norm()))
          << "block " << k << " column " << d << "\nnumeric  " << numeric.transpose() << "\nanalytic "
          << analytic.transpose();
    }
    if (sizes[k] == 7) {
      for (int row = 0; row < 15; ++row) EXPECT_EQ(jac[k][row * 7 + 6], 0.0);
    }
  }
}

}  // namespace
}  // namespace mmlio::estimator
