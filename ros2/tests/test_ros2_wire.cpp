#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "mmlio/io/cdr_messages.hpp"
#include "ros_messages.hpp"
#include "mmlio/core/error.hpp"
#include "ros2_wire.hpp"

namespace mmlio::ros2 {
namespace {

double doubleAt(const Cdr& cdr, std::size_t offset) {
  double v = 0;
  std::memcpy(&v, cdr.data() + offset, sizeof v);
  return v;
}

std::uint32_t u32At(const Cdr& cdr, std::size_t offset) {
  std::uint32_t v = 0;
  std::memcpy(&v, cdr.data() + offset, sizeof v);
  return v;
}

}  // namespace

TEST(Ros2Wire, TopicServiceAndTypeNamesAsRos2PutsThemOnDds) {
  EXPECT_EQ(topicOnWire("/odom"), "rt/odom");
  EXPECT_EQ(topicOnWire("mmlio/odometry"), "rt/mmlio/odometry");  // relative to the root namespace
  EXPECT_EQ(requestTopicOnWire("/mmlio/save_map"), "rq/mmlio/save_mapRequest");
  EXPECT_EQ(replyTopicOnWire("/mmlio/save_map"), "rr/mmlio/save_mapReply");
  EXPECT_EQ(typeOnWire("nav_msgs/msg/Odometry"), "nav_msgs::msg::dds_::Odometry_");
  EXPECT_EQ(typeOnWire("tf2_msgs/msg/TFMessage"), "tf2_msgs::msg::dds_::TFMessage_");
  EXPECT_EQ(typeOnWire("std_srvs/srv/Trigger_Request"), "std_srvs::srv::dds_::Trigger_Request_");
  for (const char* bad : {"", "/", "/a//b", "/1a", "a b", "/a/", "odom-1"})
    EXPECT_THROW(topicOnWire(bad), Error) << bad;
  for (const char* bad : {"Odometry", "nav_msgs/Odometry", "nav_msgs/idl/Odometry", "/msg/Odometry", "a/msg/b/c"})
    EXPECT_THROW(typeOnWire(bad), Error) << bad;
}

TEST(Ros2Wire, OdometryFieldsSitWhereRos2sLayoutPutsThem) {
  nav_msgs::Odometry odom;
  odom.header.stamp.sec = 1700000000;
  odom.header.stamp.nsec = 123456789;
  odom.header.frame_id = "odom";      // 4 + 5 bytes (length, characters and the terminating 0)
  odom.child_frame_id = "base_link";  // aligned to 4, then 4 + 10 bytes
  odom.pose.pose.position.x = 1.5;
  odom.pose.pose.position.z = -2.25;
  odom.pose.pose.orientation.w = 0.5;
  odom.pose.covariance[0] = 0.01;
  odom.twist.twist.angular.z = 0.3;
  odom.twist.covariance[35] = -1.0;
  const Cdr cdr = encode(odom);
  // Encapsulation CDR_LE, then the body (offsets below count from its start, after 4 bytes).
  ASSERT_GE(cdr.size(), 4u);
  EXPECT_EQ(cdr[0], 0x00);
  EXPECT_EQ(cdr[1], 0x01);
  EXPECT_EQ(u32At(cdr, 4), 1700000000u);
  EXPECT_EQ(u32At(cdr, 8), 123456789u);
  EXPECT_EQ(u32At(cdr, 12), 5u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(cdr.data() + 16)), "odom");
  EXPECT_EQ(u32At(cdr, 4 + 20), 10u);  // child_frame_id at body offset 20 (21 aligned to 4)
  // Position at body offset 40 (34 aligned to 8), orientation after it, then 36 covariances.
  EXPECT_DOUBLE_EQ(doubleAt(cdr, 4 + 40), 1.5);
  EXPECT_DOUBLE_EQ(doubleAt(cdr, 4 + 56), -2.25);
  EXPECT_DOUBLE_EQ(doubleAt(cdr, 4 + 88), 0.5);
  EXPECT_DOUBLE_EQ(doubleAt(cdr, 4 + 96), 0.01);
  const std::size_t twist = 4 + 96 + 36 * 8;
  EXPECT_DOUBLE_EQ(doubleAt(cdr, twist + 40), 0.3);
  EXPECT_DOUBLE_EQ(doubleAt(cdr, twist + 48 + 35 * 8), -1.0);
  EXPECT_EQ(cdr.size(), twist + 48 + 36 * 8);
}

TEST(Ros2Wire, PaddingIsZeroSoTheSameMessageGivesTheSameBytes) {
  nav_msgs::Odometry odom;
  odom.header.frame_id = "odom";      // padding at body offsets 17-19 ...
  odom.child_frame_id = "base_link";  // ... and 34-39
  for (int round = 0; round < 50; ++round) {
    // Freed memory full of 0x55 for the encoder's buffer to be given.
    for (std::size_t size = 64; size <= 4096; size *= 2) {
      std::vector<char> dirty(size, 0x55);
      dirty.clear();
      dirty.shrink_to_fit();
    }
    const Cdr cdr = encode(odom);
    for (const std::size_t at : {17, 18, 19, 34, 35, 36, 37, 38, 39})
      ASSERT_EQ(cdr[4 + at], 0) << "padding byte at body offset " << at << ", round " << round;
  }
}

