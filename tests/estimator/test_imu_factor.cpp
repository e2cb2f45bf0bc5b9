#include <gtest/gtest.h>

#include <memory>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/imu_factor.hpp"
#include "mmlio/estimator/pose_manifold.hpp"

namespace mmlio::estimator {
namespace {

const Eigen::Vector3d kG(0, 0, -9.81);

std::shared_ptr<imu::Preintegration> somePreintegration() {
  ImuBias lin;
  lin.acc_m_s2 = {0.01, -0.02, 0.015};
  lin.gyro_rad_s = {0.001, 0.002, -0.001};
  auto pre = std::make_shared<imu::Preintegration>(lin, imu::ImuNoise{});
  for (int i = 0; i < 40; ++i) {
    const double t0 = i * 0.005, t1 = t0 + 0.005;
    auto acc = [](double t) { return Eigen::Vector3d(0.5 * std::sin(t), 0.2, 9.81 + 0.3 * std::cos(2 * t)); };
    auto gyro = [](double t) { return Eigen::Vector3d(0.1, -0.3 * t, 0.8); };
    pre->integrate(0.005, acc(t0), gyro(t0), acc(t1), gyro(t1));
  }
  return pre;
}

struct Blocks {
  double pose_i[7], sb_i[9], pose_j[7], sb_j[9];
};

Blocks someBlocks(const imu::Preintegration& pre) {
  NavState i;
  i.p_world = {1, 2, 0.5};
  i.q_world_body = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  i.v_world = {0.4, -0.2, 0.1};
  i.bias.acc_m_s2 = {0.02, -0.01, 0.01};
  i.bias.gyro_rad_s = {0.002, 0.001, 0.0};
  NavState j = pre.predict(i, kG);
  // Off the consistent solution, so every residual row is exercised.
  j.p_world += Eigen::Vector3d(0.01, -0.02, 0.005);
  j.q_world_body = j.q_world_body * so3::exp(Eigen::Vector3d(0.01, 0.0, -0.02));
  j.bias.acc_m_s2 += Eigen::Vector3d(0.001, 0, 0);
  Blocks b;
  poseToBlock(i.pose(), b.pose_i);
  poseToBlock(j.pose(), b.pose_j);
  Eigen::Map<Eigen::Matrix<double, 9, 1>>(b.sb_i) << i.v_world, i.bias.acc_m_s2, i.bias.gyro_rad_s;
  Eigen::Map<Eigen::Matrix<double, 9, 1>>(b.sb_j) << j.v_world, j.bias.acc_m_s2, j.bias.gyro_rad_s;
  return b;
}

TEST(ImuFactor, ResidualVanishesForStatesConsistentWithThePreintegration) {
  auto pre = somePreintegration();
  NavState i;
  i.v_world = {1, 0, 0};
  i.bias = pre->biasLin();
  const NavState j = pre->predict(i, kG);
  Blocks b;
  poseToBlock(i.pose(), b.pose_i);
  poseToBlock(j.pose(), b.pose_j);
  Eigen::Map<Eigen::Matrix<double, 9, 1>>(b.sb_i) << i.v_world, i.bias.acc_m_s2, i.bias.gyro_rad_s;
  Eigen::Map<Eigen::Matrix<double, 9, 1>>(b.sb_j) << j.v_world, j.bias.acc_m_s2, j.bias.gyro_rad_s;
  ImuFactor factor(pre, kG);
  const double* params[] = {b.pose_i, b.sb_i, b.pose_j, b.sb_j};
  Eigen::Matrix<double, 15, 1> r;
  ASSERT_TRUE(factor.Evaluate(params, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-5);
}

TEST(ImuFactor, AnalyticJacobiansMatchNumericTangentDifferences) {
  auto pre = somePreintegration();
  Blocks b = someBlocks(*pre);
  ImuFactor factor(pre, kG);
  double* blocks[] = {b.pose_i, b.sb_i, b.pose_j, b.sb_j};
  const int sizes[] = {7, 9, 7, 9};
  Eigen::Matrix<double, 15, 7, Eigen::RowMajor> J0, J2;
  Eigen::Matrix<double, 15, 9, Eigen::RowMajor> J1, J3;
  double* jac[] = {J0.data(), J1.data(), J2.data(), J3.data()};
  Eigen::Matrix<double, 15, 1> r0;
  ASSERT_TRUE(factor.Evaluate(blocks, r0.data(), jac));

  PoseManifold manifold;
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
        if (sizes[k] == 7) manifold.Plus(saved, delta, blocks[k]);
        else for (int e = 0; e < 9; ++e) blocks[k][e] = saved[e] + delta[e];
        factor.Evaluate(blocks, (sign > 0 ? rp : rm).data(), nullptr);
      }
      std::copy(saved, saved + sizes[k], blocks[k]);
      const Eigen::Matrix<double, 15, 1> numeric = (rp - rm) / (2 * h);
      Eigen::Matrix<double, 15, 1> analytic;
      for (int row = 0; row < 15; ++row) analytic[row] = jac[k][row * sizes[k] + d];
      EXPECT_LT((numeric - analytic).norm(), 1e-3 * std::max(1.0, numeric.norm()))
          << "block " << k << " column " << d << "\nnumeric " << numeric.transpose() << "\nanalytic "
          << analytic.transpose();
    }
    if (sizes[k] == 7) {
      for (int row = 0; row < 15; ++row) EXPECT_EQ(jac[k][row * 7 + 6], 0.0);
    }
  }
}

}  // namespace
}  // namespace mmlio::estimator
