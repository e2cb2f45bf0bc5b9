#include "mmlio/lidar/deskew.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mmlio/core/so3.hpp"

namespace mmlio::lidar {

Eigen::Isometry3d se3Exp(const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3::exp(w).toRotationMatrix();
  const double a = w.norm();
  const Eigen::Matrix3d W = so3::hat(w);
  Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
  if (a < 1e-6) {
    V += 0.5 * W + W * W / 6.0;
  } else {
    V += (1 - std::cos(a)) / (a * a) * W + (a - std::sin(a)) / (a * a * a) * W * W;
  }
  T.translation() = V * v;
  return T;
}

SweepMotion::SweepMotion(std::vector<double> times_s, const std::vector<Eigen::Isometry3d>& T_end_t)
    : times_s_(std::move(times_s)) {
  if (times_s_.size() != T_end_t.size()) throw std::invalid_argument("SweepMotion: times and poses differ in size");
  if (!std::is_sorted(times_s_.begin(), times_s_.end())) throw std::invalid_argument("SweepMotion: times not sorted");
  q_.reserve(T_end_t.size());
  p_.reserve(T_end_t.size());
  for (const auto& T : T_end_t) {
    q_.emplace_back(Eigen::Quaterniond(T.rotation()).normalized());
    p_.emplace_back(T.translation());
  }
}

SweepMotion SweepMotion::constantTwist(const Eigen::Vector3d& v_body, const Eigen::Vector3d& w_body,
                                       double sweep_end_s) {
  SweepMotion m;
  m.is_twist_ = true;
  m.v_body_ = v_body;
  m.w_body_ = w_body;
  m.twist_end_s_ = sweep_end_s;
  return m;
}

Eigen::Isometry3d SweepMotion::at(double t_s) const {
  if (is_twist_) {
    const double dt = t_s - twist_end_s_;  // <= 0 inside the sweep
    return se3Exp(v_body_ * dt, w_body_ * dt);
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (times_s_.empty()) return T;
  std::size_t i1 = static_cast<std::size_t>(std::upper_bound(times_s_.begin(), times_s_.end(), t_s) - times_s_.begin());
  if (i1 == 0 || i1 == times_s_.size()) {  // clamped
    const std::size_t i = i1 == 0 ? 0 : times_s_.size() - 1;
    T.linear() = q_[i].toRotationMatrix();
    T.translation() = p_[i];
    return T;
  }
  const std::size_t i0 = i1 - 1;
  const double span = times_s_[i1] - times_s_[i0];
  const double a = span > 0 ? (t_s - times_s_[i0]) / span : 0.0;
  T.linear() = q_[i0].slerp(a, q_[i1]).toRotationMatrix();
  T.translation() = (1 - a) * p_[i0] + a * p_[i1];
  return T;
}

void deskewToEnd(LidarScan& scan, const Eigen::Isometry3d& T_imu_sensor, const SweepMotion& motion,
                 double sweep_end_s) {
  if (motion.isIdentity() || scan.points.empty()) return;
  // The sensor-frame correction T_endsensor_tsensor is tabulated every kTableStepS as a 3x4
  // matrix and interpolated linearly per point: exact motion evaluation (slerp / SE(3) exp) per
  // point would dominate the cost, and over 0.25 ms the rotation moves by well under a milliradian,
  // so the interpolated matrix is a rotation to ~1e-8 (far below a micrometre at 100 m).
  constexpr double kTableStepS = 0.25e-3;
  constexpr int kMaxTable = 20000;
  float tmin = scan.points.front().time_s, tmax = tmin;
  for (const Point& p : scan.points) {
    tmin = std::min(tmin, p.time_s);
    tmax = std::max(tmax, p.time_s);
  }
  const int nodes = std::clamp(static_cast<int>(std::ceil((tmax - tmin) / kTableStepS)) + 1, 2, kMaxTable);
  const double step = std::max(static_cast<double>(tmax - tmin) / (nodes - 1), 1e-12);
  const Eigen::Isometry3d T_sensor_imu = T_imu_sensor.inverse();
  const Eigen::Isometry3d T_ref_inv = motion.at(sweep_end_s).inverse();
  std::vector<Eigen::Matrix<float, 3, 4>> table(static_cast<std::size_t>(nodes));
  for (int k = 0; k < nodes; ++k)
    table[k] =
        (T_sensor_imu * (T_ref_inv * motion.at(tmin + k * step)) * T_imu_sensor).matrix().topRows<3>().cast<float>();
  const float inv_step = static_cast<float>(1.0 / step);
  for (Point& p : scan.points) {
    const float x = (p.time_s - tmin) * inv_step;
    const int k = std::clamp(static_cast<int>(x), 0, nodes - 2);
    const float a = std::clamp(x - static_cast<float>(k), 0.f, 1.f);
    const Eigen::Matrix<float, 3, 4> M = (1.f - a) * table[k] + a * table[k + 1];
    p.xyz = M.leftCols<3>() * p.xyz + M.col(3);
  }
}

}  // namespace mmlio::lidar
