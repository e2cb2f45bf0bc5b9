// Spatio-temporal LiDAR calibration on the simulated office (known truth): the VLP-16's extrinsic
// relative to the Livox from the stationary start, and the Velodyne clock offset from the turns.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "mmlio/calib/spatial_calibration.hpp"
#include "mmlio/calib/time_offset.hpp"
#include "mmlio/sim/simulator.hpp"

namespace mmlio::calib {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::vector<Eigen::Vector3d> points(const LidarScan& scan) {
  std::vector<Eigen::Vector3d> out;
  for (const Point& p : scan.points) out.push_back(p.xyz.cast<double>());
  return out;
}

struct Stationary {
  std::vector<Eigen::Vector3d> solid, spinning;
};

/// The first second at rest: 10 Livox frames accumulated, 3 Velodyne sweeps stacked.
Stationary stationaryStart(const sim::Simulator& sim) {
  Stationary s;
  for (int k = 0; k < 10; ++k) {
    const auto p = points(sim.livoxFrame(k));
    s.solid.insert(s.solid.end(), p.begin(), p.end());
  }
  for (int k = 0; k < 3; ++k) {
    const auto p = points(sim.velodyneSweep(k));
    s.spinning.insert(s.spinning.end(), p.begin(), p.end());
  }
  return s;
}

Eigen::Isometry3d trueSolidSpinning(const sim::Simulator& sim) {
  return sim.livoxExtrinsic().T_imu_sensor.inverse() * sim.velodyneExtrinsic().T_imu_sensor;
}

void expectClose(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d err = truth.inverse() * est;
  const double rot_deg = Eigen::AngleAxisd(err.rotation()).angle() / kDeg;
  std::printf("  error %.2f mm, %.4f deg\n", 1e3 * err.translation().norm(), rot_deg);
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(rot_deg, 0.1);
}

TEST(SpatialCalibration, RecoversTheVelodyneMountFromTheNominalConfigGuess) {
  const sim::Simulator sim(sim::fullWalk("office"));
  const Stationary s = stationaryStart(sim);
  // The config preset's placeholder: 0.2 m above the IMU, axes aligned (3 deg yaw, 2.5 deg tilt off).
  Eigen::Isometry3d T_imu_velodyne_nominal = Eigen::Isometry3d::Identity();
  T_imu_velodyne_nominal.translation() = Eigen::Vector3d(0, 0, 0.2);
  const Eigen::Isometry3d guess = sim.livoxExtrinsic().T_imu_sensor.inverse() * T_imu_velodyne_nominal;
  const SpatialCalibrationResult r = calibrateSpinningToSolid(s.spinning, s.solid, guess);
  std::printf("%s\n", r.message.c_str());
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_FALSE(r.yaw_searched);
  expectClose(r.T_solid_spinning, trueSolidSpinning(sim));
}

TEST(SpatialCalibration, FindsTheMountByYawSearchWithoutAGuess) {
  const sim::Simulator sim(sim::fullWalk("office"));
  const Stationary s = stationaryStart(sim);
  // A Velodyne mounted turned by 120 deg: the yaw search must find it.
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(120 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> turned;
  for (const auto& p : s.spinning) turned.push_back(turn.inverse() * p);  // points in the turned sensor frame
  const SpatialCalibrationResult r = calibrateSpinningToSolid(turned, s.solid, std::nullopt);
  std::printf("%s\n", r.message.c_str());
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(r.yaw_searched);
  expectClose(r.T_solid_spinning, trueSolidSpinning(sim) * turn);
}

TEST(SpatialCalibration, RefusesCloudsOfDifferentPlaces) {
  const sim::Simulator office(sim::fullWalk("office"));
  const sim::Simulator hall(sim::fullWalk("hall"));
  const SpatialCalibrationResult r =
      calibrateSpinningToSolid(stationaryStart(office).spinning, stationaryStart(hall).solid, std::nullopt);
  std::printf("%s\n", r.message.c_str());
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.message.empty());
}

TEST(TimeOffset, RecoversAVelodyneClockOffsetOf70MillisecondsFromTheTurns) {
  sim::SimOptions options = sim::fullWalk("office");
  options.velodyne_time_offset_s = 0.07;
  const sim::Simulator sim(options);
  std::vector<LidarScan> sweeps;
  // The first two U-turns (13.5-15.7 s, 26.5-28.3 s), with a second of walking on either side.
  for (int k = 125; k < 168; ++k) sweeps.push_back(sim.velodyneSweep(k));
  for (int k = 255; k < 295; ++k) sweeps.push_back(sim.velodyneSweep(k));
  const TimeOffsetResult r =
      calibrateTimeOffset(sweeps, sim.velodyneExtrinsic().T_imu_sensor, sim.imu(), sim.initialBias().gyro_rad_s);
  std::printf("offset %.4f s +- %.4f s from %d increments (rms %.5f rad): %s\n", r.offset_s, r.sigma_s, r.increments,
              r.rms_rad, r.message.c_str());
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.offset_s, 0.07, 0.002);
  // The stated uncertainty is honest: small, and not smaller than the error it makes.
  EXPECT_GT(r.sigma_s, 0.0);
  EXPECT_LT(r.sigma_s, 0.005);
  EXPECT_LT(std::abs(r.offset_s - 0.07), 3.0 * r.sigma_s);
}

TEST(TimeOffset, RefusesWhenTheRigDoesNotTurn) {
  sim::SimOptions options = sim::fullWalk("office");
  options.velodyne_time_offset_s = 0.07;
  const sim::Simulator sim(options);
  std::vector<LidarScan> sweeps;
  for (int k = 0; k < 15; ++k) sweeps.push_back(sim.velodyneSweep(k));  // the stationary start
  const TimeOffsetResult r = estimateTimeOffset(sweepRotations(sweeps), sim.velodyneExtrinsic().T_imu_sensor.linear(),
                                                sim.imu(), sim.initialBias().gyro_rad_s);
  std::printf("%s\n", r.message.c_str());
  EXPECT_FALSE(r.ok);
}

}  // namespace
}  // namespace mmlio::calib
