#pragma once
// ROS 2 on the DDS wire, without a ROS 2 installation: the names ROS 2 gives topics, services and
// message types in DDS, and the messages the live node publishes as ROS 2 serialises them (CDR,
// little endian, with the 4-byte encapsulation header, as rosbag2 stores them).
//
// Conventions followed (ROS 2 Humble and Jazzy, rmw_fastrtps_cpp and rmw_cyclonedds_cpp): the
// design article "Topic and Service name mapping to DDS" (topics "rt" + the fully qualified name,
// service requests "rq" + name + "Request", replies "rr" + name + "Reply") and the type names of
// rosidl_typesupport_fastrtps / rosidl_typesupport_introspection ("pkg::msg::dds_::Type_").
//
// The messages come in as the ROS 1 structs the ROS 1 node fills (live/ros_messages.hpp makes them
// from the estimator's state): the two distributions share every field the node publishes but the
// header, whose ROS 2 form has no seq and an int32 sec.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mmlio::ros2 {

using Cdr = std::vector<std::uint8_t>;

/// "/odom" or "odom" (relative to the root namespace) -> "rt/odom". Throws mmlio::Error on a name
/// ROS 2 would reject (empty, "//", characters other than [A-Za-z0-9_/~], a digit after a '/').
std::string topicOnWire(const std::string& ros_topic);
/// The request and reply topics of service "/node/save_map": "rq/node/save_mapRequest", "rr/node/save_mapReply".
std::string requestTopicOnWire(const std::string& ros_service);
std::string replyTopicOnWire(const std::string& ros_service);
/// "nav_msgs/msg/Odometry" -> "nav_msgs::msg::dds_::Odometry_"; "std_srvs/srv/Trigger_Request" ->
/// "std_srvs::srv::dds_::Trigger_Request_". Throws mmlio::Error unless it reads pkg/{msg,srv}/Type.
std::string typeOnWire(const std::string& ros_type);

Cdr encode(const nav_msgs::Odometry& msg);
Cdr encode(const nav_msgs::Path& msg);
Cdr encode(const sensor_msgs::PointCloud2& msg);
Cdr encode(const tf2_msgs::TFMessage& msg);
Cdr encode(const diagnostic_msgs::DiagnosticArray& msg);
/// std_srvs/srv/Trigger's reply.
Cdr encodeTriggerReply(bool success, const std::string& message);

}  // namespace mmlio::ros2
