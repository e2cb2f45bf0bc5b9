#pragma once
// livox_ros_driver/CustomMsg for building FAST-LIO2 as a speed reference (bench/fastlio), without
// the Livox driver: the layout and traits of include/mmlio/io/livox_msg.hpp under the driver's names.
#include <boost/array.hpp>
#include <boost/shared_ptr.hpp>
#include <cstdint>
#include <ros/builtin_message_traits.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <std_msgs/Header.h>
#include <vector>
namespace livox_ros_driver {
struct CustomPoint { std::uint32_t offset_time = 0; float x = 0, y = 0, z = 0; std::uint8_t reflectivity = 0, tag = 0, line = 0; };
struct CustomMsg {
  std_msgs::Header header; std::uint64_t timebase = 0; std::uint32_t point_num = 0; std::uint8_t lidar_id = 0;
  boost::array<std::uint8_t, 3> rsvd{{0, 0, 0}}; std::vector<CustomPoint> points;
  typedef boost::shared_ptr<CustomMsg> Ptr; typedef boost::shared_ptr<CustomMsg const> ConstPtr;
};
}
namespace ros {
namespace message_traits {

template <> struct IsMessage<livox_ros_driver::CustomMsg> : TrueType {};
template <> struct IsMessage<const livox_ros_driver::CustomMsg> : TrueType {};
template <> struct HasHeader<livox_ros_driver::CustomMsg> : TrueType {};
template <> struct HasHeader<const livox_ros_driver::CustomMsg> : TrueType {};

template <> struct MD5Sum<livox_ros_driver::CustomMsg> {
  static const char* value() { return "e4d6829bdfe657cb6c21a746c86b21a6"; }
  static const char* value(const livox_ros_driver::CustomMsg&) { return value(); }
};
template <> struct DataType<livox_ros_driver::CustomMsg> {
  static const char* value() { return "livox_ros_driver/CustomMsg"; }
  static const char* value(const livox_ros_driver::CustomMsg& m) {
    return "livox_ros_driver/CustomMsg";
  }
};
template <> struct Definition<livox_ros_driver::CustomMsg> {
  static const char* value() { return ""; }
  static const char* value(const livox_ros_driver::CustomMsg& m) {
    return "";
  }
};

template <> struct IsMessage<livox_ros_driver::CustomPoint> : TrueType {};
template <> struct IsMessage<const livox_ros_driver::CustomPoint> : TrueType {};
template <> struct IsFixedSize<livox_ros_driver::CustomPoint> : TrueType {};
template <> struct IsFixedSize<const livox_ros_driver::CustomPoint> : TrueType {};
template <> struct MD5Sum<livox_ros_driver::CustomPoint> {
  static const char* value() { return "109a3cc548bb1f96626be89a5008bd6d"; }
  static const char* value(const livox_ros_driver::CustomPoint&) { return value(); }
};
template <> struct DataType<livox_ros_driver::CustomPoint> {
  static const char* value() { return "livox_ros_driver/CustomPoint"; }
  static const char* value(const livox_ros_driver::CustomPoint&) { return value(); }
};
template <> struct Definition<livox_ros_driver::CustomPoint> {
  static const char* value() { return ""; }
  static const char* value(const livox_ros_driver::CustomPoint&) { return value(); }
};

}  // namespace message_traits

namespace serialization {

template <> struct Serializer<livox_ros_driver::CustomPoint> {
  template <typename Stream, typename T> inline static void allInOne(Stream& stream, T m) {
    stream.next(m.offset_time);
    stream.next(m.x);
    stream.next(m.y);
    stream.next(m.z);
    stream.next(m.reflectivity);
    stream.next(m.tag);
    stream.next(m.line);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

template <> struct Serializer<livox_ros_driver::CustomMsg> {
  template <typename Stream, typename T> inline static void allInOne(Stream& stream, T m) {
    stream.next(m.header);
    stream.next(m.timebase);
    stream.next(m.point_num);
    stream.next(m.lidar_id);
    stream.next(m.rsvd);
    stream.next(m.points);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

}  // namespace serialization
}  // namespace ros
