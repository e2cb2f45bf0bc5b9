#include <CLI/CLI.hpp>
#include <iostream>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
int main(int argc, char** argv) {
  CLI::App app{"mmlio"};
  CLI11_PARSE(app, argc, argv);
  rosbag::Bag bag("/tmp/smoke.bag", rosbag::bagmode::Write);
  sensor_msgs::Imu imu; imu.header.stamp = ros::Time(1.0);
  bag.write("/imu", imu.header.stamp, imu);
  bag.close();
  std::cout << "ok\n";
}
