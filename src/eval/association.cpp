#include "mmlio/eval/association.hpp"

#include <algorithm>

namespace mmlio::eval {
namespace {

Trajectory sortedByStamp(const Trajectory& trajectory) {
  Trajectory sorted = trajectory;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp_ns < b.stamp_ns; });
  return sorted;
}

}  // namespace

Eigen::Isometry3d interpolatePose(const StampedPose& a, const StampedPose& b, Stamp stamp_ns) {
  const Stamp span_ns = b.stamp_ns - a.stamp_ns;
  const double u = span_ns > 0 ? static_cast<double>(stamp_ns - a.stamp_ns) / static_cast<double>(span_ns) : 0.0;
  const Eigen::Quaterniond qa(a.T_world_body.rotation());
  const Eigen::Quaterniond qb(b.T_world_body.rotation());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = qa.slerp(u, qb).normalized().toRotationMatrix();
  T.translation() = (1.0 - u) * a.T_world_body.translation() + u * b.T_world_body.translation();
  return T;
}

std::vector<AssociatedPose> associate(const Trajectory& gt_in, const Trajectory& est_in, double max_gap_s) {
  std::vector<AssociatedPose> pairs;
  if (gt_in.empty() || est_in.empty()) return pairs;
  const Trajectory gt = sortedByStamp(gt_in);
  const Trajectory est = sortedByStamp(est_in);
  const Stamp max_gap_ns = fromSec(max_gap_s);
  pairs.reserve(est.size());

  for (const StampedPose& pose : est) {
    const Stamp t = pose.stamp_ns;
    if (t < gt.front().stamp_ns || t > gt.back().stamp_ns) continue;
    // First GT sample with stamp >= t; it exists because t <= gt.back().stamp_ns.
    auto upper =
        std::lower_bound(gt.begin(), gt.end(), t, [](const StampedPose& p, Stamp s) { return p.stamp_ns < s; });
    const StampedPose& b = *upper;
    const StampedPose& a = upper == gt.begin() ? *upper : *(upper - 1);
    const Stamp nearest_ns = std::min(t - a.stamp_ns, b.stamp_ns - t);
    if (nearest_ns > max_gap_ns) continue;
    AssociatedPose pair;
    pair.stamp_ns = t;
    pair.T_world_gt = b.stamp_ns == t ? b.T_world_body : interpolatePose(a, b, t);
    pair.T_world_est = pose.T_world_body;
    pairs.push_back(pair);
  }
  return pairs;
}

}  // namespace mmlio::eval
