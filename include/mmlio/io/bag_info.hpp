#pragma once
// What is in a ROS 1 or ROS 2 bag, for `mmlio info` and for choosing topics in a rig config. No ROS types.

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "mmlio/core/types.hpp"

namespace mmlio::io {

struct TopicInfo {
  std::string topic, type;
  std::size_t messages = 0;
  double rate_hz = 0;               // (messages - 1) / time span of the topic; 0 for < 2 messages
  std::vector<std::string> fields;  // point clouds: "name(datatype)" per field, e.g. "ring(uint16)"
  double mean_points = 0;           // point clouds: mean points per message over the first 50 messages
  std::string frame_id;             // clouds and IMU: the first message's header.frame_id, no leading '/' (ROS 1 bags)
};

/// One transform of /tf_static: poses of `child` frames in `parent` frames.
struct StaticTransform {
  std::string parent, child;  // without a leading '/'
  Eigen::Isometry3d T_parent_child = Eigen::Isometry3d::Identity();
};

struct BagInfo {
  std::string path;
  std::string format;              // "ROS 1 bag", "ROS 2 mcap (12 zstd chunks)", "ROS 2 sqlite3 (1 file)"
  Stamp begin_ns = 0, end_ns = 0;  // bag time of the first and last message
  std::vector<TopicInfo> topics;   // sorted by topic name
  std::string imu_unit_guess;      // first sensor_msgs/Imu topic: "g", "m/s2"; "" without IMU
  std::vector<StaticTransform> static_transforms;  // /tf_static (ROS 1 bags)
};

/// Reads the index (ROS 2: the database or a scan of the MCAP file) and a few messages per cloud /
/// IMU topic. Throws mmlio::Error like BagSource.
BagInfo describeBag(const std::string& path);
/// Human-readable multi-line summary.
std::string formatBagInfo(const BagInfo& info);

}  // namespace mmlio::io
