#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "mmlio/core/so3.hpp"
#include "mmlio/imu/imu_integrator.hpp"
#include "mmlio/imu/preintegration.hpp"

namespace mmlio::imu {
namespace {

const Eigen::Vector3d kG(0, 0, -9.81);

// Body on a horizontal circle of radius r at angular rate w, facing along the velocity, with a
// constant climb rate: closed-form pose, velocity and the IMU it produces.
struct CircleMotion {
  double r = 2.0, w = 0.8, climb = 0.1;
  NavState state(double t) const {
    NavState s;
    s.stamp_ns = fromSec(t);
    s.p_world = {r * std::cos(w * t), r * std::sin(w * t), climb * t};
    s.v_world = {-r * w * std::sin(w * t), r * w * std::cos(w * t), climb};
    s.q_world_body = Eigen::AngleAxisd(w * t + M_PI / 2, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX());
    return s;
  }
  ImuSample sample(double t) const {
    const NavState s = state(t);
    const Eigen::Vector3d a_world(-r * w * w * std::cos(w * t), -r * w * w * std::sin(w * t), 0);
    ImuSample m;
    m.stamp_ns = fromSec(t);
    m.acc_m_s2 = s.q_world_body.inverse() * (a_world - kG);
    // Angular velocity w about world z, expressed in the body frame.
    m.gyro_rad_s = s.q_world_body.inverse() * Eigen::Vector3d(0, 0, w);
    return m;
  }
  std::vector<ImuSample> samples(double t0, double t1, double rate_hz) const {
    std::vector<ImuSample> out;
    const int n = static_cast<int>(std::round((t1 - t0) * rate_hz));
    for (int i = 0; i <= n; ++i) out.push_back(sample(t0 + i / rate_hz));
    return out;
  }
};

TEST(Preintegration, PredictsAClosedFormCircularMotionToAMillimetreOverOneSecond) {
  CircleMotion motion;
  Preintegration pre(ImuBias{}, ImuNoise{});
  pre.integrate(motion.samples(0.0, 1.0, 200.0));
  EXPECT_NEAR(pre.sumDt(), 1.0, 1e-9);
  const NavState predicted = pre.predict(motion.state(0.0), kG);
  const NavState truth = motion.state(1.0);
  EXPECT_LT((predicted.p_world - truth.p_world).norm(), 1e-3);
  EXPECT_LT((predicted.v_world - truth.v_world).norm(), 2e-3);
  EXPECT_LT(predicted.q_world_body.angularDistance(truth.q_world_body), 1e-4);
  EXPECT_LT(pre.residual(motion.state(0.0), truth, kG).norm(), 3e-3);
}

TEST(Preintegration, ConstantRateAndAccelerationGiveTheAnalyticDeltas) {
  // Pure rotation about z at 0.5 rad/s and a constant body-frame specific force: dR = Exp(w t).
  Preintegration pre(ImuBias{}, ImuNoise{});
  const Eigen::Vector3d w(0, 0, 0.5), a(0, 0, 0);
  for (int i = 0; i < 100; ++i) pre.integrate(0.01, a, w, a, w);
  EXPECT_LT(pre.deltaQ().angularDistance(so3::exp(w * 1.0)), 1e-9);
  EXPECT_LT(pre.deltaP().norm(), 1e-12);
  // Constant specific force without rotation: dv = a t, dp = a t^2 / 2.
  Preintegration lin(ImuBias{}, ImuNoise{});
  const Eigen::Vector3d f(1.0, -2.0, 0.5), zero(0, 0, 0);
  for (int i = 0; i < 100; ++i) lin.integrate(0.01, f, zero, f, zero);
  EXPECT_LT((lin.deltaV() - f).norm(), 1e-12);
  EXPECT_LT((lin.deltaP() - 0.5 * f).norm(), 1e-12);
}

TEST(Preintegration, ConstantYawRateWithConstantSpecificForceGivesTheClosedFormDeltas) {
  // Body turning at w about z while feeling a constant body-frame force f = (a, 0, c):
  // dv(t) = (a/w sin wt, a/w (1 - cos wt), c t), dp(t) = (a/w^2 (1 - cos wt), a/w (t - sin(wt)/w), c t^2/2).
  const double w = 0.7, a = 1.3, c = -0.4, T = 1.0;
  Preintegration pre(ImuBias{}, ImuNoise{});
  const Eigen::Vector3d gyro(0, 0, w), f(a, 0, c);
  pre.integrate(0.0, f, gyro);
  for (int i = 0; i < 200; ++i) pre.integrate(0.005, f, gyro);
  EXPECT_NEAR(pre.sumDt(), T, 1e-12);
  EXPECT_LT(pre.deltaQ().angularDistance(so3::exp(gyro * T)), 1e-9);
  const Eigen::Vector3d dv(a / w * std::sin(w * T), a / w * (1 - std::cos(w * T)), c * T);
  const Eigen::Vector3d dp(a / (w * w) * (1 - std::cos(w * T)), a / w * (T - std::sin(w * T) / w), 0.5 * c * T * T);
  EXPECT_LT((pre.deltaV() - dv).norm(), 1e-5) << pre.deltaV().transpose() << " vs " << dv.transpose();
  EXPECT_LT((pre.deltaP() - dp).norm(), 1e-5) << pre.deltaP().transpose() << " vs " << dp.transpose();
}

TEST(Preintegration, PushingSingleMeasurementsEqualsIntegratingSamplePairs) {
  CircleMotion motion;
  const auto samples = motion.samples(0.0, 0.5, 200.0);
  Preintegration pairs(ImuBias{}, ImuNoise{});
  pairs.integrate(samples);
  Preintegration pushed(ImuBias{}, ImuNoise{});
  pushed.integrate(0.0, samples[0].acc_m_s2, samples[0].gyro_rad_s);  // only records the start
  for (std::size_t k = 1; k < samples.size(); ++k) {
    pushed.integrate(toSec(samples[k].stamp_ns - samples[k - 1].stamp_ns), samples[k].acc_m_s2, samples[k].gyro_rad_s);
  }
  EXPECT_NEAR(pushed.sumDt(), pairs.sumDt(), 1e-12);
  EXPECT_LT((pushed.deltaP() - pairs.deltaP()).norm(), 1e-12);
  EXPECT_LT((pushed.deltaV() - pairs.deltaV()).norm(), 1e-12);
  EXPECT_LT(pushed.deltaQ().angularDistance(pairs.deltaQ()), 1e-12);
  EXPECT_LT((pushed.covariance() - pairs.covariance()).norm(), 1e-15);
}

TEST(Preintegration, ResidualIsZeroForStatesConsistentWithTheDeltas) {
  CircleMotion motion;
  ImuBias lin;
  lin.acc_m_s2 = {0.03, -0.02, 0.01};
  lin.gyro_rad_s = {0.004, 0.002, -0.003};
  Preintegration pre(lin, ImuNoise{});
  pre.integrate(motion.samples(0.0, 1.0, 200.0));
  NavState i = motion.state(0.0);
  i.bias = lin;
  const NavState j = pre.predict(i, kG);
  EXPECT_EQ(j.stamp_ns, fromSec(1.0));
  EXPECT_LT(pre.residual(i, j, kG).norm(), 1e-12);
  // Another bias at i: the corrected deltas keep prediction and residual consistent.
  i.bias.gyro_rad_s += Eigen::Vector3d(0.01, 0, -0.01);
  EXPECT_LT(pre.residual(i, pre.predict(i, kG), kG).norm(), 1e-12);
  // ... and a 1 cm error shows up as exactly that rotated into frame i.
  NavState off = pre.predict(i, kG);
  off.p_world.x() += 0.01;
  EXPECT_NEAR(pre.residual(i, off, kG).head<3>().norm(), 0.01, 1e-12);
}

TEST(Preintegration, BiasJacobiansMatchFiniteDifferencesOfReintegration) {
  CircleMotion motion;
  ImuBias lin;
  lin.acc_m_s2 = {0.02, 0.01, -0.03};
  lin.gyro_rad_s = {0.003, -0.002, 0.001};
  Preintegration pre(lin, ImuNoise{});
  pre.integrate(motion.samples(0.0, 1.0, 200.0));
  const Matrix15d& J = pre.jacobian();
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Eigen::Vector3d dp[2], dv[2], dth[2];
    for (int s = 0; s < 2; ++s) {
      ImuBias b = lin;
      (k < 3 ? b.acc_m_s2 : b.gyro_rad_s)[k % 3] += (s == 0 ? h : -h);
      Preintegration re = pre;
      re.repropagate(b);
      dp[s] = re.deltaP();
      dv[s] = re.deltaV();
      dth[s] = so3::log(pre.deltaQ().inverse() * re.deltaQ());  // right perturbation of dq
    }
    const int col = k < 3 ? 9 + k : 12 + (k - 3);
    const Eigen::Vector3d num_p = (dp[0] - dp[1]) / (2 * h), num_v = (dv[0] - dv[1]) / (2 * h),
                          num_th = (dth[0] - dth[1]) / (2 * h);
    EXPECT_LT((num_p - J.block<3, 1>(0, col)).norm(), 1e-4 * std::max(1.0, num_p.norm())) << "bias " << k;
    EXPECT_LT((num_v - J.block<3, 1>(6, col)).norm(), 1e-4 * std::max(1.0, num_v.norm())) << "bias " << k;
    EXPECT_LT((num_th - J.block<3, 1>(3, col)).norm(), 1e-4 * std::max(1.0, num_th.norm())) << "bias " << k;
  }
  // The accelerometer bias does not rotate the delta; a gyro bias over 1 s rotates it by ~1 s.
  EXPECT_LT((J.block<3, 3>(3, 9).norm()), 1e-15);
  EXPECT_NEAR((J.block<3, 3>(3, 12).norm()), std::sqrt(3.0), 0.2);
}

TEST(Preintegration, CovarianceGrowsAndStaysSymmetricPositiveDefinite) {
  CircleMotion motion;
  Preintegration pre(ImuBias{}, ImuNoise{});
  const auto samples = motion.samples(0.0, 1.0, 200.0);
  double previous_trace = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    pre.integrate(0.005, samples[i - 1].acc_m_s2, samples[i - 1].gyro_rad_s, samples[i].acc_m_s2,
                  samples[i].gyro_rad_s);
    EXPECT_GT(pre.covariance().trace(), previous_trace);
    previous_trace = pre.covariance().trace();
  }
  EXPECT_LT((pre.covariance() - pre.covariance().transpose()).norm(), 1e-15);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix15d>(pre.covariance()).eigenvalues().minCoeff(), 0.0);
}

