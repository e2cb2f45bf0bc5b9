#include "mmlio/io/cdr_messages.hpp"

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>

#include <stdexcept>

namespace mmlio::io {
namespace {

namespace fc = eprosima::fastcdr;

/// A CDR payload with its encapsulation header read (endianness from the header).
class CdrReader {
 public:
  explicit CdrReader(const std::vector<std::uint8_t>& data)
      : size_(data.size()),
        buffer_(reinterpret_cast<char*>(const_cast<std::uint8_t*>(data.data())), data.size()),
        cdr_(buffer_, fc::Cdr::DEFAULT_ENDIAN, fc::Cdr::DDS_CDR) {
    if (size_ < 4)
      throw std::runtime_error("CDR payload of " + std::to_string(size_) + " bytes has no encapsulation header");
    cdr_.read_encapsulation();
  }

  template <class T> T get() {
    T v{};
    cdr_.deserialize(v);
    return v;
  }
  std::string string() {
    std::string s;
    cdr_.deserialize(s);
    return s;
  }
  template <class T> void array(T* out, std::size_t n) {
    if (n > 0) cdr_.deserializeArray(out, n);
  }
  /// A sequence length, checked against the bytes left (a damaged length must not allocate gigabytes).
  std::uint32_t length(std::size_t min_bytes_each, const char* what) {
    const auto n = get<std::uint32_t>();
    if (static_cast<std::uint64_t>(n) * min_bytes_each > left())
      throw std::runtime_error(std::string(what) + " length " + std::to_string(n) + " exceeds the " +
                               std::to_string(left()) + " bytes left in the CDR payload");
    return n;
  }

  std_msgs::Header header() {
    std_msgs::Header h;
    const auto sec = get<std::int32_t>();
    const auto nanosec = get<std::uint32_t>();
    h.stamp.sec = static_cast<std::uint32_t>(sec);
    h.stamp.nsec = nanosec;
    h.frame_id = string();
    return h;
  }
  void vector3(geometry_msgs::Vector3& v) {
    v.x = get<double>();
    v.y = get<double>();
    v.z = get<double>();
  }

 private:
  std::size_t left() const { return size_ - cdr_.getSerializedDataLength(); }

  std::size_t size_;
  fc::FastBuffer buffer_;
  fc::Cdr cdr_;
};

/// Fast CDR's own exceptions say "Not enough memory in the buffer stream": say what it means here.
template <class F> auto decodeOrExplain(const std::vector<std::uint8_t>& cdr, const char* type, F&& decode) {
  try {
    return decode();
  } catch (const fc::exception::Exception& e) {
    throw std::runtime_error(std::string("CDR payload of ") + std::to_string(cdr.size()) + " bytes is not a valid " +
                             type + " (" + e.what() + ")");
  }
}

}  // namespace

Ros2Type ros2Type(const std::string& type) {
  if (type == "sensor_msgs/msg/Imu") return Ros2Type::kImu;
  if (type == "sensor_msgs/msg/PointCloud2") return Ros2Type::kPointCloud2;
  if (type == "livox_ros_driver2/msg/CustomMsg" || type == "livox_interfaces/msg/CustomMsg" ||
      type == "livox_ros_driver/msg/CustomMsg")
    return Ros2Type::kLivox;
  return Ros2Type::kOther;
}

sensor_msgs::Imu decodeImuCdr(const std::vector<std::uint8_t>& cdr) {
  return decodeOrExplain(cdr, "sensor_msgs/msg/Imu", [&] {
    CdrReader in(cdr);
    sensor_msgs::Imu m;
    m.header = in.header();
    m.orientation.x = in.get<double>();
    m.orientation.y = in.get<double>();
    m.orientation.z = in.get<double>();
    m.orientation.w = in.get<double>();
    in.array(m.orientation_covariance.data(), 9);
    in.vector3(m.angular_velocity);
    in.array(m.angular_velocity_covariance.data(), 9);
    in.vector3(m.linear_acceleration);
    in.array(m.linear_acceleration_covariance.data(), 9);
    return m;
  });
}

sensor_msgs::PointCloud2 decodePointCloud2Cdr(const std::vector<std::uint8_t>& cdr) {
  return decodeOrExplain(cdr, "sensor_msgs/msg/PointCloud2", [&] {
    CdrReader in(cdr);
    sensor_msgs::PointCloud2 m;
    m.header = in.header();
    m.height = in.get<std::uint32_t>();
    m.width = in.get<std::uint32_t>();
    m.fields.resize(in.length(13, "PointCloud2 fields"));  // name length, offset, datatype, count
    for (sensor_msgs::PointField& f : m.fields) {
      f.name = in.string();
      f.offset = in.get<std::uint32_t>();
      f.datatype = in.get<std::uint8_t>();
      f.count = in.get<std::uint32_t>();
    }
    m.is_bigendian = in.get<bool>();
    m.point_step = in.get<std::uint32_t>();
    m.row_step = in.get<std::uint32_t>();
    m.data.resize(in.length(1, "PointCloud2 data"));
    in.array(m.data.data(), m.data.size());
    m.is_dense = in.get<bool>();
    return m;
  });
}

LivoxCustomMsg decodeLivoxCdr(const std::vector<std::uint8_t>& cdr) {
  return decodeOrExplain(cdr, "CustomMsg", [&] {
    CdrReader in(cdr);
    LivoxCustomMsg m;
    m.header = in.header();
    m.timebase = in.get<std::uint64_t>();
    m.point_num = in.get<std::uint32_t>();
    m.lidar_id = in.get<std::uint8_t>();
    in.array(m.rsvd.data(), 3);
    m.points.resize(in.length(19, "CustomMsg points"));  // 4 + 3 x 4 + 3 bytes, plus padding
    for (LivoxCustomPoint& p : m.points) {
      p.offset_time = in.get<std::uint32_t>();
      p.x = in.get<float>();
      p.y = in.get<float>();
      p.z = in.get<float>();
      p.reflectivity = in.get<std::uint8_t>();
      p.tag = in.get<std::uint8_t>();
      p.line = in.get<std::uint8_t>();
    }
    m.driver2 = true;
    return m;
  });
}

geometry_msgs::PoseWithCovarianceStamped decodePoseWithCovarianceStampedCdr(const std::vector<std::uint8_t>& cdr) {
  return decodeOrExplain(cdr, "geometry_msgs/msg/PoseWithCovarianceStamped", [&] {
    CdrReader in(cdr);
    geometry_msgs::PoseWithCovarianceStamped m;
    m.header = in.header();
    geometry_msgs::Pose& p = m.pose.pose;
    p.position.x = in.get<double>();
    p.position.y = in.get<double>();
    p.position.z = in.get<double>();
    p.orientation.x = in.get<double>();
    p.orientation.y = in.get<double>();
    p.orientation.z = in.get<double>();
    p.orientation.w = in.get<double>();
    in.array(m.pose.covariance.data(), 36);
    return m;
  });
}

}  // namespace mmlio::io
