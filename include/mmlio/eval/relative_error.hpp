#pragma once
// Relative pose error over fixed path-length segments, KITTI odometry style: drift per
// distance travelled, insensitive to where along the trajectory an error happened.

#include <Eigen/Geometry>
#include <vector>

namespace mmlio::eval {

struct RelativeError {
  double translation_pct = 0.0;     // mean ||relative translation error|| / segment path length, %
  double rotation_deg_per_m = 0.0;  // mean relative rotation angle / segment path length, deg/m
  size_t num_segments = 0;          // 0 when the GT path is shorter than one segment (means are NaN)
};

/// For every start index i, the segment ends at the first j whose GT path length from i reaches
/// `segment_m`. The error of a segment is E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j); its
/// translation and rotation angle are divided by the segment's GT path length (KITTI divides
/// by the nominal length; with dense poses the two differ by the overshoot of the last step).
/// `gt` and `est` are associated pairs of equal length, `est` already in the GT world frame.
RelativeError relativePoseError(const std::vector<Eigen::Isometry3d>& gt, const std::vector<Eigen::Isometry3d>& est,
                                double segment_m);

/// Cumulative GT path length: out[0] = 0, out[k] = sum of ||p[i+1] - p[i]|| for i < k.
std::vector<double> cumulativePathLength(const std::vector<Eigen::Isometry3d>& poses);

}  // namespace mmlio::eval
