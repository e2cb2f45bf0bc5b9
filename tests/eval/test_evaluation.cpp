// Trajectory metrics on synthetic trajectories whose errors are known by construction.
#include <gtest/gtest.h>

#include <cmath>

#include "mmlio/core/error.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/eval/association.hpp"
#include "mmlio/eval/evaluation.hpp"

namespace mmlio::eval {
namespace {

constexpr Stamp kStart = 1'600'000'000'000'000'000;  // an absolute, bag-like epoch

Eigen::Isometry3d pose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = p;
  return T;
}

/// Samples `f(t)` (t in seconds since kStart) at `rate_hz` over [t0, t1].
template <typename F> Trajectory sample(F f, double rate_hz, double t0_s, double t1_s) {
  Trajectory out;
  const int n = static_cast<int>(std::floor((t1_s - t0_s) * rate_hz + 1e-9));
  for (int i = 0; i <= n; ++i) {
    const double t = t0_s + i / rate_hz;
    out.push_back({kStart + fromSec(t), f(t)});
  }
  return out;
}

// A 3D wiggly path with turning heading: nothing collinear, so alignment is well posed.
Eigen::Isometry3d curvy(double t) {
  const Eigen::Vector3d p(8.0 * std::sin(0.2 * t), 5.0 * std::sin(0.3 * t) + t, 0.5 * std::sin(0.5 * t));
  return pose(p, so3::exp(Eigen::Vector3d(0.05 * std::sin(t), 0.02, 0.2 * t)));
}

Eigen::Isometry3d straightX(double t) { return pose(Eigen::Vector3d(t, 0.0, 0.0)); }

TEST(Evaluation, RigidlyMovedCopyOfGroundTruthHasZeroAteAfterAlignmentAndFullCoverage) {
  const Trajectory gt = sample(curvy, 200.0, 0.0, 60.0);
  const Eigen::Isometry3d T_est_gt =
      pose(Eigen::Vector3d(120.0, -35.0, 4.0), so3::exp(Eigen::Vector3d(0.3, -1.1, 2.4)));
  Trajectory est;
  for (size_t i = 0; i < gt.size(); i += 20) est.push_back({gt[i].stamp_ns, T_est_gt * gt[i].T_world_body});

  const EvalResult r = evaluate(gt, est, {});
  EXPECT_EQ(r.num_associated, est.size());
  EXPECT_LT(r.ate_rmse_m, 1e-9);
  EXPECT_LT(r.ate_max_m, 1e-9);
  EXPECT_NEAR(r.coverage, 1.0, 1e-12);
  EXPECT_LT(r.rpe_10m_pct, 1e-9);
  EXPECT_LT(r.rpe_10m_deg_per_m, 1e-6);
  EXPECT_TRUE(r.T_gt_est.isApprox(T_est_gt.inverse(), 1e-9));
  // Without alignment the offset is the error.
  EvalOptions raw;
  raw.align = false;
  EXPECT_GT(evaluate(gt, est, raw).ate_rmse_m, 10.0);
}

// A run tilted whole: the alignment turns it level (ATE zero), so only the metrics against gravity
// can say that its height drifted with the distance travelled.
TEST(Evaluation, ARunTiltedWholeHasZeroAteButItsTiltAndHeightErrorAreStated) {
  const Trajectory gt = sample(straightX, 10.0, 0.0, 50.0);  // 50 m along x, level
  const double tilt_rad = 0.5 * M_PI / 180.0;                // pitched 0.5 deg about y, and turned in yaw
  const Eigen::Isometry3d T_est_gt =
      pose(Eigen::Vector3d(1.0, 2.0, 0.0), Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                                                              Eigen::AngleAxisd(tilt_rad, Eigen::Vector3d::UnitY())));
  Trajectory est;
  for (const StampedPose& p : gt) est.push_back({p.stamp_ns, T_est_gt * p.T_world_body});
  const EvalResult tilted = evaluate(gt, est, {});
  EXPECT_LT(tilted.ate_rmse_m, 1e-9);
  EXPECT_NEAR(tilted.tilt_rmse_deg, 0.5, 1e-9);
  EXPECT_NEAR(tilted.tilt_max_deg, 0.5, 1e-9);
  EXPECT_NEAR(tilted.height_error_max_m, 50.0 * std::sin(tilt_rad), 1e-9);  // 44 cm after 50 m

  // Turned in yaw and moved only: level, nothing to state.
  Trajectory turned;
  const Eigen::Isometry3d T_yaw =
      pose(Eigen::Vector3d(1.0, 2.0, 3.0), Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ())));
  for (const StampedPose& p : gt) turned.push_back({p.stamp_ns, T_yaw * p.T_world_body});
  const EvalResult level = evaluate(gt, turned, {});
  EXPECT_LT(level.tilt_max_deg, 1e-9);
  EXPECT_LT(level.height_error_max_m, 1e-9);
}

