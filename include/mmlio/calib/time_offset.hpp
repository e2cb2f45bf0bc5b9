#pragma once
// Temporal calibration of a LiDAR against the IMU: the rotation the LiDAR sees between
// consecutive sweeps (scan-to-scan ICP) is compared with the gyroscope integrated over the same
// interval shifted by a candidate clock offset; the offset that makes them agree best is the
// estimate (t_imu = t_lidar_stamp + offset). Grid search, parabolic refinement, and a standard
// deviation from the cost's curvature and the residual spread. Needs rotation: turns in the
// first seconds of motion are what make it observable.
#include <map>
#include <string>
#include <vector>

#include "mmlio/backend/point_to_plane_icp.hpp"
#include "mmlio/core/types.hpp"

namespace mmlio::calib {

/// The sensor's rotation from t0 to t1 (sensor clock), R_sensor(t0)^T R_sensor(t1) = Exp(rotvec).
struct SensorRotation {
  Stamp t0_ns = 0, t1_ns = 0;
  Eigen::Vector3d rotvec = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // of the sensor, in its frame at t0
};

/// Gyro-based de-skew of the sweeps before their scan-to-scan registration, at a trial offset.
struct GyroDeskew {
  const std::vector<ImuSample>* imu = nullptr;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Isometry3d T_imu_sensor = Eigen::Isometry3d::Identity();
  double offset_s = 0.0;  // t_imu = t_stamp + offset_s
  // Sensor-frame velocity per sweep start stamp (from a previous registration pass); sweeps not
  // listed are de-skewed in rotation only. Walking at 1 m/s moves a sweep by 10 cm.
  const std::map<Stamp, Eigen::Vector3d>* velocity = nullptr;
};

/// Scan-to-scan rotations of consecutive sweeps (sensor frame). Raw sweeps are stamped at their
/// mid times; with `deskew` each sweep is first rotated to its end with the gyroscope (turning at
/// 1.5 rad/s smears a sweep by 9 deg, which biases raw scan-to-scan rotations) and the rotation is
/// stamped at the sweep ends. Pairs whose ICP fails are skipped.
std::vector<SensorRotation> sweepRotations(const std::vector<LidarScan>& sweeps,
                                           const backend::IcpConfig& icp = backend::IcpConfig(),
                                           const GyroDeskew* deskew = nullptr);

struct TimeOffsetConfig {
  double max_offset_s = 0.2;    // search range +-
  double step_s = 0.001;        // grid step (refined by a parabola)
  double min_rate_rad_s = 0.2;  // increments turning slower than this carry no timing information
  int min_increments = 10;      // fewer moving increments: refuse
};

struct TimeOffsetResult {
  bool ok = false;
  double offset_s = 0, sigma_s = 0;  // t_imu = t_stamp + offset_s
  int increments = 0;                // used
  double rms_rad = 0;                // residual rotation mismatch per increment at the estimate
  std::string message;
};

/// R_imu_sensor: rotation of the LiDAR's extrinsic. gyro_bias: from the stationary start.
/// One comparison of given rotations with the gyroscope.
TimeOffsetResult estimateTimeOffset(const std::vector<SensorRotation>& rotations, const Eigen::Matrix3d& R_imu_sensor,
                                    const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                                    const TimeOffsetConfig& cfg = TimeOffsetConfig());

/// The whole temporal calibration: raw scan-to-scan rotations give a first offset, then the
/// turning sweeps are de-skewed with the gyroscope at the current offset and re-registered until
/// the offset moves by less than a step (at most max_rounds).
TimeOffsetResult calibrateTimeOffset(const std::vector<LidarScan>& sweeps, const Eigen::Isometry3d& T_imu_sensor,
                                     const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                                     const TimeOffsetConfig& cfg = TimeOffsetConfig(), int max_rounds = 4);

}  // namespace mmlio::calib
