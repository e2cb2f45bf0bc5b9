#pragma once
// livox_ros_driver/CustomMsg (and livox_ros_driver2/CustomMsg, same layout and MD5) without the
// Livox driver: a plain struct plus the ros::message_traits / ros::serialization specialisations
// rosbag needs to read and write it. ROS headers are allowed here (io/ edge only).
//
// The two drivers differ only in the package name of the type. `driver2` (not serialised)
// selects which one the instance-based traits report, so a bag written with driver2 = true
// carries "livox_ros_driver2/CustomMsg"; reading sets it from the connection's datatype.

#include <boost/array.hpp>
#include <cstdint>
#include <ros/builtin_message_traits.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <std_msgs/Header.h>
#include <vector>

namespace mmlio::io {

/// One Livox return.
struct LivoxCustomPoint {
  std::uint32_t offset_time = 0;    // ns after CustomMsg::timebase
  float x = 0.f, y = 0.f, z = 0.f;  // m, sensor frame
  std::uint8_t reflectivity = 0;    // 0..255
  std::uint8_t tag = 0;             // Livox return tag (0x10: single return, normal)
  std::uint8_t line = 0;            // laser line (Horizon: 0..5)
};

/// One Livox frame.
struct LivoxCustomMsg {
  std_msgs::Header header;
  std::uint64_t timebase = 0;  // ns, time of the first point
  std::uint32_t point_num = 0;
  std::uint8_t lidar_id = 0;
  boost::array<std::uint8_t, 3> rsvd{{0, 0, 0}};
  std::vector<LivoxCustomPoint> points;

  bool driver2 = false;  // not serialised: livox_ros_driver2/CustomMsg instead of livox_ros_driver/
};

inline constexpr const char* kLivoxCustomMsgType = "livox_ros_driver/CustomMsg";
inline constexpr const char* kLivox2CustomMsgType = "livox_ros_driver2/CustomMsg";
inline constexpr const char* kLivoxCustomMsgMd5 = "e4d6829bdfe657cb6c21a746c86b21a6";
inline constexpr const char* kLivoxCustomPointMd5 = "109a3cc548bb1f96626be89a5008bd6d";

/// Full message definition as written into a bag's connection record (gencpp format).
const char* livoxCustomMsgDefinition(bool driver2);
const char* livoxCustomPointDefinition();

}  // namespace mmlio::io

namespace ros {
namespace message_traits {

template <> struct IsMessage<mmlio::io::LivoxCustomMsg> : TrueType {};
template <> struct IsMessage<const mmlio::io::LivoxCustomMsg> : TrueType {};
template <> struct HasHeader<mmlio::io::LivoxCustomMsg> : TrueType {};
template <> struct HasHeader<const mmlio::io::LivoxCustomMsg> : TrueType {};

template <> struct MD5Sum<mmlio::io::LivoxCustomMsg> {
  static const char* value() { return mmlio::io::kLivoxCustomMsgMd5; }
  static const char* value(const mmlio::io::LivoxCustomMsg&) { return value(); }
};
template <> struct DataType<mmlio::io::LivoxCustomMsg> {
  static const char* value() { return mmlio::io::kLivoxCustomMsgType; }
  static const char* value(const mmlio::io::LivoxCustomMsg& m) {
    return m.driver2 ? mmlio::io::kLivox2CustomMsgType : mmlio::io::kLivoxCustomMsgType;
  }
};
template <> struct Definition<mmlio::io::LivoxCustomMsg> {
  static const char* value() { return mmlio::io::livoxCustomMsgDefinition(false); }
  static const char* value(const mmlio::io::LivoxCustomMsg& m) {
    return mmlio::io::livoxCustomMsgDefinition(m.driver2);
  }
};

template <> struct IsMessage<mmlio::io::LivoxCustomPoint> : TrueType {};
template <> struct IsMessage<const mmlio::io::LivoxCustomPoint> : TrueType {};
template <> struct IsFixedSize<mmlio::io::LivoxCustomPoint> : TrueType {};
template <> struct IsFixedSize<const mmlio::io::LivoxCustomPoint> : TrueType {};
template <> struct MD5Sum<mmlio::io::LivoxCustomPoint> {
  static const char* value() { return mmlio::io::kLivoxCustomPointMd5; }
  static const char* value(const mmlio::io::LivoxCustomPoint&) { return value(); }
};
template <> struct DataType<mmlio::io::LivoxCustomPoint> {
  static const char* value() { return "livox_ros_driver/CustomPoint"; }
  static const char* value(const mmlio::io::LivoxCustomPoint&) { return value(); }
};
template <> struct Definition<mmlio::io::LivoxCustomPoint> {
  static const char* value() { return mmlio::io::livoxCustomPointDefinition(); }
  static const char* value(const mmlio::io::LivoxCustomPoint&) { return value(); }
};

}  // namespace message_traits

namespace serialization {

template <> struct Serializer<mmlio::io::LivoxCustomPoint> {
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

template <> struct Serializer<mmlio::io::LivoxCustomMsg> {
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
