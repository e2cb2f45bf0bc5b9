#pragma once
// Live counterpart of the bag reader's IMU unit detection (src/io/imu_unit.*): with acc_unit
// "auto" the first `samples` messages are held back until their mean |acc| decides g vs m/s^2
// (the same rule and threshold as for bags, via io::imuAccScaleFromMean); then they and every
// later message come out decoded in m/s^2, in arrival order.
#include <sensor_msgs/Imu.h>

#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::live {

class ImuUnitGate {
 public:
  /// Throws mmlio::Error for an acc_unit other than auto, g or m/s2.
  ImuUnitGate(std::string topic, std::string acc_unit, int samples = 50);

  /// Decoded samples released by this message (none while still guessing).
  std::vector<ImuSample> add(const sensor_msgs::Imu& msg);
  /// Decides from what is held (end of stream with fewer than `samples` messages) and releases it.
  std::vector<ImuSample> release();

  bool decided() const { return scale_ > 0; }
  double accScale() const { return scale_; }

 private:
  std::vector<ImuSample> decide();

  std::string topic_, acc_unit_;
  int samples_;
  double scale_ = -1.0;  // multiplier to m/s^2, < 0 until decided
  std::vector<sensor_msgs::Imu> held_;
};

}  // namespace mmlio::live
