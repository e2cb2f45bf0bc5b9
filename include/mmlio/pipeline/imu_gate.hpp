#pragma once
// IMU samples are checked before they reach the estimator. One corrupt value (a NaN, or random
// bytes read as 1.8e109 m/s^2) would otherwise poison every pose after it, and one stamp far in the
// future would make every later sample look out of order. Dropped and counted: non-finite values,
// values beyond any MEMS IMU's range, stamps not after the last accepted sample (duplicates, out of
// order), and stamps that jump far ahead of it (kept out until the stream comes back near it, or
// stays there for a few samples) or far back (kept out: only the whole stream's time base going back
// together, which OnlinePipeline checks, lets them in).
// The first drop of each kind is logged; the report carries the counts.
#include <cstddef>
#include <limits>

#include "mmlio/core/types.hpp"
#include "mmlio/pipeline/stamp_jump_guard.hpp"

namespace mmlio::pipeline {

class ImuGate {
 public:
  struct Config {
    double max_acc_m_s2 = 50.0 * 9.80665;  // 50 g: beyond every MEMS IMU's range
    double max_gyro_rad_s = 50.0;
    double max_jump_s = 1.0;      // a later stamp further ahead than this is rejected ...
    int jump_confirmations = 20;  // ... unless this many samples in a row agree (a real gap)
  };
  struct Counts {
    std::size_t non_finite = 0, out_of_range = 0, out_of_order = 0, jumped = 0;
    // Where in the stream drops happened: the last accepted stamp at the first and the last drop
    // (a dropped sample's own stamp may be the garbage that got it dropped).
    Stamp first_at_ns = 0, last_at_ns = 0;
    std::size_t total() const { return non_finite + out_of_range + out_of_order + jumped; }
  };

  ImuGate() = default;
  explicit ImuGate(Config config) : cfg_(config) {}

  /// True if the sample may reach the estimator.
  bool accept(const ImuSample& sample);
  const Counts& counts() const { return counts_; }
  const Config& config() const { return cfg_; }
  /// Stamp of the last accepted sample (min() before the first).
  Stamp lastNs() const { return last_ns_; }
  /// The stream's time base moved back by delta (see OnlinePipeline): later stamps arrive shifted.
  void shiftBack(Stamp delta_ns) { last_ns_ -= delta_ns; }
  /// The samples just dropped have stayed far before the last accepted one long enough to be
  /// believed: the IMU's clock went back (a bag played again), not one corrupt stamp.
  bool wentBack() const { return back_.confirmed(); }

 private:
  Config cfg_;
  Counts counts_;
  Stamp last_ns_ = std::numeric_limits<Stamp>::min();
  StampJumpGuard jump_{cfg_.max_jump_s, cfg_.jump_confirmations, cfg_.max_jump_s};
  StampJumpGuard back_{cfg_.max_jump_s, cfg_.jump_confirmations, cfg_.max_jump_s};
};

}  // namespace mmlio::pipeline
