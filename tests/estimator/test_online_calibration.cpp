#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/online_calibration.hpp"

namespace mmlio::estimator {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A room (12 x 9 x 3 m) with a pillar and two cabinets, as points 5 cm apart on every face: what
// both LiDARs see, the anchor exactly, the refined one through its miscalibration.
std::vector<Eigen::Vector3d> room() {
  struct Box {
    Eigen::Vector3d lo, hi;
  };
  const std::vector<Box> boxes = {{{-6, -4.5, 0}, {6, 4.5, 3}},
                                  {{1.0, 1.0, 0}, {1.6, 1.6, 3}},
                                  {{-4.0, -3.0, 0}, {-2.5, -2.2, 1.2}},
                                  {{3.0, -4.5, 0}, {4.2, -3.6, 2.0}}};
  std::vector<Eigen::Vector3d> pts;
  const double step = 0.05;
  for (const Box& b : boxes)
    for (int axis = 0; axis < 3; ++axis)
      for (double side : {b.lo[axis], b.hi[axis]}) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (double a = b.lo[u] + step / 2; a < b.hi[u]; a += step)
          for (double c = b.lo[v] + step / 2; c < b.hi[v]; c += step) {
            Eigen::Vector3d p;
            p[axis] = side;
            p[u] = a;
            p[v] = c;
            pts.push_back(p);
          }
      }
  return pts;
}

Eigen::Isometry3d pose(double x, double y, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.5);
  return T;
}

struct Rig {
  Eigen::Isometry3d T_imu_spinning;  // the truth
  double clock_error_s = 0.0;        // the spinning LiDAR's stamps are this much early
};

/// A robot drives through the room: straight stretches, stops and turns on the spot. Each sweep,
/// the anchor (solid state) sees a 80-degree cone ahead, the spinning LiDAR all around; the
/// spinning LiDAR's points are placed with the calibration's current correction.
OnlineCalibration drive(const Rig& truth, const LidarExtrinsic& given, const OnlineCalibrationConfig& cfg, int sweeps,
                        unsigned seed) {
  LidarExtrinsic anchor;
  anchor.name = "livox";
  anchor.kind = LidarKind::kSolidState;
  OnlineCalibration calib(cfg, {given, anchor}, {1, 0}, 1, 0.2, 0.05, 60.0);
  const std::vector<Eigen::Vector3d> world = room();
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  double x = -3.0, y = 0.0, yaw = 0.0;
  for (int k = 0; k < sweeps; ++k) {
    // 2 s forward at 0.8 m/s, 1 s turning at 60 deg/s, 0.5 s still; then again.
    const double phase = std::fmod(0.1 * k, 3.5);
    Eigen::Vector3d v_body = Eigen::Vector3d::Zero(), w_body = Eigen::Vector3d::Zero();
    if (phase < 2.0)
      v_body.x() = 0.8;
    else if (phase < 3.0)
      w_body.z() = ((k / 35) % 2 ? -60.0 : 60.0) * kDeg;
    x += 0.1 * v_body.x() * std::cos(yaw);
    y += 0.1 * v_body.x() * std::sin(yaw);
    yaw += 0.1 * w_body.z();
    if (std::abs(x) > 4.5 || std::abs(y) > 3.0) yaw += M_PI;  // turn back before the walls
    const Eigen::Isometry3d T = pose(std::clamp(x, -4.5, 4.5), std::clamp(y, -3.0, 3.0), yaw);
    Features f;
    const Eigen::Isometry3d T_body_world = T.inverse();
    const Eigen::Isometry3d placed = calib.clockShift(0, v_body, w_body) * calib.extrinsic(0);
    for (std::size_t i = k % 7; i < world.size(); i += 7) {
      const Eigen::Vector3d p = T_body_world * world[i];
      if (p.norm() > 12.0 || p.norm() < 0.5) continue;
      const Eigen::Vector3d jitter(noise(rng), noise(rng), noise(rng));
      if (std::atan2(std::abs(p.y()), p.x()) < 40 * kDeg && i % 2 == 0) {
        f.planes.emplace_back(p + jitter);
        f.plane_source.push_back(1);
      } else if (i % 2 == 1) {
        // What the spinning LiDAR measured: the point where the body was clock_error_s later.
        const Eigen::Vector3d moved = so3::exp(-w_body * truth.clock_error_s) * p - v_body * truth.clock_error_s;
        f.planes.emplace_back(placed * (truth.T_imu_spinning.inverse() * moved) + jitter);
        f.plane_source.push_back(0);
      }
    }
    if (k % 10 == 0) calib.addAnchorKeyframe(f, T);
    calib.observe(f, T, v_body, w_body, 1700000000000000000LL + k * 100000000LL);
  }
  return calib;
}

Rig spinningMount() {
  Rig r;
  r.T_imu_spinning.setIdentity();
  r.T_imu_spinning.linear() = (so3::exp(Eigen::Vector3d(0.02, -0.03, 0.05))).toRotationMatrix();
  r.T_imu_spinning.translation() = Eigen::Vector3d(0.03, -0.02, 0.18);
  return r;
}

