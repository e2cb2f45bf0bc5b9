// mmlio init: a starter rig config from a bag's topics.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <filesystem>

#include "../common/error_of.hpp"
#include "cloud_builder.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/bag_info.hpp"
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
  info.topics = {
      topic("/imu/data", "sensor_msgs/Imu", 100), topic("/livox/imu", "sensor_msgs/Imu", 200),
      topic("/livox/lidar", "livox_ros_driver/CustomMsg", 10),
      topic("/velodyne_points", "sensor_msgs/PointCloud2", 10,
            {"x(float32)", "y(float32)", "z(float32)", "intensity(float32)", "ring(uint16)", "time(float32)"})};
  const std::string text = starterRigConfig(info);
  const config::RigConfig cfg = config::parseRigConfig(text, "starter.yaml");
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
  const config::RigConfig cfg = config::parseRigConfig(starterRigConfig(info), "starter.yaml");
  EXPECT_EQ(cfg.mode, "vi");
  ASSERT_EQ(cfg.lidars.size(), 2u);
  EXPECT_EQ(cfg.lidars[0].type, "generic_spinning");
  EXPECT_EQ(cfg.lidars[1].type, "ouster");
  EXPECT_EQ(cfg.lidars[1].num_rings, 64);

  info.topics = {topic("/imu", "sensor_msgs/msg/Imu", 200), topic("/a", "livox_ros_driver2/msg/CustomMsg", 10),
                 topic("/b", "livox_ros_driver2/msg/CustomMsg", 10)};
  const config::RigConfig two = config::parseRigConfig(starterRigConfig(info), "starter.yaml");
  EXPECT_EQ(two.mode, "hi");
  ASSERT_EQ(two.lidars.size(), 2u);
  EXPECT_EQ(two.lidars[0].name, "livox");
  EXPECT_EQ(two.lidars[1].name, "livox_2");
}

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child,
                                          const Eigen::Isometry3d& T) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  const Eigen::Quaterniond q(T.linear());
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  t.transform.translation.x = T.translation().x();
  t.transform.translation.y = T.translation().y();
  t.transform.translation.z = T.translation().z();
  return t;
}

TEST(StarterRigConfig, ExtrinsicsComeFromTheBagsTfStaticThroughTheFrameTree) {
  // base_link carries the IMU (turned 90 deg, 0.1 m ahead) and the VLP-16 (0.5 m up): the LiDAR in
  // the IMU's frame is found through base_link, whichever way the transforms point.
  Eigen::Isometry3d T_base_imu = Eigen::Isometry3d::Identity();
  T_base_imu.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_base_imu.translation() = Eigen::Vector3d(0.1, 0.0, 0.2);
  Eigen::Isometry3d T_base_velodyne = Eigen::Isometry3d::Identity();
  T_base_velodyne.translation() = Eigen::Vector3d(0.0, 0.0, 0.5);
  const std::string path = (std::filesystem::temp_directory_path() / "mmlio_tf_static.bag").string();
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    const ros::Time t0(1700000000, 0);
    tf2_msgs::TFMessage tf;
    tf.transforms = {transform("base_link", "imu_link", T_base_imu),
                     transform("/base_link", "velodyne", T_base_velodyne)};
    bag.write("/tf_static", t0, tf);
    for (int k = 0; k < 3; ++k) {
      const ros::Time t = t0 + ros::Duration(0.1 * k);
      sensor_msgs::Imu imu;
      imu.header.stamp = t;
      imu.header.frame_id = "/imu_link";
      imu.linear_acceleration.z = 9.81;
      bag.write("/imu", t, imu);
      sensor_msgs::PointCloud2 cloud = makeCloud(
          {{"x", PF::FLOAT32}, {"y", PF::FLOAT32}, {"z", PF::FLOAT32}, {"ring", PF::UINT16}, {"time", PF::FLOAT32}},
          static_cast<Stamp>(t.toNSec()), 1);
      cloud.header.frame_id = "velodyne";
      putXyz(cloud, 0, 5.0f, 0.0f, 0.0f);
      bag.write("/velodyne_points", t, cloud);
    }
  }
  const BagInfo info = describeBag(path);
  ASSERT_EQ(info.static_transforms.size(), 2u);
  const config::RigConfig cfg = config::parseRigConfig(starterRigConfig(info), "starter.yaml");
  ASSERT_EQ(cfg.lidars.size(), 1u);
  EXPECT_EQ(cfg.lidars[0].type, "velodyne");
  const Eigen::Isometry3d want = T_base_imu.inverse() * T_base_velodyne;
  EXPECT_TRUE(cfg.lidars[0].T_imu_sensor.isApprox(want, 1e-6)) << cfg.lidars[0].T_imu_sensor.matrix();
  std::filesystem::remove(path);
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
