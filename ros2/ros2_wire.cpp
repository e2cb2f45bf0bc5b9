#include "ros2_wire.hpp"

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>

#include <cctype>
#include <type_traits>

#include "mmlio/core/error.hpp"

namespace mmlio::ros2 {
namespace {

namespace fc = eprosima::fastcdr;

/// Fields in ROS 2's order and alignment (each to its own size, counted after the encapsulation
/// header), little endian, as rmw serialises them. Fast CDR skips alignment bytes without writing
/// them, and its buffer grows uninitialised: the padding is written here, as zeros, so the bytes on
/// the wire are the message's alone (the same message, the same bytes).
class CdrWriter {
 public:
  CdrWriter() : cdr_(buffer_, fc::Cdr::LITTLE_ENDIANNESS, fc::Cdr::DDS_CDR) { cdr_.serialize_encapsulation(); }

  template <class T> CdrWriter& operator<<(const T& v) {
    if constexpr (std::is_arithmetic_v<T>)
      align(sizeof(T));
    else
      align(4);  // a string starts with its uint32 length
    cdr_.serialize(v);
    return *this;
  }
  void bytes(const std::vector<std::uint8_t>& v) {
    *this << static_cast<std::uint32_t>(v.size());
    if (!v.empty()) cdr_.serializeArray(v.data(), v.size());
  }
  void header(const std_msgs::Header& h) {
    // builtin_interfaces/Time: int32 sec, uint32 nanosec (ROS 1: uint32 sec); no seq.
    *this << static_cast<std::int32_t>(h.stamp.sec) << static_cast<std::uint32_t>(h.stamp.nsec) << h.frame_id;
  }
  void vector3(double x, double y, double z) { *this << x << y << z; }
  void pose(const geometry_msgs::Pose& p) {
    vector3(p.position.x, p.position.y, p.position.z);
    quaternion(p.orientation);
  }
  void quaternion(const geometry_msgs::Quaternion& q) { *this << q.x << q.y << q.z << q.w; }
  template <std::size_t N> void array(const boost::array<double, N>& a) {
    align(sizeof(double));
    cdr_.serializeArray(a.data(), N);
  }

  Cdr take() const {
    const auto* begin = reinterpret_cast<const std::uint8_t*>(buffer_.getBuffer());
    return Cdr(begin, begin + cdr_.getSerializedDataLength());
  }

 private:
  void align(std::size_t n) {
    while ((cdr_.getSerializedDataLength() - 4) % n != 0) cdr_.serialize(std::uint8_t{0});
  }

  fc::FastBuffer buffer_;  // grows as needed
  fc::Cdr cdr_;
};

bool validName(const std::string& name) {
  if (name.empty() || name == "/") return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (c == '/') {
      if (i + 1 < name.size() && (name[i + 1] == '/' || std::isdigit(static_cast<unsigned char>(name[i + 1]))))
        return false;
      continue;
    }
    if (!std::isalnum(c) && c != '_') return false;
  }
  if (std::isdigit(static_cast<unsigned char>(name[0]))) return false;
  return name.back() != '/';
}

/// The fully qualified name (in the root namespace) without its leading '/'.
std::string qualified(const std::string& name, const char* what) {
  if (!validName(name)) throw Error(std::string("'") + name + "' is not a valid ROS 2 " + what + " name");
  return name[0] == '/' ? name.substr(1) : name;
}

}  // namespace

std::string topicOnWire(const std::string& ros_topic) { return "rt/" + qualified(ros_topic, "topic"); }
std::string requestTopicOnWire(const std::string& ros_service) {
  return "rq/" + qualified(ros_service, "service") + "Request";
}
std::string replyTopicOnWire(const std::string& ros_service) {
  return "rr/" + qualified(ros_service, "service") + "Reply";
}

std::string typeOnWire(const std::string& ros_type) {
  const std::size_t a = ros_type.find('/');
  const std::size_t b = a == std::string::npos ? a : ros_type.find('/', a + 1);
  const std::string kind = b == std::string::npos ? "" : ros_type.substr(a + 1, b - a - 1);
  if (a == 0 || b == std::string::npos || b + 1 >= ros_type.size() || (kind != "msg" && kind != "srv") ||
      ros_type.find('/', b + 1) != std::string::npos)
    throw Error("'" + ros_type + "' is not a ROS 2 type name (package/msg/Type or package/srv/Type)");
  return ros_type.substr(0, a) + "::" + kind + "::dds_::" + ros_type.substr(b + 1) + "_";
}

Cdr encode(const nav_msgs::Odometry& msg) {
  CdrWriter w;
  w.header(msg.header);
  w << msg.child_frame_id;
  w.pose(msg.pose.pose);
  w.array(msg.pose.covariance);
  const auto& t = msg.twist.twist;
  w.vector3(t.linear.x, t.linear.y, t.linear.z);
  w.vector3(t.angular.x, t.angular.y, t.angular.z);
  w.array(msg.twist.covariance);
  return w.take();
}

Cdr encode(const nav_msgs::Path& msg) {
  CdrWriter w;
  w.header(msg.header);
  w << static_cast<std::uint32_t>(msg.poses.size());
  for (const auto& p : msg.poses) {
    w.header(p.header);
    w.pose(p.pose);
  }
  return w.take();
}

Cdr encode(const sensor_msgs::PointCloud2& msg) {
  CdrWriter w;
  w.header(msg.header);
  w << msg.height << msg.width << static_cast<std::uint32_t>(msg.fields.size());
  for (const auto& f : msg.fields) w << f.name << f.offset << f.datatype << f.count;
  w << static_cast<bool>(msg.is_bigendian) << msg.point_step << msg.row_step;
  w.bytes(msg.data);
  w << static_cast<bool>(msg.is_dense);
  return w.take();
}

Cdr encode(const tf2_msgs::TFMessage& msg) {
  CdrWriter w;
  w << static_cast<std::uint32_t>(msg.transforms.size());
  for (const auto& t : msg.transforms) {
    w.header(t.header);
    w << t.child_frame_id;
    const auto& tr = t.transform;
    w.vector3(tr.translation.x, tr.translation.y, tr.translation.z);
    w.quaternion(tr.rotation);
  }
  return w.take();
}

Cdr encode(const diagnostic_msgs::DiagnosticArray& msg) {
  CdrWriter w;
  w.header(msg.header);
  w << static_cast<std::uint32_t>(msg.status.size());
  for (const auto& d : msg.status) {
    w << static_cast<std::uint8_t>(d.level) << d.name << d.message << d.hardware_id
      << static_cast<std::uint32_t>(d.values.size());
    for (const auto& kv : d.values) w << kv.key << kv.value;
  }
  return w.take();
}

Cdr encodeTriggerReply(bool success, const std::string& message) {
  CdrWriter w;
  w << success << message;
  return w.take();
}

}  // namespace mmlio::ros2
