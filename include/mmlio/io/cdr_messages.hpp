#pragma once
// ROS 2 messages (CDR, as rosbag2 stores them and DDS carries them) decoded into the same message structs the ROS 1
// reader fills, so that every decoder and check behind them is shared: by the ROS 2 bag reader and the ROS 2 node.
// Layouts are the ROS 2 IDL ones: builtin_interfaces/Time is int32 sec + uint32 nanosec, and fields are aligned to
// their size counted from the end of the 4-byte encapsulation header.
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <string>
#include <vector>

#include "mmlio/io/livox_msg.hpp"

namespace mmlio::io {

/// What a ROS 2 type name is to the reader.
enum class Ros2Type { kOther, kImu, kPointCloud2, kLivox };
/// "sensor_msgs/msg/Imu", "sensor_msgs/msg/PointCloud2", and the Livox ROS 2 drivers' CustomMsg
/// ("livox_ros_driver2/msg/CustomMsg", "livox_interfaces/msg/CustomMsg" of livox_ros2_driver).
Ros2Type ros2Type(const std::string& type);

/// Each throws (a std::exception, never a crash) when the payload is shorter than its fields or a sequence length
/// exceeds the bytes left.
sensor_msgs::Imu decodeImuCdr(const std::vector<std::uint8_t>& cdr);
sensor_msgs::PointCloud2 decodePointCloud2Cdr(const std::vector<std::uint8_t>& cdr);
LivoxCustomMsg decodeLivoxCdr(const std::vector<std::uint8_t>& cdr);
/// What rviz2's "2D Pose Estimate" publishes on /initialpose.
geometry_msgs::PoseWithCovarianceStamped decodePoseWithCovarianceStampedCdr(const std::vector<std::uint8_t>& cdr);

}  // namespace mmlio::io
