#pragma once
// The poses of a long run, one per sweep: stored as 3x4 matrices in fixed-size blocks, so the log
// grows a block at a time, never copying itself to grow as a vector does (which holds up to twice
// its size meanwhile), at 104 bytes a pose instead of a StampedPose's 136. The poses read back bit
// for bit as they went in.
#include <Eigen/Core>
#include <deque>

#include "mmlio/core/types.hpp"

namespace mmlio {

class PoseLog {
 public:
  void push_back(const StampedPose& pose) {
    entries_.push_back({pose.stamp_ns, pose.T_world_body.matrix().topRows<3>()});
  }
  std::size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  StampedPose operator[](std::size_t i) const { return expand(entries_[i]); }
  StampedPose front() const { return expand(entries_.front()); }
  StampedPose back() const { return expand(entries_.back()); }
  /// f(StampedPose) for every pose, oldest first.
  template <class F> void forEach(F&& f) const {
    for (const Entry& e : entries_) f(expand(e));
  }
  Trajectory trajectory() const {
    Trajectory out;
    out.reserve(entries_.size());
    forEach([&out](const StampedPose& p) { out.push_back(p); });
    return out;
  }

 private:
  struct Entry {
    Stamp stamp_ns;
    Eigen::Matrix<double, 3, 4> top;  // the isometry's rows above (0 0 0 1)
  };
  static StampedPose expand(const Entry& e) {
    StampedPose p{e.stamp_ns, Eigen::Isometry3d::Identity()};
    p.T_world_body.matrix().topRows<3>() = e.top;
    return p;
  }
  std::deque<Entry> entries_;
};

}  // namespace mmlio