TEST(Preintegration, FirstOrderBiasCorrectionMatchesReintegration) {
  CircleMotion motion;
  Preintegration pre(ImuBias{}, ImuNoise{});
  pre.integrate(motion.samples(0.0, 1.0, 200.0));
  ImuBias b;
  b.acc_m_s2 = {0.02, -0.01, 0.03};
  b.gyro_rad_s = {0.002, 0.001, -0.003};
  Eigen::Quaterniond dq;
  Eigen::Vector3d dv, dp;
  pre.corrected(b, &dq, &dv, &dp);
  Preintegration re = pre;
  re.repropagate(b);
  EXPECT_LT((dp - re.deltaP()).norm(), 1e-4);
  EXPECT_LT((dv - re.deltaV()).norm(), 1e-4);
  EXPECT_LT(dq.angularDistance(re.deltaQ()), 1e-5);
  // ... and the correction is not trivial: it moved the deltas by much more than its error.
  EXPECT_GT((dp - pre.deltaP()).norm(), 1e-2 * 0.5);
}

TEST(ImuIntegrator, PropagationAgreesWithPreintegrationAndInterpolatesQueries) {
  CircleMotion motion;
  const auto samples = motion.samples(0.0, 1.0, 200.0);
  const std::vector<Stamp> queries{fromSec(0.2537), fromSec(0.5), fromSec(1.0)};
  const auto states = propagate(motion.state(0.0), samples, queries, kG);
  ASSERT_EQ(states.size(), 3u);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    EXPECT_EQ(states[i].stamp_ns, queries[i]);
    EXPECT_LT((states[i].p_world - motion.state(toSec(queries[i])).p_world).norm(), 1e-3);
  }
}

