#pragma once
// livox_ros_driver/CustomMsg for building FAST-LIO2 as a speed reference (bench/fastlio) without the
// Livox driver: mmlio's own message (include/mmlio/io/livox_msg.hpp) under the driver's names, with
// its ROS traits and serialiser.
#include <boost/shared_ptr.hpp>

#include "mmlio/io/livox_msg.hpp"

namespace livox_ros_driver {
using CustomPoint = mmlio::io::LivoxCustomPoint;
struct CustomMsg : mmlio::io::LivoxCustomMsg {
  typedef boost::shared_ptr<CustomMsg> Ptr;
  typedef boost::shared_ptr<CustomMsg const> ConstPtr;
};
}  // namespace livox_ros_driver

namespace ros {
namespace message_traits {
template <> struct IsMessage<livox_ros_driver::CustomMsg> : TrueType {};
template <> struct IsMessage<const livox_ros_driver::CustomMsg> : TrueType {};
template <> struct HasHeader<livox_ros_driver::CustomMsg> : TrueType {};
template <> struct HasHeader<const livox_ros_driver::CustomMsg> : TrueType {};
template <> struct MD5Sum<livox_ros_driver::CustomMsg> : MD5Sum<mmlio::io::LivoxCustomMsg> {};
template <> struct DataType<livox_ros_driver::CustomMsg> : DataType<mmlio::io::LivoxCustomMsg> {};
template <> struct Definition<livox_ros_driver::CustomMsg> {  // not needed by a subscriber
  static const char* value() { return ""; }
  static const char* value(const livox_ros_driver::CustomMsg&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <> struct Serializer<livox_ros_driver::CustomMsg> : Serializer<mmlio::io::LivoxCustomMsg> {};
}  // namespace serialization
}  // namespace ros
