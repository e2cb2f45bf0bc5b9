#include "mmlio/pipeline/imu_gate.hpp"

#include "mmlio/core/log.hpp"

namespace mmlio::pipeline {

bool ImuGate::accept(const ImuSample& s) {
  const auto drop = [&](std::size_t* count, const char* why) {
    const Stamp at = last_ns_ != std::numeric_limits<Stamp>::min() ? last_ns_ : s.stamp_ns;
    if (counts_.total() == 0) counts_.first_at_ns = at;
    counts_.last_at_ns = at;
    if ((*count)++ == 0)
      log::warn("IMU sample at ", log::stampText(s.stamp_ns), " s dropped: ", why,
                " (further ones are counted in the report)");
    return false;
  };
  if (!s.acc_m_s2.allFinite() || !s.gyro_rad_s.allFinite()) return drop(&counts_.non_finite, "non-finite value");
  if (s.acc_m_s2.norm() > cfg_.max_acc_m_s2 || s.gyro_rad_s.norm() > cfg_.max_gyro_rad_s)
    return drop(&counts_.out_of_range, "beyond any IMU's range (50 g, 50 rad/s)");
  if (last_ns_ != std::numeric_limits<Stamp>::min()) {
    if (back_.jumpedBack(last_ns_, s.stamp_ns)) {
      back_.holdBack(last_ns_, s.stamp_ns);
      return drop(&counts_.jumped, "stamp far before the previous sample (the IMU's clock went back?)");
    }
    back_.accepted();
    if (s.stamp_ns <= last_ns_) return drop(&counts_.out_of_order, "stamp not after the previous sample");
    if (jump_.jumped(last_ns_, s.stamp_ns)) {
      // A lone stamp far ahead is corrupt; a stream that stays there had a real gap.
      if (jump_.holdBack(last_ns_, s.stamp_ns)) return drop(&counts_.jumped, "stamp jumps far ahead of the stream");
      log::warn("IMU stream resumed ", toSec(s.stamp_ns - last_ns_), " s after the last accepted sample");
    }
  }
  jump_.accepted();
  last_ns_ = s.stamp_ns;
  return true;
}

}  // namespace mmlio::pipeline
