#pragma once
// Which sensor a bag's message type carries, as ROS 1 or ROS 2 spells it: the bag reader accepts
// exactly these, and `mmlio init` guesses a rig from them.
#include <string>

#include "mmlio/io/livox_msg.hpp"
#include "mmlio/io/cdr_messages.hpp"

namespace mmlio::io::detail {

inline constexpr const char* kPointCloud2Type = "sensor_msgs/PointCloud2";
inline constexpr const char* kImuType = "sensor_msgs/Imu";

inline bool isImuType(const std::string& t) { return t == kImuType || ros2Type(t) == Ros2Type::kImu; }
inline bool isCloudType(const std::string& t) { return t == kPointCloud2Type || ros2Type(t) == Ros2Type::kPointCloud2; }
inline bool isLivoxType(const std::string& t) {
  return t == kLivoxCustomMsgType || t == kLivox2CustomMsgType || ros2Type(t) == Ros2Type::kLivox;
}

}  // namespace mmlio::io::detail
