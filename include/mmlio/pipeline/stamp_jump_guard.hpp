#pragma once
// One stream's guard against stamps that jump far ahead or far back (IMU samples, one LiDAR's
// scans): a lone corrupt stamp is dropped instead of making everything after it look out of order;
// a stream that stays there (a real gap, a clock that jumped, a bag played again) is confirmed once a
// few stamps agree.
#include "mmlio/core/types.hpp"

namespace mmlio::pipeline {

class StampJumpGuard {
 public:
  /// A stamp more than max_jump_s after the last accepted one has jumped; a run of jumped stamps,
  /// each within run_spacing_s after the one before, is accepted from its `confirmations`-th on.
  StampJumpGuard(double max_jump_s, int confirmations, double run_spacing_s)
      : max_jump_ns_(fromSec(max_jump_s)), run_spacing_ns_(fromSec(run_spacing_s)), confirmations_(confirmations) {}

  bool jumped(Stamp last_ns, Stamp stamp_ns) const { return stamp_ns - last_ns > max_jump_ns_; }
  /// The same backwards: more than max_jump_s before the last accepted stamp.
  bool jumpedBack(Stamp last_ns, Stamp stamp_ns) const { return last_ns - stamp_ns > max_jump_ns_; }
  /// For a jumped stamp (either way): true while it must be held back (dropped).
  bool holdBack(Stamp last_ns, Stamp stamp_ns) {
    const bool continues = run_ > 0 && stamp_ns > run_last_ns_ && stamp_ns - run_last_ns_ < run_spacing_ns_;
    if (!continues) size_ns_ = stamp_ns - last_ns;
    run_ = continues ? run_ + 1 : 1;
    run_last_ns_ = stamp_ns;
    return run_ < confirmations_;
  }
  /// A stamp was accepted: any run of jumped stamps is over.
  void accepted() { run_ = 0; }
  /// A run of jumped stamps is being held back, its first `pendingJumpNs()` after the last accepted
  /// one (negative: before it).
  bool pending() const { return run_ > 0; }
  /// The run being held back is long enough to be believed.
  bool confirmed() const { return run_ >= confirmations_; }
  Stamp pendingJumpNs() const { return size_ns_; }
  int confirmations() const { return confirmations_; }

 private:
  Stamp max_jump_ns_, run_spacing_ns_;
  int confirmations_;
  int run_ = 0;            // consecutive jumped stamps so far
  Stamp run_last_ns_ = 0;  // the latest of them
  Stamp size_ns_ = 0;      // how far the run's first lay after the last accepted stamp
};

}  // namespace mmlio::pipeline
