#include <gtest/gtest.h>

#include <random>

#include "mmlio/imu/initializer.hpp"

namespace mmlio::imu {
namespace {

std::vector<ImuSample> staticSamples(const Eigen::Quaterniond& q_world_imu, double scale, double seconds,
                                     const Eigen::Vector3d& gyro_bias, double wobble_rad_s = 0.0) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<ImuSample> out;
  for (int i = 0; i < seconds * 200; ++i) {
    ImuSample s;
    s.stamp_ns = fromSec(100.0 + i / 200.0);
    s.acc_m_s2 = q_world_imu.inverse() * Eigen::Vector3d(0, 0, 9.81) / scale + 0.02 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    s.gyro_rad_s = gyro_bias + 0.003 * Eigen::Vector3d(n(rng), n(rng), n(rng)) +
                   wobble_rad_s * Eigen::Vector3d(std::sin(i * 0.02), 0, 0);
    out.push_back(s);
  }
  return out;
}

TEST(ImuInitializer, RecoversRollPitchAndGyroBiasAtRestWithYawZero) {
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d bias(0.003, -0.002, 0.004);
  ImuInitializer init;
  for (const auto& s : staticSamples(tilt, 1.0, 1.5, bias)) init.add(s);
  ASSERT_TRUE(init.ready());
  const ImuInitResult r = init.result();
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_FALSE(r.forced);
  EXPECT_NEAR(r.gravity_norm_m_s2, 9.81, 0.01);
  EXPECT_DOUBLE_EQ(r.acc_scale, 1.0);
  EXPECT_LT((r.gyro_bias - bias).norm(), 1e-3);
  // Gravity maps onto -z; the estimated attitude differs from the truth only by a yaw.
  const Eigen::Vector3d up = r.q_world_imu * (tilt.inverse() * Eigen::Vector3d::UnitZ());
  EXPECT_LT((up - Eigen::Vector3d::UnitZ()).norm(), 3e-3);
  const Eigen::Vector3d x_world = r.q_world_imu * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(x_world.y(), x_world.x()), 0.0, 1e-9);
}

TEST(ImuInitializer, NoticesAccelerationsReportedInG) {
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 9.81, 1.2, Eigen::Vector3d::Zero())) init.add(s);
  ASSERT_TRUE(init.ready());
  EXPECT_DOUBLE_EQ(init.result().acc_scale, 9.80665);
}

TEST(ImuInitializer, WaitsWhileTheRigMovesAndSaysWhy) {
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 1.0, 3.0, Eigen::Vector3d::Zero(), 0.5)) init.add(s);
  EXPECT_FALSE(init.ready());
  const ImuInitResult r = init.result();
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("gyro std"), std::string::npos) << r.message;
}

TEST(ImuInitializer, ForcesAnInitialisationAfterTooLongWithoutRest) {
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 1.0, 7.0, Eigen::Vector3d::Zero(), 0.5)) init.add(s);
  ASSERT_TRUE(init.ready());
  const ImuInitResult r = init.result();
  EXPECT_TRUE(r.ok);
  EXPECT_TRUE(r.forced);
  EXPECT_NE(r.message.find("forced"), std::string::npos);
}

}  // namespace
}  // namespace mmlio::imu
