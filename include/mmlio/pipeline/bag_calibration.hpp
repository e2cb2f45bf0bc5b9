#pragma once
// `mmlio calibrate` and `calibration: auto`: the spinning LiDAR's extrinsic and clock offset from
// the start of a bag (calib::calibrateSpinningToSolid on the stationary start, then
// calib::calibrateTimeOffset on the first turns). The solid-state LiDAR keeps its factory
// extrinsic from the config (its IMU is the reference), so the result chains
// T_imu_spinning = T_imu_solid * T_solid_spinning.
#include <string>

#include "mmlio/calib/spatial_calibration.hpp"
#include "mmlio/calib/time_offset.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/pipeline/json.hpp"
#include "mmlio/pipeline/mount_check.hpp"

namespace mmlio::pipeline {

struct BagCalibrationOptions {
  int solid_frames = 10;              // solid-state frames accumulated at the stationary start (n)
  int spinning_sweeps = 10;           // spinning sweeps stacked in the same window
  double max_rest_gyro_rad_s = 0.05;  // stationary: every 50 ms gyro mean within this of the window's
  double max_rest_acc_m_s2 = 0.3;     // ... and every 50 ms accelerometer mean within this
  bool estimate_time_offset = true;
  double temporal_window_s = 120.0;  // bag time after the start searched for turns (only turning
                                     // sweeps are kept: memory follows the turns, not the window)
  double temporal_voxel_m = 0.05;    // kept sweeps are voxel-filtered (each voxel keeps a point's time)
  double motion_window_s = 20.0;     // when the still start cannot tell the mount: the solid-state
                                     // LiDAR's map of this much of the bag (0: refuse instead)
  double motion_radius_m = 5.0;      // ... of its frames within this distance of the start
  // A mount from motion stands on the frames' placement by the solid-state odometry, whose drift
  // over the window (centimetres to decimetres, up to a degree along a wall it faced) the frames
  // cannot tell apart from the mount: its stated uncertainty is at least this, per axis.
  double motion_sigma_translation_m = 0.06;
  double motion_sigma_rotation_deg = 0.5;
  calib::SpatialCalibrationConfig spatial;
  calib::TimeOffsetConfig temporal;
};

struct BagCalibrationResult {
  config::Calibration calibration;  // both LiDARs, ready for config::applyCalibration / writeCalibration
  std::string spinning, solid;      // their names
  calib::SpatialCalibrationResult spatial;
  calib::TimeOffsetResult temporal;  // temporal.ok == false: the config's clock offset was kept
  bool from_motion = false;          // the mount from the first seconds of motion, not the still start
  // The spinning LiDAR's stated extrinsic uncertainty in the IMU frame: one sigma of its position
  // and of its rotation about the IMU's x, y, z axes (calib::SpatialCalibrationResult::covariance).
  Eigen::Vector3d translation_sigma_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_sigma_rad = Eigen::Vector3d::Zero();
  Json report;       // what was measured, for report.json
  YAML::Node extra;  // fitness, overlap, points, offset sigma: for writeCalibration
};

/// Whether the spinning LiDAR's mount given in a rig file agrees with the solid-state LiDAR's view
/// at the bag's still start (see MountCheck).
MountCheck checkMountAtStart(const std::string& bag_path, const config::RigConfig& cfg);

/// Throws mmlio::Error with a one-line reason when it cannot calibrate: the config lacks a spinning
/// or a solid-state LiDAR, the rig moves during the stationary window, too few points, no overlap,
/// GICP refuses.
BagCalibrationResult calibrateBag(const std::string& bag_path, const config::RigConfig& cfg,
                                  const BagCalibrationOptions& options = BagCalibrationOptions());

}  // namespace mmlio::pipeline
