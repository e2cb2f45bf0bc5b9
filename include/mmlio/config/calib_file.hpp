#pragma once
// Calibration file: what `mmlio calibrate` and `mmlio simulate` write and `mmlio run --calib`
// reads. YAML, one top-level map per LiDAR name:
//
//   velodyne:
//     T_imu_sensor: [1, 0, 0, 0.1,  0, 1, 0, 0,  0, 0, 1, 0.2,  0, 0, 0, 1]  # 4x4 row-major
//     time_offset_s: 0.0     # t_imu = t_stamp + time_offset_s
//     fitness: 0.031         # any other key is kept by the writer and ignored by the reader
//   livox:
//     T_imu_sensor: [...]
//
// T_imu_sensor maps points from the sensor frame into the IMU frame. A top-level entry is a
// sensor when it is a map holding T_imu_sensor; every other top-level key (e.g. `imu:` noise,
// `generated_by:`) is metadata, ignored on read.

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <map>
#include <string>

namespace mmlio::config {

struct SensorCalibration {
  Eigen::Isometry3d T_imu_sensor = Eigen::Isometry3d::Identity();  // sensor -> IMU frame
  double time_offset_s = 0.0;                                      // t_imu = t_stamp + offset, s
};

using Calibration = std::map<std::string, SensorCalibration>;

/// Throws mmlio::Error naming the file (and line, sensor) when the file is missing, is not YAML,
/// holds no sensor, or a transform is not exactly 16 numbers / not rigid (rotation orthonormal
/// within 1e-6, bottom row 0 0 0 1). time_offset_s defaults to 0 when absent.
Calibration readCalibration(const std::string& path);

/// Writes atomically. `extra` (a map, optional): entries whose key is a sensor name and whose
/// value is a map are merged into that sensor's map (after T_imu_sensor and time_offset_s, which
/// they cannot override); all other entries are written as top-level metadata after the sensors.
void writeCalibration(const std::string& path, const Calibration& sensors, const YAML::Node& extra = YAML::Node());

}  // namespace mmlio::config
