#include "ros_messages.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstring>

namespace mmlio::live {

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

geometry_msgs::Pose toPose(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose pose;
  const Eigen::Quaterniond q(T.linear());
  pose.position.x = T.translation().x();
  pose.position.y = T.translation().y();
  pose.position.z = T.translation().z();
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T, Stamp stamp_ns, const std::string& frame_id,
                                            const std::string& child_frame_id) {
  const geometry_msgs::Pose pose = toPose(T);
  geometry_msgs::TransformStamped msg;
  msg.header.stamp = toRosTime(stamp_ns);
  msg.header.frame_id = frame_id;
  msg.child_frame_id = child_frame_id;
  msg.transform.translation.x = pose.position.x;
  msg.transform.translation.y = pose.position.y;
  msg.transform.translation.z = pose.position.z;
  msg.transform.rotation = pose.orientation;
  return msg;
}

std::array<double, 36> poseCovariance(const estimator::Degeneracy& d, const Eigen::Quaterniond& q_world_body,
                                      double point_sigma_m, double max_variance) {
  const double s2 = point_sigma_m * point_sigma_m;
  const auto block = [&](const Eigen::Matrix3d& basis, const Eigen::Vector3d& eigenvalues) {
    Eigen::Vector3d variance;
    for (int i = 0; i < 3; ++i) variance[i] = eigenvalues[i] > s2 / max_variance ? s2 / eigenvalues[i] : max_variance;
    return Eigen::Matrix3d(basis * variance.asDiagonal() * basis.transpose());
  };
  const Eigen::Matrix3d R = q_world_body.toRotationMatrix();
  const Eigen::Matrix3d translation = block(d.translation_basis, d.translation_eigenvalues);  // world axes
  const Eigen::Matrix3d rotation =
      R * block(d.rotation_basis, d.rotation_eigenvalues) * R.transpose();  // body -> world
  std::array<double, 36> out{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      out[static_cast<std::size_t>(6 * r + c)] = translation(r, c);
      out[static_cast<std::size_t>(6 * (r + 3) + c + 3)] = rotation(r, c);
    }
  return out;
}

nav_msgs::Odometry toOdometry(const NavState& state, const Eigen::Isometry3d& T_frame_body,
                              const Eigen::Vector3d& angular_velocity_body,
                              const std::array<double, 36>& pose_covariance, const std::string& frame_id,
                              const std::string& child_frame_id) {
  nav_msgs::Odometry msg;
  msg.header.stamp = toRosTime(state.stamp_ns);
  msg.header.frame_id = frame_id;
  msg.child_frame_id = child_frame_id;
  msg.pose.pose = toPose(T_frame_body);
  std::copy(pose_covariance.begin(), pose_covariance.end(), msg.pose.covariance.begin());
  const Eigen::Vector3d v_body = state.q_world_body.conjugate() * state.v_world;
  msg.twist.twist.linear.x = v_body.x();
  msg.twist.twist.linear.y = v_body.y();
  msg.twist.twist.linear.z = v_body.z();
  msg.twist.twist.angular.x = angular_velocity_body.x();
  msg.twist.twist.angular.y = angular_velocity_body.y();
  msg.twist.twist.angular.z = angular_velocity_body.z();
  for (int i = 0; i < 6; ++i) msg.twist.covariance[static_cast<std::size_t>(7 * i)] = -1.0;
  return msg;
}

nav_msgs::Path toPath(const Trajectory& trajectory, const std::string& frame_id) {
  nav_msgs::Path path;
  path.header.frame_id = frame_id;
  if (!trajectory.empty()) path.header.stamp = toRosTime(trajectory.back().stamp_ns);
  path.poses.reserve(trajectory.size());
  for (const StampedPose& p : trajectory) {
    geometry_msgs::PoseStamped ps;
    ps.header.stamp = toRosTime(p.stamp_ns);
    ps.header.frame_id = frame_id;
    ps.pose = toPose(p.T_world_body);
    path.poses.push_back(ps);
  }
  return path;
}

Eigen::Isometry3d fromPose(const geometry_msgs::Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  const Eigen::Quaterniond q(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z);
  if (q.norm() > 1e-6) T.linear() = q.normalized().toRotationMatrix();
  return T;
}

namespace {

void addValue(diagnostic_msgs::DiagnosticStatus* d, const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue kv;
  kv.key = key;
  kv.value = value;
  d->values.push_back(kv);
}

}  // namespace

diagnostic_msgs::DiagnosticStatus localizationStatus(const backend::LocalizationStatus& s, Stamp now_ns,
                                                     const std::string& name) {
  diagnostic_msgs::DiagnosticStatus d;
  d.name = name;
  const bool lost = !s.localized && !s.lost_spells.empty();
  if (s.localized) {
    d.level = diagnostic_msgs::DiagnosticStatus::OK;
    d.message = "localized in the session map";
  } else if (lost) {
    d.level = diagnostic_msgs::DiagnosticStatus::ERROR;
    d.message = "lost for " + std::to_string(static_cast<int>(toSec(now_ns - s.lost_spells.back().first))) +
                " s: relocalizing (" + s.last_reason + ")";
  } else {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    d.message = "not localized yet (" + s.last_reason + ")";
  }
  addValue(&d, "localized", s.localized ? "true" : "false");
  addValue(&d, "first_localized_s_ago",
           s.first_localized_ns ? std::to_string(toSec(now_ns - *s.first_localized_ns)) : "never");
  addValue(&d, "keyframes", std::to_string(s.keyframes));
  addValue(&d, "keyframes_fitting_the_map", std::to_string(s.keyframes_fitted));
  addValue(&d, "last_fitness_m", std::to_string(s.last_fitness_m));
  addValue(&d, "last_overlap", std::to_string(s.last_overlap));
  addValue(&d, "lost_spells", std::to_string(s.lost_spells.size()));
  addValue(&d, "relocalizations", std::to_string(s.relocalizations));
  addValue(&d, "pose_hints", std::to_string(s.pose_hints));
  addValue(&d, "pose_hints_refuted", std::to_string(s.pose_hints_refuted));
  return d;
}

diagnostic_msgs::DiagnosticStatus inputStatus(const InputFigures& f, const std::string& name) {
  diagnostic_msgs::DiagnosticStatus d;
  d.name = name;
  const bool recent = f.quiet_s < kRecentTroubleS;
  if (f.dropped_imu > 0 && recent) {
    d.level = diagnostic_msgs::DiagnosticStatus::ERROR;
    d.message = std::to_string(f.dropped_imu) + " IMU messages dropped: the node falls behind its sensors";
  } else if (f.dropped_scans > 0 && recent) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    d.message = std::to_string(f.dropped_scans) + " LiDAR messages dropped: the node falls behind its sensors";
  } else if (f.sweeps_degraded > 0 && recent) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    d.message = std::to_string(f.sweeps_degraded) + " of " + std::to_string(f.sweeps) + " sweeps degraded";
  } else {
    d.level = diagnostic_msgs::DiagnosticStatus::OK;
    d.message = "keeping up";
    if (f.dropped_imu + f.dropped_scans + f.sweeps_degraded == 0) {
      d.message += ", nothing dropped";
    } else {
      d.message += " (earlier: " + std::to_string(f.dropped_imu) + " IMU and " + std::to_string(f.dropped_scans) +
                   " LiDAR messages dropped, " + std::to_string(f.sweeps_degraded) + " sweeps degraded; the last " +
                   std::to_string(static_cast<long>(f.quiet_s)) + " s ago)";
    }
  }
  addValue(&d, "imu_messages", std::to_string(f.imu_messages));
  addValue(&d, "sweeps", std::to_string(f.sweeps));
  addValue(&d, "sweeps_degraded", std::to_string(f.sweeps_degraded));
  addValue(&d, "dropped_imu", std::to_string(f.dropped_imu));
  addValue(&d, "dropped_scans", std::to_string(f.dropped_scans));
  return d;
}

diagnostic_msgs::DiagnosticArray toDiagnostics(std::vector<diagnostic_msgs::DiagnosticStatus> statuses,
                                               Stamp stamp_ns) {
  diagnostic_msgs::DiagnosticArray out;
  out.header.stamp = toRosTime(stamp_ns);
  out.status = std::move(statuses);
  return out;
}

}  // namespace mmlio::live
