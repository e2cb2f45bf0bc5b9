#pragma once
// De-skew (motion compensation): a sweep's points are taken over ~0.1 s while the body moves;
// each point is re-expressed in the sensor frame at the sweep end, using the body motion over
// the sweep (IMU-propagated in the pipeline).

#include <Eigen/Geometry>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::lidar {

/// Body (IMU) poses over a sweep relative to the body at the sweep end: T_end_t maps a point in
/// the body frame at time t into the body frame at the sweep end. Times are seconds in the sweep's
/// time base (the same as Point::time_s, i.e. from the window start).
class SweepMotion {
 public:
  SweepMotion() = default;  // identity: no motion
  /// Samples at sorted times; at() interpolates between them (lerp + slerp) and clamps outside.
  SweepMotion(std::vector<double> times_s, const std::vector<Eigen::Isometry3d>& T_end_t);
  /// Constant body-frame twist (screw motion: T_world_body(t) = T0 * Exp([v, w] t)), exact at
  /// every t: T_end_t = Exp(-[v, w] (sweep_end_s - t)).
  static SweepMotion constantTwist(const Eigen::Vector3d& v_body, const Eigen::Vector3d& w_body, double sweep_end_s);

  Eigen::Isometry3d at(double t_s) const;
  bool isIdentity() const { return !is_twist_ && times_s_.empty(); }

 private:
  std::vector<double> times_s_;
  std::vector<Eigen::Quaterniond> q_;
  std::vector<Eigen::Vector3d> p_;
  bool is_twist_ = false;
  Eigen::Vector3d v_body_ = Eigen::Vector3d::Zero(), w_body_ = Eigen::Vector3d::Zero();
  double twist_end_s_ = 0.0;
};

/// SE(3) exponential of the twist [v (m), w (rad)], body-frame (left Jacobian on the translation).
Eigen::Isometry3d se3Exp(const Eigen::Vector3d& v, const Eigen::Vector3d& w);

/// In place: each point (sensor frame, taken at its time_s) becomes that point in the sensor frame
/// at sweep_end_s: p <- T_imu_sensor^-1 * T_end_t(t) * T_imu_sensor * p, with T_end_t re-referenced
/// to sweep_end_s (motion.at(sweep_end_s)^-1 * motion.at(t)) so a motion relative to another
/// instant also works. Point times are left unchanged.
void deskewToEnd(LidarScan& scan, const Eigen::Isometry3d& T_imu_sensor, const SweepMotion& motion, double sweep_end_s);

}  // namespace mmlio::lidar
