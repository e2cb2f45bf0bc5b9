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
    s.acc_m_s2 = q_world_imu.inverse() * Eigen::Vector3d(0, 0, 9.81) / scale +
                 0.02 / scale * Eigen::Vector3d(n(rng), n(rng), n(rng));  // same sensor, other unit
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
  EXPECT_NE(r.message.find("roll"), std::string::npos);
  EXPECT_DOUBLE_EQ(r.acc_scale, 1.0);
  EXPECT_LT((r.gyro_bias - bias).norm(), 1e-3);
  // Gravity maps onto -z; the estimated attitude differs from the truth only by a yaw.
  const Eigen::Vector3d up = r.q_world_imu * (tilt.inverse() * Eigen::Vector3d::UnitZ());
  EXPECT_LT((up - Eigen::Vector3d::UnitZ()).norm(), 3e-3);
  const Eigen::Vector3d x_world = r.q_world_imu * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(x_world.y(), x_world.x()), 0.0, 1e-9);
}

TEST(ImuInitializer, RecoversGravityDirectionAndGyroBiasFromAccelerationsReportedInG) {
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d bias(-0.004, 0.001, 0.002);
  ImuInitializer init;
  for (const auto& s : staticSamples(tilt, 9.81, 1.2, bias)) init.add(s);
  ASSERT_TRUE(init.ready());
  const ImuInitResult r = init.result();
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_DOUBLE_EQ(r.acc_scale, 9.80665);
  EXPECT_NEAR(r.gravity_norm_m_s2, 9.80665, 0.01);  // reported in m/s^2 whatever the input unit
  EXPECT_LT((r.gyro_bias - bias).norm(), 1e-3);
  const Eigen::Vector3d up = r.q_world_imu * (tilt.inverse() * Eigen::Vector3d::UnitZ());
  EXPECT_LT((up - Eigen::Vector3d::UnitZ()).norm(), 3e-3);
  // The summary names the roll the data implies.
  const Eigen::Matrix3d R = r.q_world_imu.toRotationMatrix();
  EXPECT_NEAR(std::atan2(R(2, 1), R(2, 2)), 0.15, 0.01);
  EXPECT_NE(r.message.find("9.80"), std::string::npos) << r.message;
}

TEST(ImuInitializer, RefusesASteadyTurnThatLooksLikeALargeGyroBias) {
  // Turntable about the vertical: constant rates and constant specific force, so block means are
  // still, but 0.3 rad/s is no gyroscope bias.
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 1.0, 2.0, Eigen::Vector3d(0, 0, 0.3))) {
    init.add(s);
  }
  EXPECT_FALSE(init.ready());
  EXPECT_NE(init.result().message.find("turning steadily"), std::string::npos) << init.result().message;
}

TEST(ImuInitializer, RefusesAnAccelerationMagnitudeThatIsNeitherGNorMetresPerSecondSquared) {
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 2.0, 2.0, Eigen::Vector3d::Zero())) init.add(s);
  EXPECT_FALSE(init.ready());
  EXPECT_FALSE(init.result().ok);
  EXPECT_NE(init.result().message.find("neither"), std::string::npos) << init.result().message;
}

TEST(ImuInitializer, WaitsWhileTheRigMovesAndSaysWhy) {
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 1.0, 1.5, Eigen::Vector3d::Zero(), 0.5))
    init.add(s);
  EXPECT_FALSE(init.ready());
  const ImuInitResult r = init.result();
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("turning: gyro std"), std::string::npos) << r.message;
}

TEST(ImuInitializer, ForcesAnInitialisationAfterTooLongWithoutRest) {
  ImuInitializer init;
  for (const auto& s : staticSamples(Eigen::Quaterniond::Identity(), 1.0, 3.0, Eigen::Vector3d::Zero(), 0.5))
    init.add(s);
  ASSERT_TRUE(init.ready());
  const ImuInitResult r = init.result();
  EXPECT_TRUE(r.ok);
  EXPECT_TRUE(r.forced);
  EXPECT_NE(r.message.find("forced"), std::string::npos);
}

}  // namespace
}  // namespace mmlio::imu
