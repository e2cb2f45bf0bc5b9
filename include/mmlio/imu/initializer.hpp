#pragma once
// Static IMU initialisation: while the rig stands still, the mean specific force is gravity
// (giving roll and pitch; yaw is set to 0) and the mean angular rate is the gyroscope bias.
#include <Eigen/Geometry>
#include <deque>
#include <string>

#include "mmlio/core/types.hpp"

namespace mmlio::imu {

struct ImuInitConfig {
  double duration_s = 1.0;  // standstill window
  // Standstill test on the spread of 0.1-window-long block means (white noise averages out):
  double max_gyro_std_rad_s = 0.02;  // above: the rig is turning
  double max_acc_std_m_s2 = 0.2;     // above: the rig is accelerating
  // A constant turn (turntable, steady curve) leaves the block means still: rates above any
  // plausible MEMS gyroscope bias are motion, not bias.
  double max_gyro_bias_rad_s = 0.1;
  // |mean acc| must look like gravity in m/s^2 (9.81) or in g (1.0), within this fraction.
  double max_gravity_norm_error = 0.1;
  // Never still for this long: initialise anyway (a warning; report imu_init.forced). Each second
  // waited is a second without poses for a bag that starts in motion; a rig that starts still is
  // found still within duration_s.
  double force_after_s = 2.0;
};

struct ImuInitResult {
  bool ok = false;
  Eigen::Quaterniond q_world_imu = Eigen::Quaterniond::Identity();  // gravity along -z, yaw 0
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  double gravity_norm_m_s2 = 0.0;  // |mean acc| over the window, times acc_scale
  double acc_scale = 1.0;          // 9.80665 when the accelerations looked like g (|mean| < 3)
  bool forced = false;             // initialised while moving (gyro bias left at 0)
  std::string message;             // summary, or why not ready
};

class ImuInitializer {
 public:
  explicit ImuInitializer(ImuInitConfig cfg = {});
  void add(const ImuSample& sample);
  /// A full window that looked stationary (or the force_after_s fallback).
  bool ready() const;
  ImuInitResult result() const;

 private:
  struct WindowStats {
    Eigen::Vector3d mean_acc, mean_gyro;
    double acc_std, gyro_std, span_s;
  };
  WindowStats stats() const;
  /// Empty when the window looks like a standstill, else the reason it does not.
  std::string notStillReason(const WindowStats& s) const;

  ImuInitConfig cfg_;
  std::deque<ImuSample> window_;
  Stamp first_ns_ = -1;
};

}  // namespace mmlio::imu
