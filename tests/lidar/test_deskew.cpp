#include <gtest/gtest.h>

#include <cmath>

#include "mmlio/lidar/deskew.hpp"

using namespace mmlio;
using mmlio::lidar::se3Exp;
using mmlio::lidar::SweepMotion;

namespace {

Eigen::Isometry3d makeExtrinsic() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.1, -0.2, 0.3);
  return T;
}

// Points of the static wall x = 5 (world) seen by a sensor while the body follows T_world_body(t);
// returns the sweep as measured (sensor frame at each point's time) and the truth at the sweep end.
template <typename PoseAt> void scanWall(const PoseAt& T_world_body, const Eigen::Isometry3d& T_imu_sensor,
                                         double sweep_s, LidarScan* scan, std::vector<Eigen::Vector3d>* truth_at_end) {
  const Eigen::Isometry3d T_world_sensor_end = T_world_body(sweep_s) * T_imu_sensor;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double t = sweep_s * i / (n - 1);
    const Eigen::Isometry3d T_world_sensor = T_world_body(t) * T_imu_sensor;
    // A ray towards world +x, fanning in azimuth and elevation.
    const double az = -0.5 + 1.0 * i / (n - 1), el = 0.3 * std::sin(i * 0.37);
    const Eigen::Vector3d d_world(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Vector3d o = T_world_sensor.translation();
    const Eigen::Vector3d p_world = o + (5.0 - o.x()) / d_world.x() * d_world;
    Point p;
    p.xyz = (T_world_sensor.inverse() * p_world).cast<float>();
    p.time_s = static_cast<float>(t);
    scan->points.push_back(p);
    truth_at_end->push_back(T_world_sensor_end.inverse() * p_world);
  }
}

double maxError(const LidarScan& scan, const std::vector<Eigen::Vector3d>& truth) {
  double e = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) e = std::max(e, (scan.points[i].xyz.cast<double>() - truth[i]).norm());
  return e;
}

}  // namespace

TEST(Deskew, WallScannedWhileRotatingAt90DegPerSecondLandsOnTheWallToUnderAMillimetre) {
  const double sweep_s = 0.1;
  const Eigen::Vector3d w(0, 0, M_PI / 2), v(0.5, 0.2, 0.0);  // 90 deg/s yaw and some translation
  const auto T_world_body = [&](double t) { return se3Exp(v * t, w * t); };
  const Eigen::Isometry3d T_imu_sensor = makeExtrinsic();
  LidarScan scan;
  std::vector<Eigen::Vector3d> truth;
  scanWall(T_world_body, T_imu_sensor, sweep_s, &scan, &truth);
  const double skewed_error = maxError(scan, truth);
  EXPECT_GT(skewed_error, 0.5);  // without compensation the first points are tens of cm off

  lidar::deskewToEnd(scan, T_imu_sensor, SweepMotion::constantTwist(v, w, sweep_s), sweep_s);
  EXPECT_LT(maxError(scan, truth), 1e-3);
}

TEST(Deskew, SampledMotionWithSlerpIsExactForAConstantRotationRate) {
  const double sweep_s = 0.1;
  const Eigen::Vector3d w(0.3, -0.2, M_PI / 2);
  const auto T_world_body = [&](double t) { return se3Exp(Eigen::Vector3d::Zero(), w * t); };
  const Eigen::Isometry3d T_imu_sensor = makeExtrinsic();
  LidarScan scan;
  std::vector<Eigen::Vector3d> truth;
  scanWall(T_world_body, T_imu_sensor, sweep_s, &scan, &truth);
  // IMU-rate samples (every 5 ms) of T_end_t = T_world_body(end)^-1 T_world_body(t).
  std::vector<double> times;
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k <= 20; ++k) {
    times.push_back(0.005 * k);
    poses.push_back(T_world_body(sweep_s).inverse() * T_world_body(0.005 * k));
  }
  lidar::deskewToEnd(scan, T_imu_sensor, SweepMotion(times, poses), sweep_s);
  EXPECT_LT(maxError(scan, truth), 1e-4);
}

TEST(Deskew, MotionIsClampedOutsideItsSamplesAndIdentityLeavesPointsAlone) {
  Eigen::Isometry3d A = Eigen::Isometry3d::Identity(), B = Eigen::Isometry3d::Identity();
  A.translation() = Eigen::Vector3d(1, 0, 0);
  const SweepMotion m({0.0, 0.1}, {A, B});
  EXPECT_TRUE(m.at(-1.0).isApprox(A));
  EXPECT_TRUE(m.at(5.0).isApprox(B));
  EXPECT_NEAR(m.at(0.05).translation().x(), 0.5, 1e-12);

  LidarScan scan;
  Point p;
  p.xyz = Eigen::Vector3f(1, 2, 3);
  scan.points = {p};
  lidar::deskewToEnd(scan, makeExtrinsic(), SweepMotion(), 0.1);
  EXPECT_TRUE(scan.points[0].xyz.isApprox(Eigen::Vector3f(1, 2, 3)));
}
