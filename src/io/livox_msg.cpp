#include "mmlio/io/livox_msg.hpp"

namespace mmlio::io {
namespace {

#define MMLIO_LIVOX_POINT_DEF                                         \
  "# Livox costom pointcloud format.\n"                               \
  "\n"                                                                \
  "uint32 offset_time      # offset time relative to the base time\n" \
  "float32 x               # X axis, unit:m\n"                        \
  "float32 y               # Y axis, unit:m\n"                        \
  "float32 z               # Z axis, unit:m\n"                        \
  "uint8 reflectivity      # reflectivity, 0~255\n"                   \
  "uint8 tag               # livox tag\n"                             \
  "uint8 line              # laser number in lidar\n"

#define MMLIO_LIVOX_MSG_DEF(PKG)                                                                \
  "# Livox publish pointcloud msg format.\n"                                                    \
  "\n"                                                                                          \
  "Header header             # ROS standard message header\n"                                   \
  "uint64 timebase           # The time of first point\n"                                       \
  "uint32 point_num          # Total number of pointclouds\n"                                   \
  "uint8  lidar_id           # Lidar device id number\n"                                        \
  "uint8[3]  rsvd            # Reserved use\n"                                                  \
  "CustomPoint[] points      # Pointcloud data\n"                                               \
  "\n"                                                                                          \
  "\n"                                                                                          \
  "================================================================================\n"          \
  "MSG: std_msgs/Header\n"                                                                      \
  "# Standard metadata for higher-level stamped data types.\n"                                  \
  "# This is generally used to communicate timestamped data \n"                                 \
  "# in a particular coordinate frame.\n"                                                       \
  "# \n"                                                                                        \
  "# sequence ID: consecutively increasing ID \n"                                               \
  "uint32 seq\n"                                                                                \
  "#Two-integer timestamp that is expressed as:\n"                                              \
  "# * stamp.sec: seconds (stamp_secs) since epoch (in Python the variable is called 'secs')\n" \
  "# * stamp.nsec: nanoseconds since stamp_secs (in Python the variable is called 'nsecs')\n"   \
  "# time-handling sugar is provided by the client library\n"                                   \
  "time stamp\n"                                                                                \
  "#Frame this data is associated with\n"                                                       \
  "string frame_id\n"                                                                           \
  "\n"                                                                                          \
  "================================================================================\n"          \
  "MSG: " PKG "/CustomPoint\n" MMLIO_LIVOX_POINT_DEF

const char kDriver1[] = MMLIO_LIVOX_MSG_DEF("livox_ros_driver");
const char kDriver2[] = MMLIO_LIVOX_MSG_DEF("livox_ros_driver2");
const char kPoint[] = MMLIO_LIVOX_POINT_DEF;

}  // namespace

const char* livoxCustomMsgDefinition(bool driver2) { return driver2 ? kDriver2 : kDriver1; }
const char* livoxCustomPointDefinition() { return kPoint; }

}  // namespace mmlio::io