LidarExtrinsic givenAs(const Eigen::Isometry3d& T) {
  LidarExtrinsic e;
  e.name = "velodyne";
  e.kind = LidarKind::kSpinning;
  e.T_imu_sensor = T;
  return e;
}

TEST(OnlineCalibration, FindsAClockTwentyMillisecondsOffAndAMountADegreeAndTwoCentimetresOff) {
  Rig truth = spinningMount();
  truth.clock_error_s = 0.020;
  Eigen::Isometry3d given = truth.T_imu_spinning;
  given.linear() = so3::exp(Eigen::Vector3d(0.3, 0.5, 0.8).normalized() * kDeg).toRotationMatrix() * given.linear();
  given.translation() += Eigen::Vector3d(0.6, -0.5, 0.62).normalized() * 0.02;
  OnlineCalibrationConfig cfg;
  cfg.apply = true;
  cfg.prior_sigma_translation_z_m = 0.05;  // the height refined too
  const OnlineCalibration calib = drive(truth, givenAs(given), cfg, 300, 1);
  // What a next run starts from (the estimate where roughly determined) is within 3 of its sigmas.
  const LidarCalibrationEstimate e = calib.estimates().at(0);
  EXPECT_NEAR(e.settled_time_offset_s, 0.020, std::max(3.0 * e.time_offset_sigma_s, 0.001));
  const Eigen::Vector3d translation_error =
      given.translation() + e.settled_translation_m - truth.T_imu_spinning.translation();
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(translation_error[i]), 3.0 * e.translation_sigma_m[i]) << "axis " << i;
  const Eigen::Matrix3d R = so3::exp(e.settled_rotation_rad).toRotationMatrix() * given.linear();
  EXPECT_LT(Eigen::AngleAxisd(R.transpose() * truth.T_imu_spinning.linear()).angle(), 0.1 * kDeg);
  EXPECT_LT(e.time_offset_sigma_s, 0.002);
}

TEST(OnlineCalibration, LeavesARightCalibrationWhereItIs) {
  const Rig truth = spinningMount();
  OnlineCalibrationConfig cfg;
  cfg.apply = true;
  cfg.prior_sigma_translation_z_m = 0.05;
  const OnlineCalibration calib = drive(truth, givenAs(truth.T_imu_spinning), cfg, 300, 2);
  const LidarCalibrationEstimate e = calib.estimates().at(0);
  EXPECT_NEAR(e.time_offset_s, 0.0, 0.001);
  EXPECT_LT(e.translation_m.norm(), 0.003);
  EXPECT_LT(e.rotation_rad.norm(), 0.05 * kDeg);
}

TEST(OnlineCalibration, KeepsTheHeightAsGivenWhenItsSigmaIsZero) {
  Rig truth = spinningMount();
  truth.clock_error_s = -0.015;
  Eigen::Isometry3d given = truth.T_imu_spinning;
  given.translation() += Eigen::Vector3d(0.01, -0.01, 0.01);
  OnlineCalibrationConfig cfg;
  cfg.apply = true;
  EXPECT_GT(cfg.prior_sigma_translation_z_m, 0.0);  // refined by default
  cfg.prior_sigma_translation_z_m = 0.0;
  const OnlineCalibration calib = drive(truth, givenAs(given), cfg, 300, 3);
  const LidarCalibrationEstimate e = calib.estimates().at(0);
  EXPECT_LT(std::abs(e.translation_m.z()), 1e-5);
  EXPECT_LT((e.translation_m.head<2>() - Eigen::Vector2d(-0.01, 0.01)).norm(), 0.004);  // x and y are refined
  EXPECT_NEAR(e.time_offset_s, -0.015, 0.002);                                          // and the clock
}

TEST(OnlineCalibration, OnlyEstimatesWhenItMayNotApply) {
  Rig truth = spinningMount();
  truth.clock_error_s = 0.012;
  OnlineCalibrationConfig cfg;
  cfg.apply = false;
  const LidarExtrinsic given = givenAs(truth.T_imu_spinning);
  const OnlineCalibration calib = drive(truth, given, cfg, 300, 4);
  const LidarCalibrationEstimate e = calib.estimates().at(0);
  EXPECT_TRUE(calib.extrinsic(0).isApprox(given.T_imu_sensor));
  EXPECT_EQ(e.time_offset_s, 0.0);
  // Measured through a fixed calibration, with each sweep's points placed where the estimate puts
  // them, the estimate reaches the error (what the next pass starts from).
  EXPECT_NEAR(e.settled_time_offset_s, 0.012, std::max(3.0 * e.time_offset_sigma_s, 0.001));
}

TEST(OnlineCalibration, WithoutASolidStateLidarItIsOff) {
  OnlineCalibration calib(OnlineCalibrationConfig{}, {givenAs(Eigen::Isometry3d::Identity())}, {1}, -1, 0.2, 0.05,
                          60.0);
  EXPECT_FALSE(calib.active());
  EXPECT_TRUE(calib.estimates().empty());
  EXPECT_TRUE(
      calib.clockShift(0, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ()).isApprox(Eigen::Isometry3d::Identity()));
}

}  // namespace
}  // namespace mmlio::estimator
