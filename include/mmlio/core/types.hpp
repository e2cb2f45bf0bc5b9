#pragma once
// Core data types of mmlio: plain structs and Eigen, no PCL, no ROS.
//
// Time: absolute stamps are integer nanoseconds (`*_ns`, int64) so that long
// bags keep full resolution; per-point offsets inside a sweep are float seconds.
// Frames: `T_a_b` maps points from frame b into frame a (p_a = T_a_b * p_b).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace mmlio {

using Stamp = std::int64_t;  // nanoseconds since the Unix epoch

inline double toSec(Stamp ns) { return static_cast<double>(ns) * 1e-9; }
inline Stamp fromSec(double s) { return static_cast<Stamp>(s * 1e9 + (s >= 0 ? 0.5 : -0.5)); }

/// One LiDAR return in its sensor frame.
struct Point {
  Eigen::Vector3f xyz = Eigen::Vector3f::Zero();  // m, sensor frame
  float intensity = 0.f;                          // driver units (0..255 typical)
  float time_s = 0.f;                             // offset from the sweep start, s
  std::uint16_t ring = 0;                         // spinning-LiDAR ring or Livox line
  std::uint8_t source = 0;                        // which LiDAR of the rig (estimator's index), once merged
};

/// How a LiDAR scans: decides the feature extractor's neighbourhood and the bad-frame check.
enum class LidarKind { kSpinning, kSolidState };

/// One sweep (spinning) or frame (solid state) of one LiDAR.
struct LidarScan {
  std::string sensor;         // config name, e.g. "velodyne", "livox"
  Stamp start_ns = 0;         // time of the first point (sweep start)
  std::vector<Point> points;  // sorted by time_s, time_s >= 0

  /// Duration covered by the points, s.
  double durationS() const { return points.empty() ? 0.0 : points.back().time_s; }
  Stamp endNs() const { return start_ns + fromSec(durationS()); }
};

/// One IMU measurement in the IMU frame.
struct ImuSample {
  Stamp stamp_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();  // angular velocity, rad/s
  Eigen::Vector3d acc_m_s2 = Eigen::Vector3d::Zero();    // specific force, m/s^2
};

/// IMU biases.
struct ImuBias {
  Eigen::Vector3d acc_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
};

/// State of the IMU (body) frame in the gravity-aligned world frame.
struct NavState {
  Stamp stamp_ns = 0;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // m
  Eigen::Quaterniond q_world_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();  // m/s
  ImuBias bias;

  Eigen::Isometry3d pose() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q_world_body.toRotationMatrix();
    T.translation() = p_world;
    return T;
  }
};

/// A timestamped pose, the unit of trajectories (TUM / KITTI output, evaluation).
struct StampedPose {
  Stamp stamp_ns = 0;
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
};
using Trajectory = std::vector<StampedPose>;

/// Static description of one LiDAR of the rig.
struct LidarExtrinsic {
  std::string name;  // "velodyne", "livox"
  LidarKind kind = LidarKind::kSpinning;
  Eigen::Isometry3d T_imu_sensor = Eigen::Isometry3d::Identity();  // sensor -> IMU frame
  double time_offset_s = 0.0;                                      // t_imu = t_stamp + offset
};

}  // namespace mmlio
