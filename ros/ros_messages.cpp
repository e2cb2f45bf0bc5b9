#include "ros_messages.hpp"

#include <cstring>

namespace mmlio::ros_node {

ros::Time toRosTime(Stamp stamp_ns) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(stamp_ns < 0 ? 0 : stamp_ns));
  return t;
}

sensor_msgs::PointCloud2 toPointCloud2(const std::vector<Point>& points, const Eigen::Isometry3d& T_frame_points,
                                       Stamp stamp_ns, const std::string& frame_id) {
  sensor_msgs::PointCloud2 msg;
  msg.header.stamp = toRosTime(stamp_ns);
  msg.header.frame_id = frame_id;
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(points.size());
  const char* names[] = {"x", "y", "z", "intensity"};
  for (std::uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.is_bigendian = false;
  msg.point_step = 16;
  msg.row_step = msg.point_step * msg.width;
  msg.is_dense = true;
  msg.data.resize(static_cast<std::size_t>(msg.row_step));
  const Eigen::Isometry3f T = T_frame_points.cast<float>();
  std::uint8_t* out = msg.data.data();
  for (const Point& p : points) {
    const Eigen::Vector3f q = T * p.xyz;
    const float v[4] = {q.x(), q.y(), q.z(), p.intensity};
    std::memcpy(out, v, sizeof v);
    out += sizeof v;
  }
  return msg;
}

geometry_msgs::PoseStamped toPoseStamped(const NavState& state, const std::string& frame_id) {
  geometry_msgs::PoseStamped msg;
  msg.header.stamp = toRosTime(state.stamp_ns);
  msg.header.frame_id = frame_id;
  const Eigen::Quaterniond q = state.q_world_body.normalized();
  msg.pose.position.x = state.p_world.x();
  msg.pose.position.y = state.p_world.y();
  msg.pose.position.z = state.p_world.z();
  msg.pose.orientation.x = q.x();
  msg.pose.orientation.y = q.y();
  msg.pose.orientation.z = q.z();
  msg.pose.orientation.w = q.w();
  return msg;
}

geometry_msgs::TransformStamped toTransformStamped(const NavState& state, const std::string& frame_id,
                                                   const std::string& child_frame_id) {
  const geometry_msgs::PoseStamped pose = toPoseStamped(state, frame_id);
  geometry_msgs::TransformStamped msg;
  msg.header = pose.header;
  msg.child_frame_id = child_frame_id;
  msg.transform.translation.x = pose.pose.position.x;
  msg.transform.translation.y = pose.pose.position.y;
  msg.transform.translation.z = pose.pose.position.z;
  msg.transform.rotation = pose.pose.orientation;
  return msg;
}

}  // namespace mmlio::ros_node
