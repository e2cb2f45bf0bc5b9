// mmlio_ros_play BAG [RATE] [WAIT_S]: publishes the sensor_msgs/Imu, sensor_msgs/PointCloud2 and
// livox_ros_driver(2)/CustomMsg messages of a ROS1 bag on their topics, paced by their bag
// times / RATE (default 1). A stand-in for `rosbag play` (not packaged by Debian) to smoke-test
// mmlio_node. Waits up to WAIT_S s (default 10) for every topic to have a subscriber first.
// Also listens to /mmlio_node/pose and /mmlio_node/keyframe_cloud and prints what it received.
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <geometry_msgs/PoseStamped.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <iostream>
#include <map>
#include <string>

#include "mmlio/io/livox_msg.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "mmlio_ros_play", ros::init_options::AnonymousName);
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::cerr << "usage: mmlio_ros_play BAG [RATE=1] [WAIT_S=10]\n";
    return argc < 2 ? 1 : 0;
  }
  const double rate = argc > 2 ? std::stod(argv[2]) : 1.0;
  const double wait_s = argc > 3 ? std::stod(argv[3]) : 10.0;
  if (!ros::master::check()) {
    std::cerr << "mmlio_ros_play: no ROS master reachable at " << ros::master::getURI() << "\n";
    return 1;
  }
  rosbag::Bag bag(argv[1], rosbag::bagmode::Read);
  rosbag::View view(bag);
  ros::NodeHandle nh;
  std::size_t poses = 0, clouds = 0, cloud_points = 0;
  geometry_msgs::PoseStamped last_pose;
  ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "/mmlio_node/pose", 1000, [&](const geometry_msgs::PoseStamped::ConstPtr& m) { ++poses; last_pose = *m; });
  ros::Subscriber cloud_sub = nh.subscribe<sensor_msgs::PointCloud2>(
      "/mmlio_node/keyframe_cloud", 10, [&](const sensor_msgs::PointCloud2::ConstPtr& m) {
        ++clouds;
        cloud_points += m->width * m->height;
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  std::map<std::string, ros::Publisher> pubs;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (pubs.count(c->topic)) continue;
    if (c->datatype == "sensor_msgs/Imu") pubs[c->topic] = nh.advertise<sensor_msgs::Imu>(c->topic, 5000);
    else if (c->datatype == "sensor_msgs/PointCloud2")
      pubs[c->topic] = nh.advertise<sensor_msgs::PointCloud2>(c->topic, 100);
    else if (c->datatype == mmlio::io::kLivoxCustomMsgType || c->datatype == mmlio::io::kLivox2CustomMsgType)
      pubs[c->topic] = nh.advertise<mmlio::io::LivoxCustomMsg>(c->topic, 100);
  }
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wait_s);
  for (auto& [topic, pub] : pubs) {
    while (ros::ok() && pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.05).sleep();
    std::cerr << "mmlio_ros_play: " << topic << " has " << pub.getNumSubscribers() << " subscriber(s)\n";
  }
  const ros::Time bag_start = view.getBeginTime();
  const ros::WallTime wall_start = ros::WallTime::now();
  std::size_t sent = 0;
  for (const rosbag::MessageInstance& m : view) {
    if (!ros::ok()) break;
    const auto it = pubs.find(m.getTopic());
    if (it == pubs.end()) continue;
    const ros::WallTime due = wall_start + ros::WallDuration((m.getTime() - bag_start).toSec() / rate);
    const ros::WallDuration wait = due - ros::WallTime::now();
    if (wait > ros::WallDuration(0)) wait.sleep();
    if (auto imu = m.instantiate<sensor_msgs::Imu>()) it->second.publish(*imu);
    else if (auto cloud = m.instantiate<sensor_msgs::PointCloud2>()) it->second.publish(*cloud);
    else if (auto livox = m.instantiate<mmlio::io::LivoxCustomMsg>()) it->second.publish(*livox);
    else continue;
    ++sent;
  }
  ros::WallDuration(3.0).sleep();  // let the transport deliver the tail and the node finish
  spinner.stop();
  std::cerr << "mmlio_ros_play: published " << sent << " messages; received " << poses
            << " poses on /mmlio_node/pose (last: " << last_pose.header.frame_id << " t=" << last_pose.header.stamp
            << " p=" << last_pose.pose.position.x << " " << last_pose.pose.position.y << " "
            << last_pose.pose.position.z << "), " << clouds << " clouds (" << cloud_points
            << " points) on /mmlio_node/keyframe_cloud\n";
  return 0;
}
