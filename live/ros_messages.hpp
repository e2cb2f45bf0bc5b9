#pragma once
// Core types -> the ROS messages the node publishes (and the pose hint it takes). Stateless, no
// estimation.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "mmlio/backend/map_localizer.hpp"
#include "mmlio/core/types.hpp"
#include "mmlio/estimator/degeneracy.hpp"

namespace mmlio::live {

/// Integer nanoseconds since the epoch -> ros::Time (exact).
ros::Time toRosTime(Stamp stamp_ns);

/// Points (x y z intensity, float32, point_step 16, dense, little endian) moved by T_frame_points
/// into `frame_id`, e.g. body-frame sweep points with T_odom_body into "odom".
sensor_msgs::PointCloud2 toPointCloud2(const std::vector<Point>& points, const Eigen::Isometry3d& T_frame_points,
                                       Stamp stamp_ns, const std::string& frame_id);

geometry_msgs::Pose toPose(const Eigen::Isometry3d& T);
/// frame_id <- child_frame_id.
geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T_frame_child, Stamp stamp_ns,
                                            const std::string& frame_id, const std::string& child_frame_id);

/// Pose covariance (ROS order x y z, rotation about x y z; both in `frame_id`'s axes) from what the
/// sweep's LiDAR matches constrain: sigma^2 / eigenvalue along each eigenvector of the translation
/// and rotation information (point_sigma_m: the matches' point noise). Directions the LiDARs do not
/// observe (a corridor's axis) get a large variance, capped at max_variance.
std::array<double, 36> poseCovariance(const estimator::Degeneracy& d, const Eigen::Quaterniond& q_world_body,
                                      double point_sigma_m, double max_variance = 1e4);

/// nav_msgs/Odometry: pose of child_frame_id in frame_id, twist in child_frame_id (REP 105).
/// Twist covariance is not estimated: its diagonal is -1.
nav_msgs::Odometry toOdometry(const NavState& state, const Eigen::Isometry3d& T_frame_body,
                              const Eigen::Vector3d& angular_velocity_body,
                              const std::array<double, 36>& pose_covariance, const std::string& frame_id,
                              const std::string& child_frame_id);

nav_msgs::Path toPath(const Trajectory& trajectory, const std::string& frame_id);

Eigen::Isometry3d fromPose(const geometry_msgs::Pose& pose);

/// A localization's state as /diagnostics carries it (rqt_robot_monitor): OK once localized, WARN
/// while searching, ERROR when lost; its figures as key/values. now_ns in the estimator's time
/// (the status's stamps).
diagnostic_msgs::DiagnosticStatus localizationStatus(const backend::LocalizationStatus& s, Stamp now_ns,
                                                     const std::string& name);

/// What the node has had to give up so far.
struct InputFigures {
  std::size_t imu_messages = 0, sweeps = 0, sweeps_degraded = 0;
  std::size_t dropped_imu = 0, dropped_scans = 0;  // by the full hand-off queue: the node falls behind
  double quiet_s = 0.0;                            // sensor time since the last drop or degraded sweep
};
/// The input's state for /diagnostics, now: WARN when LiDAR messages were dropped (the node is
/// slower than the sensors) or sweeps degraded within the last kRecentTroubleS, ERROR when IMU
/// messages were; OK otherwise, with what was given up earlier in its message.
constexpr double kRecentTroubleS = 10.0;
diagnostic_msgs::DiagnosticStatus inputStatus(const InputFigures& f, const std::string& name);

diagnostic_msgs::DiagnosticArray toDiagnostics(std::vector<diagnostic_msgs::DiagnosticStatus> statuses, Stamp stamp_ns);

}  // namespace mmlio::live
