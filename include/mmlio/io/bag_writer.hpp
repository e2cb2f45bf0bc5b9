#pragma once
// Writes ROS1 bags with the message layouts real drivers publish, so that simulated sequences
// and tests go through exactly the decoding path of recorded data. No ROS types in this header.

#include <memory>
#include <string>

#include "mmlio/core/types.hpp"

namespace mmlio::io {

class BagWriter {
 public:
  /// Creates (overwrites) `path`. Throws mmlio::Error naming the file when it cannot be opened.
  explicit BagWriter(const std::string& path);
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  /// sensor_msgs/PointCloud2 in the velodyne_pointcloud layout: x y z intensity (float32),
  /// ring (uint16), time (float32 s relative to header.stamp); header.stamp = bag time = scan.start_ns.
  void writeVelodyneCloud(const std::string& topic, const std::string& frame_id, const LidarScan& scan);
  /// livox_ros_driver/CustomMsg (driver2: livox_ros_driver2/CustomMsg): timebase = header.stamp =
  /// bag time = scan.start_ns, offset_time = time_s in ns, line = ring, reflectivity = intensity, tag 0x10.
  void writeLivoxCloud(const std::string& topic, const std::string& frame_id, const LidarScan& scan,
                       bool driver2 = false);
  /// sensor_msgs/Imu at sample.stamp_ns; linear_acceleration divided by 9.80665 when acc_in_g
  /// (what the Livox built-in IMU publishes). Orientation covariance[0] = -1 (no orientation).
  void writeImu(const std::string& topic, const std::string& frame_id, const ImuSample& sample, bool acc_in_g);
  /// Writes the index and closes the file; idempotent (the destructor calls it).
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mmlio::io
