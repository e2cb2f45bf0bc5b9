#pragma once
// Timestamp association of an estimated trajectory to ground truth.
//
// Each estimate pose is paired with the ground truth interpolated at the estimate's stamp:
// position linearly, rotation by slerp, between the two GT samples that bracket the stamp.
// A pose is associated only when its stamp lies inside the GT time span and the nearer of the
// two bracketing GT samples is at most `max_gap_s` away (so a GT dropout does not get bridged
// by a long interpolation). Estimate poses outside the GT span are never associated.

#include <Eigen/Geometry>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::eval {

/// One estimate pose and the ground truth at the same instant.
struct AssociatedPose {
  Stamp stamp_ns = 0;                                             // the estimate's stamp
  Eigen::Isometry3d T_world_gt = Eigen::Isometry3d::Identity();   // GT, interpolated
  Eigen::Isometry3d T_world_est = Eigen::Isometry3d::Identity();  // estimate, as given
};

/// Pose between `a` and `b` at `stamp_ns` (a.stamp_ns <= stamp_ns <= b.stamp_ns):
/// linear in translation, slerp in rotation.
Eigen::Isometry3d interpolatePose(const StampedPose& a, const StampedPose& b, Stamp stamp_ns);

/// Pairs every estimate pose that falls inside the GT span (see the file comment).
/// Neither input needs to be sorted; the result is in estimate time order.
std::vector<AssociatedPose> associate(const Trajectory& gt, const Trajectory& est, double max_gap_s);

}  // namespace mmlio::eval