TEST(Ros2Wire, APointCloudReadsBackThroughTheRos2BagDecoder) {
  // As the node publishes a registered sweep: x y z intensity, float32.
  std::vector<Point> points(3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i].xyz = Eigen::Vector3f(1.5f * static_cast<float>(i), -2.f, 0.25f);
    points[i].intensity = 10.f * static_cast<float>(i);
  }
  const sensor_msgs::PointCloud2 cloud =
      live::toPointCloud2(points, Eigen::Isometry3d::Identity(), 42'000'000'007, "map");
  const sensor_msgs::PointCloud2 back = io::decodePointCloud2Cdr(encode(cloud));
  EXPECT_EQ(back.header.stamp.sec, 42u);
  EXPECT_EQ(back.header.stamp.nsec, 7u);
  EXPECT_EQ(back.header.frame_id, "map");
  ASSERT_EQ(back.fields.size(), 4u);
  EXPECT_EQ(back.fields[3].name, "intensity");
  EXPECT_EQ(back.fields[3].offset, 12u);
  EXPECT_EQ(back.fields[3].datatype, sensor_msgs::PointField::FLOAT32);
  EXPECT_EQ(back.width, 3u);
  EXPECT_EQ(back.point_step, 16u);
  EXPECT_EQ(back.row_step, 48u);
  EXPECT_EQ(back.data, cloud.data);
  EXPECT_TRUE(back.is_dense);
}

TEST(Ros2Wire, TransformsAndTriggerRepliesHaveTheirRos2Size) {
  tf2_msgs::TFMessage tf;
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "map";        // body: sequence length 4, time 8, frame 4 + 4 -> 20
  t.child_frame_id = "odom";        // 4 + 5 -> 29, aligned to 8: 32
  t.transform.translation.y = 2.0;  // translation at 32, rotation at 56, end at 88
  t.transform.rotation.w = 1.0;
  tf.transforms.push_back(t);
  const Cdr cdr = encode(tf);
  EXPECT_EQ(u32At(cdr, 4), 1u);
  EXPECT_DOUBLE_EQ(doubleAt(cdr, 4 + 40), 2.0);
  EXPECT_DOUBLE_EQ(doubleAt(cdr, 4 + 80), 1.0);
  EXPECT_EQ(cdr.size(), 4u + 88u);
  const Cdr reply = encodeTriggerReply(true, "saved");  // bool, then the string aligned to 4
  ASSERT_EQ(reply.size(), 4u + 4u + 4u + 6u);
  EXPECT_EQ(reply[4], 1);
  EXPECT_EQ(u32At(reply, 8), 6u);
}

TEST(Ros2Wire, DiagnosticsAndAPoseHintHaveRos2sLayout) {
  diagnostic_msgs::DiagnosticArray diag;  // body: time 8, frame "" 4 + 1 -> 13, aligned to 4: 16
  diagnostic_msgs::DiagnosticStatus d;
  d.level = diagnostic_msgs::DiagnosticStatus::ERROR;  // status count at 16, level (octet) at 20
  d.name = "mmlio";                                    // aligned to 4: length at 24, "mmlio\0" to 34
  d.values.resize(1);
  d.values[0].key = "k";
  d.values[0].value = "v";
  diag.status.push_back(d);
  const Cdr cdr = encode(diag);
  EXPECT_EQ(u32At(cdr, 4 + 16), 1u);
  EXPECT_EQ(cdr[4 + 20], diagnostic_msgs::DiagnosticStatus::ERROR);
  EXPECT_EQ(u32At(cdr, 4 + 24), 6u);
  // message "" at 36 (4 + 1 -> 41), hardware_id "" at 44 (-> 49), values count at 52, key at 56
  // (4 + 2 -> 62), value at 64 (4 + 2 -> 70).
  EXPECT_EQ(u32At(cdr, 4 + 52), 1u);
  EXPECT_EQ(cdr.size(), 4u + 70u);

  // geometry_msgs/msg/PoseWithCovarianceStamped as rviz2 sends it: header (time 8, "map" 4 + 4 ->
  // 16), position at 16, orientation at 40, covariance (36 doubles) at 72, end at 360.
  Cdr hint(4 + 360, 0);
  hint[1] = 1;  // CDR little endian
  const std::uint32_t frame_length = 4;
  std::memcpy(hint.data() + 4 + 8, &frame_length, 4);
  std::memcpy(hint.data() + 4 + 12, "map", 4);
  const double pose[7] = {1.5, -2.0, 0.0, 0.0, 0.0, 0.7071067811865476, 0.7071067811865476};
  std::memcpy(hint.data() + 4 + 16, pose, sizeof pose);
  const double variance = 0.25;
  std::memcpy(hint.data() + 4 + 72, &variance, 8);
  const geometry_msgs::PoseWithCovarianceStamped m = io::decodePoseWithCovarianceStampedCdr(hint);
  EXPECT_EQ(m.header.frame_id, "map");
  EXPECT_DOUBLE_EQ(m.pose.pose.position.x, 1.5);
  EXPECT_DOUBLE_EQ(m.pose.pose.position.y, -2.0);
  EXPECT_DOUBLE_EQ(m.pose.pose.orientation.w, pose[6]);
  EXPECT_DOUBLE_EQ(m.pose.covariance[0], 0.25);
  hint.resize(100);
  EXPECT_THROW(io::decodePoseWithCovarianceStampedCdr(hint), std::exception);
}

}  // namespace mmlio::ros2
