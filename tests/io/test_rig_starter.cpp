// mmlio init: a starter rig config from a bag's topics.
#include <gtest/gtest.h>

#include "error_of.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/rig_config.hpp"
#include "mmlio/io/rig_starter.hpp"

namespace mmlio::io {
namespace {

TopicInfo topic(const std::string& name, const std::string& type, double hz, std::vector<std::string> fields = {}) {
  TopicInfo t;
  t.topic = name;
  t.type = type;
  t.rate_hz = hz;
  t.messages = static_cast<std::size_t>(hz * 60);
  t.fields = std::move(fields);
  return t;
}

TEST(StarterRigConfig, AVelodyneALivoxAndItsImuGiveAnHviRigThatLoads) {
  BagInfo info;
  info.path = "rig.bag";
  info.imu_unit_guess = "g";
  info.topics = {topic("/imu/data", "sensor_msgs/Imu", 100),
                 topic("/livox/imu", "sensor_msgs/Imu", 200),
                 topic("/livox/lidar", "livox_ros_driver/CustomMsg", 10),
                 topic("/velodyne_points", "sensor_msgs/PointCloud2", 10,
                       {"x(float32)", "y(float32)", "z(float32)", "intensity(float32)", "ring(uint16)", "time(float32)"})};
  const std::string text = starterRigConfig(info);
  const RigConfig cfg = parseRigConfig(text, "starter.yaml");
  EXPECT_EQ(cfg.mode, "hvi");
  EXPECT_EQ(cfg.imu.topic, "/livox/imu");  // the faster IMU: the Livox's own
  ASSERT_EQ(cfg.lidars.size(), 2u);
  EXPECT_EQ(cfg.lidars[0].name, "velodyne");
  EXPECT_EQ(cfg.lidars[0].type, "velodyne");
  EXPECT_EQ(cfg.lidars[0].topic, "/velodyne_points");
  EXPECT_EQ(cfg.lidars[1].type, "livox");
  EXPECT_EQ(cfg.lidars[1].topic, "/livox/lidar");
  EXPECT_EQ(cfg.reference_lidar, "velodyne");
  EXPECT_TRUE(cfg.lidars[0].T_imu_sensor.matrix().isIdentity(0.0));
  EXPECT_NEAR(cfg.lidars[1].T_imu_sensor.translation().x(), 0.05512, 1e-12);
  // Every guess says what to check.
  EXPECT_NE(text.find("CHECK: not in the bag"), std::string::npos) << text;
  EXPECT_NE(text.find("read as g"), std::string::npos) << text;
}

TEST(StarterRigConfig, TheCloudsFieldsNameTheDriverAndTheKindsNameTheMode) {
  BagInfo info;
  info.path = "ouster.db3";
  info.topics = {topic("/imu", "sensor_msgs/msg/Imu", 400),  // in name order, as describeBag lists them
                 topic("/lidar2", "sensor_msgs/msg/PointCloud2", 10, {"x(float32)", "y(float32)", "z(float32)"}),
                 topic("/os/points", "sensor_msgs/msg/PointCloud2", 10, {"x(float32)", "t(uint32)", "ring(uint16)"})};
  const RigConfig cfg = parseRigConfig(starterRigConfig(info), "starter.yaml");
  EXPECT_EQ(cfg.mode, "vi");
  ASSERT_EQ(cfg.lidars.size(), 2u);
  EXPECT_EQ(cfg.lidars[0].type, "generic_spinning");
  EXPECT_EQ(cfg.lidars[1].type, "ouster");
  EXPECT_EQ(cfg.lidars[1].num_rings, 64);

  info.topics = {topic("/imu", "sensor_msgs/msg/Imu", 200),
                 topic("/a", "livox_ros_driver2/msg/CustomMsg", 10),
                 topic("/b", "livox_ros_driver2/msg/CustomMsg", 10)};
  const RigConfig two = parseRigConfig(starterRigConfig(info), "starter.yaml");
  EXPECT_EQ(two.mode, "hi");
  ASSERT_EQ(two.lidars.size(), 2u);
  EXPECT_EQ(two.lidars[0].name, "livox");
  EXPECT_EQ(two.lidars[1].name, "livox_2");
}

TEST(StarterRigConfig, ABagWithoutAnImuOrALidarIsAnError) {
  BagInfo info;
  info.path = "x.bag";
  info.topics = {topic("/velodyne_points", "sensor_msgs/PointCloud2", 10)};
  EXPECT_ERROR_CONTAINS(starterRigConfig(info), "x.bag has no sensor_msgs/Imu topic");
  info.topics = {topic("/imu", "sensor_msgs/Imu", 200)};
  EXPECT_ERROR_CONTAINS(starterRigConfig(info), "x.bag has no point-cloud topic");
}

}  // namespace
}  // namespace mmlio::io
