#include "mmlio/io/bag_writer.hpp"

#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "mmlio/core/error.hpp"
#include "mmlio/io/livox_msg.hpp"

namespace mmlio::io {
namespace {

constexpr double kGravity = 9.80665;

ros::Time rosTime(Stamp ns) {
  if (ns < 0) throw Error("bag writer: negative time stamp " + std::to_string(ns) + " ns cannot be stored in a bag");
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(ns));
  return t;
}

std_msgs::Header header(const std::string& frame_id, Stamp ns, std::uint32_t seq) {
  std_msgs::Header h;
  h.seq = seq;
  h.stamp = rosTime(ns);
  h.frame_id = frame_id;
  return h;
}

sensor_msgs::PointField field(const char* name, std::uint32_t offset, std::uint8_t type) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = 1;
  return f;
}

}  // namespace

struct BagWriter::Impl {
  std::string path;
  rosbag::Bag bag;
  bool open = false;
  std::uint32_t seq = 0;

  template <typename M> void write(const std::string& topic, Stamp ns, const M& msg) {
    if (!open) throw Error("bag writer: " + path + " is already closed");
    try {
      bag.write(topic, rosTime(ns), msg);
    } catch (const rosbag::BagException& e) {
      throw Error("bag writer: cannot write topic " + topic + " to " + path + ": " + e.what());
    }
  }
};

BagWriter::BagWriter(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  try {
    impl_->bag.open(path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    throw Error("cannot create bag " + path + ": " + e.what());
  }
  impl_->open = true;
}

BagWriter::~BagWriter() {
  try {
    close();
  } catch (...) {
  }
}

void BagWriter::close() {
  if (!impl_->open) return;
  impl_->open = false;
  try {
    impl_->bag.close();
  } catch (const rosbag::BagException& e) {
    throw Error("cannot finish bag " + impl_->path + ": " + e.what());
  }
}

void BagWriter::writeVelodyneCloud(const std::string& topic, const std::string& frame_id, const LidarScan& scan) {
  sensor_msgs::PointCloud2 msg;
  msg.header = header(frame_id, scan.start_ns, impl_->seq++);
  using PF = sensor_msgs::PointField;
  // velodyne_pointcloud's XYZIRT, byte for byte: a PCL point (x y z and a pad float), intensity,
  // ring and time, padded to 32 bytes. Tests then move the message sizes a real driver sends.
  msg.fields = {field("x", 0, PF::FLOAT32),          field("y", 4, PF::FLOAT32),    field("z", 8, PF::FLOAT32),
                field("intensity", 16, PF::FLOAT32), field("ring", 20, PF::UINT16), field("time", 24, PF::FLOAT32)};
  constexpr std::uint32_t kStep = 32;
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(scan.points.size());
  msg.is_bigendian = false;
  msg.point_step = kStep;
  msg.row_step = kStep * msg.width;
  msg.is_dense = true;
  msg.data.assign(static_cast<std::size_t>(msg.row_step), 0);
  std::uint8_t* out = msg.data.data();
  for (const Point& p : scan.points) {
    std::memcpy(out + 0, p.xyz.data(), 12);
    std::memcpy(out + 16, &p.intensity, 4);
    std::memcpy(out + 20, &p.ring, 2);
    std::memcpy(out + 24, &p.time_s, 4);
    if (!std::isfinite(p.xyz.x()) || !std::isfinite(p.xyz.y()) || !std::isfinite(p.xyz.z())) msg.is_dense = false;
    out += kStep;
  }
  impl_->write(topic, scan.start_ns, msg);
}

void BagWriter::writeLivoxCloud(const std::string& topic, const std::string& frame_id, const LidarScan& scan,
                                bool driver2) {
  LivoxCustomMsg msg;
  msg.driver2 = driver2;
  msg.header = header(frame_id, scan.start_ns, impl_->seq++);
  msg.timebase = static_cast<std::uint64_t>(scan.start_ns);
  msg.point_num = static_cast<std::uint32_t>(scan.points.size());
  msg.points.resize(scan.points.size());
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    const Point& p = scan.points[i];
    LivoxCustomPoint& q = msg.points[i];
    const double offset_ns = std::max(0.0, std::round(static_cast<double>(p.time_s) * 1e9));
    q.offset_time = static_cast<std::uint32_t>(offset_ns);
    q.x = p.xyz.x();
    q.y = p.xyz.y();
    q.z = p.xyz.z();
    q.reflectivity = static_cast<std::uint8_t>(std::clamp(std::lround(p.intensity), 0L, 255L));
    q.tag = 0x10;
    q.line = static_cast<std::uint8_t>(std::min<int>(p.ring, 255));
  }
  impl_->write(topic, scan.start_ns, msg);
}

void BagWriter::writeImu(const std::string& topic, const std::string& frame_id, const ImuSample& sample,
                         bool acc_in_g) {
  sensor_msgs::Imu msg;
  msg.header = header(frame_id, sample.stamp_ns, impl_->seq++);
  msg.orientation.w = 1.0;
  msg.orientation_covariance[0] = -1.0;
  msg.angular_velocity.x = sample.gyro_rad_s.x();
  msg.angular_velocity.y = sample.gyro_rad_s.y();
  msg.angular_velocity.z = sample.gyro_rad_s.z();
  const double scale = acc_in_g ? 1.0 / kGravity : 1.0;
  msg.linear_acceleration.x = sample.acc_m_s2.x() * scale;
  msg.linear_acceleration.y = sample.acc_m_s2.y() * scale;
  msg.linear_acceleration.z = sample.acc_m_s2.z() * scale;
  impl_->write(topic, sample.stamp_ns, msg);
}

}  // namespace mmlio::io