TEST(Evaluation, OnePercentScaleDriftAlongAStraightPathGivesOnePercentRpe) {
  const Trajectory gt = sample(straightX, 200.0, 0.0, 60.0);  // 60 m at 1 m/s
  // The estimate travels 1.01 m per GT metre: every 10 m segment is 0.1 m too long.
  const Trajectory est = sample([](double t) { return pose(Eigen::Vector3d(1.01 * t, 0.0, 0.0)); }, 10.0, 0.0, 60.0);
  const EvalResult r = evaluate(gt, est, {});
  EXPECT_NEAR(r.rpe_10m_pct, 1.0, 1e-6);
  EXPECT_NEAR(r.rpe_10m_deg_per_m, 0.0, 1e-9);
  EXPECT_EQ(r.rpe_num_segments, 601u - 100u);  // starts 0..50 s at 10 Hz whose +10 m end exists
  EXPECT_NEAR(r.path_length_m, 60.0, 1e-9);
  EXPECT_NEAR(r.end_to_end_m, 60.6, 1e-9);
  EXPECT_NEAR(r.gt_end_to_end_m, 60.0, 1e-9);
}

TEST(Evaluation, HeadingDriftOfTwoTenthsDegreePerMetreIsTheRpeRotation) {
  const double drift_rad_per_m = 0.2 * M_PI / 180.0;
  const Trajectory gt = sample(straightX, 200.0, 0.0, 40.0);
  const Trajectory est = sample(
      [&](double t) { return pose(Eigen::Vector3d(t, 0, 0), so3::exp(Eigen::Vector3d(0, 0, drift_rad_per_m * t))); },
      10.0, 0.0, 40.0);
  const EvalResult r = evaluate(gt, est, {});
  EXPECT_NEAR(r.rpe_10m_deg_per_m, 0.2, 1e-9);
  // Positions agree exactly; only the heading drifts.
  EXPECT_LT(r.ate_rmse_m, 1e-9);
}

TEST(Evaluation, LateralOffsetOnHalfTheTrajectoryGivesTheHandComputedAte) {
  const Trajectory gt = sample(straightX, 200.0, 0.0, 20.0);
  Trajectory est;
  for (int i = 0; i < 200; ++i) {  // 200 poses at 10 Hz over [0, 19.9] s
    const double t = i * 0.1;
    est.push_back({kStart + fromSec(t), pose(Eigen::Vector3d(t, i >= 100 ? 0.1 : 0.0, 0.0))});
  }
  EvalOptions raw;
  raw.align = false;
  const EvalResult r = evaluate(gt, est, raw);
  ASSERT_EQ(r.num_associated, 200u);
  // Half the errors are 0, half 0.1 m: RMSE = sqrt(0.5 * 0.01), mean 0.05, max 0.1, median 0.05.
  EXPECT_NEAR(r.ate_rmse_m, std::sqrt(0.005), 1e-12);
  EXPECT_NEAR(r.ate_mean_m, 0.05, 1e-12);
  EXPECT_NEAR(r.ate_median_m, 0.05, 1e-12);
  EXPECT_NEAR(r.ate_max_m, 0.1, 1e-12);
}

TEST(Evaluation, EndToEndErrorOfALoopIsTheEstimatesGapBetweenStartAndEnd) {
  const double period_s = 60.0, radius_m = 10.0;
  const auto circle = [&](double t) {
    const double a = 2.0 * M_PI * t / period_s;
    return pose(radius_m * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0), so3::exp(Eigen::Vector3d(0, 0, a)));
  };
  const Trajectory gt = sample(circle, 200.0, 0.0, period_s);
  // The estimate drifts linearly to (0.3, 0.4, 0) by the end of the loop: end-to-end 0.5 m.
  const Trajectory est = sample(
      [&](double t) {
        Eigen::Isometry3d T = circle(t);
        T.translation() += (t / period_s) * Eigen::Vector3d(0.3, 0.4, 0.0);
        return T;
      },
      10.0, 0.0, period_s);
  const EvalResult r = evaluate(gt, est, {});
  EXPECT_NEAR(r.end_to_end_m, 0.5, 1e-9);
  EXPECT_NEAR(r.gt_end_to_end_m, 0.0, 1e-9);
  EXPECT_NEAR(r.path_length_m, 2.0 * M_PI * radius_m, 1e-3);
}

