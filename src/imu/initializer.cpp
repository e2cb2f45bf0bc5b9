#include "mmlio/imu/initializer.hpp"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <vector>

namespace mmlio::imu {

ImuInitializer::ImuInitializer(ImuInitConfig cfg) : cfg_(cfg) {}

void ImuInitializer::add(const ImuSample& sample) {
  if (first_ns_ < 0) first_ns_ = sample.stamp_ns;
  window_.push_back(sample);
  while (window_.size() > 2 && toSec(window_.back().stamp_ns - window_[1].stamp_ns) >= cfg_.duration_s) {
    window_.pop_front();
  }
}

ImuInitializer::WindowStats ImuInitializer::stats() const {
  WindowStats s{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0, 0.0, 0.0};
  if (window_.empty()) return s;
  for (const auto& m : window_) {
    s.mean_acc += m.acc_m_s2;
    s.mean_gyro += m.gyro_rad_s;
  }
  const double n = static_cast<double>(window_.size());
  s.mean_acc /= n;
  s.mean_gyro /= n;
  // Motion shows as a drift of short-block means; white sensor noise averages out of them, so
  // the test does not depend on the IMU's noise level.
  constexpr int kBlocks = 10;
  const std::size_t per_block = std::max<std::size_t>(1, window_.size() / kBlocks);
  std::vector<Eigen::Vector3d> acc_means, gyro_means;
  for (std::size_t b = 0; b + per_block <= window_.size(); b += per_block) {
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), g = Eigen::Vector3d::Zero();
    for (std::size_t i = b; i < b + per_block; ++i) {
      a += window_[i].acc_m_s2;
      g += window_[i].gyro_rad_s;
    }
    acc_means.emplace_back(a / per_block);
    gyro_means.emplace_back(g / per_block);
  }
  for (std::size_t b = 0; b < acc_means.size(); ++b) {
    s.acc_std += (acc_means[b] - s.mean_acc).squaredNorm();
    s.gyro_std += (gyro_means[b] - s.mean_gyro).squaredNorm();
  }
  s.acc_std = std::sqrt(s.acc_std / acc_means.size());
  s.gyro_std = std::sqrt(s.gyro_std / gyro_means.size());
  s.span_s = toSec(window_.back().stamp_ns - window_.front().stamp_ns);
  return s;
}

std::string ImuInitializer::notStillReason(const WindowStats& s) const {
  char buf[160];
  if (s.span_s < 0.95 * cfg_.duration_s) {
    std::snprintf(buf, sizeof(buf), "window %.2f s of %.1f s", s.span_s, cfg_.duration_s);
    return buf;
  }
  if (s.gyro_std > cfg_.max_gyro_std_rad_s) {
    std::snprintf(buf, sizeof(buf), "turning: gyro std %.3f > %.3f rad/s", s.gyro_std, cfg_.max_gyro_std_rad_s);
    return buf;
  }
  // The threshold is in m/s^2 also when the data are in g.
  const double acc_std_m_s2 = s.acc_std * (s.mean_acc.norm() < 3.0 ? 9.80665 : 1.0);
  if (acc_std_m_s2 > cfg_.max_acc_std_m_s2) {
    std::snprintf(buf, sizeof(buf), "accelerating: acc std %.3f > %.3f m/s^2", acc_std_m_s2, cfg_.max_acc_std_m_s2);
    return buf;
  }
  if (s.mean_gyro.norm() > cfg_.max_gyro_bias_rad_s) {
    std::snprintf(buf, sizeof(buf), "turning steadily: mean gyro %.3f > %.3f rad/s", s.mean_gyro.norm(),
                  cfg_.max_gyro_bias_rad_s);
    return buf;
  }
  const double g = s.mean_acc.norm();
  const double tol = cfg_.max_gravity_norm_error;
  if (std::abs(g / 9.81 - 1.0) > tol && std::abs(g - 1.0) > tol) {
    std::snprintf(buf, sizeof(buf), "|mean acc| %.3f looks like neither 9.81 m/s^2 nor 1 g", g);
    return buf;
  }
  return {};
}

bool ImuInitializer::ready() const {
  if (window_.size() < 10) return false;
  if (toSec(window_.back().stamp_ns - first_ns_) >= cfg_.force_after_s) return true;
  return notStillReason(stats()).empty();
}

ImuInitResult ImuInitializer::result() const {
  ImuInitResult r;
  const WindowStats s = stats();
  const std::string not_still = window_.size() < 10 ? "too few samples" : notStillReason(s);
  char buf[256];
  if (!ready()) {
    std::snprintf(buf, sizeof(buf),
                  "waiting for %.1f s at rest: %s (window %.2f s, gyro std %.3f rad/s, acc std %.3f m/s^2)",
                  cfg_.duration_s, not_still.c_str(), s.span_s, s.gyro_std, s.acc_std);
    r.message = buf;
    return r;
  }
  const bool still = not_still.empty();
  r.ok = true;
  r.forced = !still;
  r.acc_scale = s.mean_acc.norm() < 3.0 ? 9.80665 : 1.0;
  r.gravity_norm_m_s2 = s.mean_acc.norm() * r.acc_scale;
  r.gyro_bias = still ? s.mean_gyro : Eigen::Vector3d::Zero();
  // At rest the accelerometer measures -g, i.e. "up": rotate it onto +z, then remove the yaw.
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(s.mean_acc, Eigen::Vector3d::UnitZ());
  const Eigen::Matrix3d R = q.toRotationMatrix();
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  r.q_world_imu = (Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()) * q).normalized();
  const Eigen::Matrix3d Rw = r.q_world_imu.toRotationMatrix();
  const double roll_deg = std::atan2(Rw(2, 1), Rw(2, 2)) * 180.0 / M_PI;
  const double pitch_deg = -std::asin(std::clamp(Rw(2, 0), -1.0, 1.0)) * 180.0 / M_PI;
  const std::string prefix = still ? "" : "rig never still (" + not_still + "), forced: ";
  std::snprintf(buf, sizeof(buf),
                "%s|g|=%.3f m/s^2 (acc scale %.5f), gyro bias (%.4f %.4f %.4f) rad/s, roll %.2f pitch %.2f deg",
                prefix.c_str(), r.gravity_norm_m_s2, r.acc_scale, r.gyro_bias.x(), r.gyro_bias.y(), r.gyro_bias.z(),
                roll_deg, pitch_deg);
  r.message = buf;
  return r;
}

}  // namespace mmlio::imu
