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
  int stride = 1;                                         // sweeps between the two compared
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

/// Scan-to-scan rotations (sensor frame) of each sweep and the ones `strides` sweeps later (1:
/// consecutive; longer strides need `deskew`). Raw sweeps are stamped at their mid times; with
/// `deskew` each sweep is first rotated to its end with the gyroscope (turning at 1.5 rad/s smears
/// a sweep by 9 deg, which biases raw scan-to-scan rotations) and the rotation is stamped at the
/// sweep ends. Pairs across a gap in the selection, and pairs whose ICP fails, are skipped.
std::vector<SensorRotation> sweepRotations(const std::vector<LidarScan>& sweeps,
                                           const backend::IcpConfig& icp = backend::IcpConfig(),
                                           const GyroDeskew* deskew = nullptr, const std::vector<int>& strides = {1});

struct TimeOffsetConfig {
  double max_offset_s = 0.2;    // search range +-
  double step_s = 0.001;        // grid step (refined by a parabola)
  double min_rate_rad_s = 0.2;  // increments turning slower than this carry no timing information
  int min_increments = 10;      // fewer moving increments: refuse
  int jackknife_blocks = 10;    // the stated sigma covers leaving out any one of this many runs of increments
  // The refinement compares rotations over 0.1-0.8 s: an increment shifted by the offset changes by
  // (rate at its end - rate at its start) * offset, which over 0.1 s of a gentle turn is too little
  // to see past the registration's own error.
  std::vector<int> strides = {1, 2, 4, 8};
  double refine_range_s = 0.04;      // searched +- around the first estimate
  double max_sigma_s = 0.003;        // a larger stated sigma: advice on which motion would do
  double deskew_smoothing_s = 0.05;  // the de-skew's gyroscope averaged over +- this
  double outlier_medians = 5.0;      // increments whose mismatch exceeds this many times the median ...
  double outlier_floor_rad = 0.003;  // ... and this are failed alignments: dropped
};

struct TimeOffsetResult {
  bool ok = false;
  double offset_s = 0, sigma_s = 0;  // t_imu = t_stamp + offset_s
  int increments = 0;                // used
  double rms_rad = 0;                // residual rotation mismatch per increment at the estimate
  // The standard deviation of the offsets each stride gives alone (0 when not computed): errors
  // that depend on the interval compared, which the jackknife over runs of increments cannot see.
  double stride_spread_s = 0;
  std::string message;
  std::string advice;  // when the sigma exceeds the config's max_sigma_s: which motion would pin it
};

/// R_imu_sensor: rotation of the LiDAR's extrinsic. gyro_bias: from the stationary start (what is
/// left of it is fitted out). One comparison of given rotations with the gyroscope, over offsets
/// center_s +- cfg.max_offset_s. The sigma is the larger of the cost curvature's and the jackknife's
/// over cfg.jackknife_blocks runs of increments.
TimeOffsetResult estimateTimeOffset(const std::vector<SensorRotation>& rotations, const Eigen::Matrix3d& R_imu_sensor,
                                    const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                                    const TimeOffsetConfig& cfg = TimeOffsetConfig(), double center_s = 0.0);

/// The whole temporal calibration: raw scan-to-scan rotations give a first offset, then the
/// turning sweeps are de-skewed with the gyroscope at the current offset and re-registered, over
/// cfg.strides, until the offset moves by less than a step (at most max_rounds). The stated sigma
/// is at least the spread of the offsets the strides give alone. When it exceeds cfg.max_sigma_s,
/// `advice` says which motion would determine it.
TimeOffsetResult calibrateTimeOffset(const std::vector<LidarScan>& sweeps, const Eigen::Isometry3d& T_imu_sensor,
                                     const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                                     const TimeOffsetConfig& cfg = TimeOffsetConfig(), int max_rounds = 4);

}  // namespace mmlio::calib