TEST(ImuIntegrator, SamplesBetweenAreCutExactlyAtTheInterval) {
  CircleMotion motion;
  const auto samples = motion.samples(0.0, 1.0, 200.0);
  const auto cut = imuBetween(samples, fromSec(0.1012), fromSec(0.2033));
  ASSERT_GE(cut.size(), 20u);
  EXPECT_EQ(cut.front().stamp_ns, fromSec(0.1012));
  EXPECT_EQ(cut.back().stamp_ns, fromSec(0.2033));
  for (std::size_t i = 1; i < cut.size(); ++i) EXPECT_GT(cut[i].stamp_ns, cut[i - 1].stamp_ns);
}

}  // namespace
}  // namespace mmlio::imu

namespace mmlio::imu {
namespace {

TEST(ImuIntegrator, CutSamplesLetAPreintegrationSpanExactlyAnOffGridInterval) {
  CircleMotion motion;
  const auto buffer = motion.samples(0.0, 2.0, 200.0);
  const Stamp t0 = fromSec(0.3217), t1 = fromSec(1.0583);
  Preintegration pre(ImuBias{}, ImuNoise{});
  pre.integrate(imuBetween(buffer, t0, t1));
  EXPECT_NEAR(pre.sumDt(), toSec(t1 - t0), 1e-12);
  const NavState predicted = pre.predict(motion.state(toSec(t0)), kG);
  EXPECT_EQ(predicted.stamp_ns, t1);
  EXPECT_LT((predicted.p_world - motion.state(toSec(t1)).p_world).norm(), 1e-3);
  EXPECT_LT(predicted.q_world_body.angularDistance(motion.state(toSec(t1)).q_world_body), 1e-4);
}

TEST(ImuIntegrator, PropagationFromAnOffGridStartMatchesTheTruthAndPreintegration) {
  CircleMotion motion;
  const auto buffer = motion.samples(0.0, 1.0, 200.0);
  const Stamp t0 = fromSec(0.1234);
  const std::vector<Stamp> queries{fromSec(0.1234), fromSec(0.4), fromSec(0.8761)};
  const auto states = propagate(motion.state(toSec(t0)), buffer, queries, kG);
  ASSERT_EQ(states.size(), queries.size());
  EXPECT_LT((states[0].p_world - motion.state(toSec(t0)).p_world).norm(), 1e-12);  // no time, no motion
  for (std::size_t k = 1; k < queries.size(); ++k) {
    const NavState truth = motion.state(toSec(queries[k]));
    EXPECT_LT((states[k].p_world - truth.p_world).norm(), 1e-3) << k;
    EXPECT_LT((states[k].v_world - truth.v_world).norm(), 2e-3) << k;
    EXPECT_LT(states[k].q_world_body.angularDistance(truth.q_world_body), 1e-4) << k;
    // Same midpoint scheme on the same cut samples: strapdown and preintegration agree closely.
    Preintegration pre(ImuBias{}, ImuNoise{});
    pre.integrate(imuBetween(buffer, t0, queries[k]));
    EXPECT_LT((pre.predict(motion.state(toSec(t0)), kG).p_world - states[k].p_world).norm(), 1e-6) << k;
  }
}

}  // namespace
}  // namespace mmlio::imu