TEST(Evaluation, GroundTruthInterpolatedAtHalfPeriodShiftedStampsIsExactOnLinearMotion) {
  // Constant velocity and constant yaw rate: linear interpolation and slerp are exact.
  const auto motion = [](double t) {
    return pose(Eigen::Vector3d(1.5 * t, -0.5 * t, 0.2 * t), so3::exp(Eigen::Vector3d(0.0, 0.0, 0.3 * t)));
  };
  const Trajectory gt = sample(motion, 200.0, 0.0, 30.0);
  const Trajectory est = sample(motion, 10.0, 0.0025, 29.9);  // half a GT period off every sample
  const std::vector<AssociatedPose> pairs = associate(gt, est, 0.05);
  ASSERT_EQ(pairs.size(), est.size());
  for (const AssociatedPose& pair : pairs) {
    EXPECT_LT((pair.T_world_gt.translation() - pair.T_world_est.translation()).norm(), 1e-9);
    EXPECT_TRUE(pair.T_world_gt.linear().isApprox(pair.T_world_est.linear(), 1e-9));
  }
  EvalOptions raw;
  raw.align = false;
  const EvalResult r = evaluate(gt, est, raw);
  EXPECT_LT(r.ate_max_m, 1e-9);
  EXPECT_LT(r.rpe_10m_deg_per_m, 1e-6);
}

TEST(Evaluation, EstimateOverTheFirstHalfCoversHalfTheGroundTruth) {
  const Trajectory gt = sample(curvy, 200.0, 0.0, 40.0);
  const Trajectory est = sample(curvy, 10.0, 0.0, 20.0);
  const EvalResult r = evaluate(gt, est, {});
  EXPECT_NEAR(r.coverage, 0.5, 1e-9);
  EXPECT_EQ(r.num_associated, 201u);
}

TEST(Evaluation, EstimatePosesOutsideTheGroundTruthSpanOrInADropoutAreNotAssociated) {
  Trajectory gt = sample(straightX, 200.0, 0.0, 10.0);
  // Remove GT over (4, 6) s: a 2 s dropout.
  gt.erase(std::remove_if(gt.begin(), gt.end(),
                          [](const StampedPose& p) {
                            const double t = toSec(p.stamp_ns - kStart);
                            return t > 4.0 + 1e-6 && t < 6.0 - 1e-6;
                          }),
           gt.end());
  const Trajectory est = sample(straightX, 10.0, -2.0, 12.0);  // 141 poses, 40 outside GT
  // Inside the span: 0..10 s is 101 poses; 4.1..5.9 (19 poses) are > 0.05 s from any GT sample.
  EXPECT_EQ(associate(gt, est, 0.05).size(), 101u - 19u);
  // A gap tolerance larger than the dropout interpolates across it.
  EXPECT_EQ(associate(gt, est, 1.5).size(), 101u);
}

TEST(Evaluation, TrajectoriesWithoutTimeOverlapAreRejectedWithAClockHint) {
  const Trajectory gt = sample(straightX, 200.0, 0.0, 10.0);
  const Trajectory est = sample(straightX, 10.0, 100.0, 110.0);
  try {
    evaluate(gt, est, {});
    FAIL() << "expected mmlio::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("clock"), std::string::npos) << e.what();
  }
  EXPECT_THROW(evaluate(gt, Trajectory{}, {}), Error);
  EXPECT_THROW(evaluate(Trajectory{}, est, {}), Error);
}

TEST(Evaluation, ScaledAlignmentRecoversAHalfScaleEstimate) {
  const Trajectory gt = sample(curvy, 200.0, 0.0, 30.0);
  const Eigen::Isometry3d T_est_gt = pose(Eigen::Vector3d(3.0, 1.0, -2.0), so3::exp(Eigen::Vector3d(0.1, 0.2, 0.7)));
  Trajectory est;
  for (size_t i = 0; i < gt.size(); i += 20) {
    Eigen::Isometry3d T = T_est_gt * gt[i].T_world_body;
    T.translation() *= 0.5;
    est.push_back({gt[i].stamp_ns, T});
  }
  EvalOptions with_scale;
  with_scale.scale = true;
  const EvalResult r = evaluate(gt, est, with_scale);
  EXPECT_NEAR(r.scale, 2.0, 1e-9);
  EXPECT_LT(r.ate_rmse_m, 1e-9);
  EXPECT_GT(evaluate(gt, est, {}).ate_rmse_m, 1.0);  // rigid alignment cannot absorb the scale
}

TEST(Evaluation, JsonLineIsOneLineWithTheMetricsAndNullForUndefinedRpe) {
  const Trajectory gt = sample(straightX, 200.0, 0.0, 5.0);  // 5 m: shorter than one RPE segment
  const Trajectory est = sample(straightX, 10.0, 0.0, 5.0);
  const std::string json = toJsonLine(evaluate(gt, est, {}));
  EXPECT_EQ(json.find('\n'), std::string::npos);
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  for (const char* key : {"\"ate_rmse_m\":", "\"end_to_end_m\":5", "\"coverage\":1", "\"num_associated\":51",
                          "\"path_length_m\":5", "\"rpe_10m_pct\":null", "\"rpe_10m_deg_per_m\":null"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
}

}  // namespace
}  // namespace mmlio::eval
