#include <gtest/gtest.h>
#include <unistd.h>

#include <condition_variable>
#include <mutex>
#include <vector>

#include "dds_transport.hpp"
#include "wait_for.hpp"
#include "mmlio/core/error.hpp"

namespace mmlio::ros2 {
namespace {

// A domain of its own per test process, so that parallel runs and other DDS users do not meet.
int testDomain() { return 100 + static_cast<int>(getpid() % 100); }

Cdr odometryNumber(int i) {
  nav_msgs::Odometry odom;
  odom.header.frame_id = "odom";
  odom.child_frame_id = "base_link";
  odom.pose.pose.position.x = i;
  return encode(odom);
}

}  // namespace

TEST(DdsTransport, MessagesReachAReaderOfTheSameTopicAndTypeInOrder) {
  DdsParticipant node(testDomain(), "mmlio_test_node");
  DdsParticipant peer(testDomain(), "mmlio_test_peer");
  std::mutex mutex;
  std::vector<Cdr> received;
  peer.reader(topicOnWire("/mmlio/odometry"), typeOnWire("nav_msgs/msg/Odometry"), reliableQos(100), [&](Cdr&& m) {
    std::lock_guard<std::mutex> lock(mutex);
    received.push_back(std::move(m));
  });
  auto& writer = node.writer(topicOnWire("/mmlio/odometry"), typeOnWire("nav_msgs/msg/Odometry"), reliableQos(100));
  ASSERT_TRUE(waitFor([&] { return writer.matched() == 1; }, 10.0)) << "the reader was not discovered";
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(writer.write(odometryNumber(i)));
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return received.size() == 20;
      },
      10.0));
  for (int i = 0; i < 20; ++i) EXPECT_EQ(received[i], odometryNumber(i)) << i;
}

TEST(DdsTransport, ALatchedMapReachesALateReaderAndLargeCloudsArriveWhole) {
  DdsParticipant node(testDomain(), "mmlio_test_node");
  auto& writer = node.writer(topicOnWire("/mmlio/map"), typeOnWire("sensor_msgs/msg/PointCloud2"), latchedQos());
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = "map";
  cloud.height = 1;
  cloud.width = 200000;  // 3.2 MB: many fragments
  cloud.point_step = 16;
  cloud.row_step = 16 * cloud.width;
  cloud.data.resize(cloud.row_step);
  for (std::size_t i = 0; i < cloud.data.size(); ++i) cloud.data[i] = static_cast<std::uint8_t>(i * 31 + i / 997);
  const Cdr map = encode(cloud);
  ASSERT_TRUE(writer.write(map));  // before anyone listens

  DdsParticipant late(testDomain(), "mmlio_test_late");
  std::mutex mutex;
  std::vector<Cdr> received;
  late.reader(topicOnWire("/mmlio/map"), typeOnWire("sensor_msgs/msg/PointCloud2"), latchedQos(), [&](Cdr&& m) {
    std::lock_guard<std::mutex> lock(mutex);
    received.push_back(std::move(m));
  });
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return !received.empty();
      },
      20.0));
  EXPECT_EQ(received.front(), map);
}

TEST(DdsTransport, DomainIdComesFromRosDomainIdAndIsChecked) {
  setenv("ROS_DOMAIN_ID", "42", 1);
  EXPECT_EQ(domainIdFromEnvironment(), 42);
  unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(domainIdFromEnvironment(), 0);
  for (const char* bad : {"233", "-1", "7x"}) {
    setenv("ROS_DOMAIN_ID", bad, 1);
    EXPECT_THROW(domainIdFromEnvironment(), Error) << bad;
  }
  unsetenv("ROS_DOMAIN_ID");
}

}  // namespace mmlio::ros2
