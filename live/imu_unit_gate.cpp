#include "imu_unit_gate.hpp"

#include <cmath>

#include "mmlio/core/error.hpp"
#include "mmlio/io/cloud_decoders.hpp"
// Private header of mmlio::io (not installed under include/): the unit rule shared with bags.
#include "../src/io/imu_unit.hpp"

namespace mmlio::live {

ImuUnitGate::ImuUnitGate(std::string topic, std::string acc_unit, int samples)
    : topic_(std::move(topic)), acc_unit_(std::move(acc_unit)), samples_(samples) {
  if (acc_unit_ != "auto") {
    // Throws for an unknown unit; never calls the mean for g or m/s2.
    scale_ = io::imuAccScaleFromMean([] { return -1.0; }, topic_, acc_unit_, "the live topic");
  }
}

std::vector<ImuSample> ImuUnitGate::add(const sensor_msgs::Imu& msg) {
  if (decided()) return {io::decodeImu(msg, scale_)};
  held_.push_back(msg);
  if (static_cast<int>(held_.size()) < samples_) return {};
  return decide();
}

std::vector<ImuSample> ImuUnitGate::release() {
  if (decided()) return {};
  return decide();
}

std::vector<ImuSample> ImuUnitGate::decide() {
  auto mean = [&] {
    double sum = 0.0;
    int n = 0;
    for (const auto& m : held_) {
      const auto& a = m.linear_acceleration;
      const double norm = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
      if (!std::isfinite(norm)) continue;
      sum += norm;
      ++n;
    }
    return n > 0 ? sum / n : -1.0;
  };
  scale_ = io::imuAccScaleFromMean(mean, topic_, acc_unit_, "the live topic");
  std::vector<ImuSample> out;
  out.reserve(held_.size());
  for (const auto& m : held_) out.push_back(io::decodeImu(m, scale_));
  held_.clear();
  return out;
}

}  // namespace mmlio::live
