#pragma once
// Core types -> ROS messages for what the node publishes. Stateless, no estimation.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::ros_node {

/// Integer nanoseconds since the epoch -> ros::Time (exact).
ros::Time toRosTime(Stamp stamp_ns);

/// Points (x y z intensity, float32, point_step 16, dense, little endian) moved by T_frame_points
/// into `frame_id`, e.g. body-frame sweep points with T_world_body into "map".
sensor_msgs::PointCloud2 toPointCloud2(const std::vector<Point>& points, const Eigen::Isometry3d& T_frame_points,
                                       Stamp stamp_ns, const std::string& frame_id);

/// The pose T_frame_body of `state` in `frame_id`, stamped at state.stamp_ns.
geometry_msgs::PoseStamped toPoseStamped(const NavState& state, const std::string& frame_id);
/// Same as a transform frame_id <- child_frame_id (what a tf broadcaster would send).
geometry_msgs::TransformStamped toTransformStamped(const NavState& state, const std::string& frame_id,
                                                   const std::string& child_frame_id);

}  // namespace mmlio::ros_node
