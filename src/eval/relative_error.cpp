#include "mmlio/eval/relative_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mmlio::eval {

std::vector<double> cumulativePathLength(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<double> length(poses.size(), 0.0);
  for (size_t i = 1; i < poses.size(); ++i)
    length[i] = length[i - 1] + (poses[i].translation() - poses[i - 1].translation()).norm();
  return length;
}

RelativeError relativePoseError(const std::vector<Eigen::Isometry3d>& gt, const std::vector<Eigen::Isometry3d>& est,
                                double segment_m) {
  RelativeError result;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  result.translation_pct = nan;
  result.rotation_deg_per_m = nan;
  if (gt.size() != est.size() || gt.size() < 2 || !(segment_m > 0.0)) return result;

  const std::vector<double> length = cumulativePathLength(gt);
  double sum_translation = 0.0, sum_rotation = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < gt.size(); ++i) {
    // Cumulative length is non-decreasing, so the segment end is a binary search.
    const auto end =
        std::lower_bound(length.begin() + static_cast<std::ptrdiff_t>(i), length.end(), length[i] + segment_m);
    if (end == length.end()) break;  // later starts cannot reach the length either
    const size_t j = static_cast<size_t>(end - length.begin());
    const double travelled_m = length[j] - length[i];
    if (travelled_m <= 0.0) continue;
    const Eigen::Isometry3d delta_gt = gt[i].inverse() * gt[j];
    const Eigen::Isometry3d delta_est = est[i].inverse() * est[j];
    const Eigen::Isometry3d error = delta_gt.inverse() * delta_est;
    const double angle_rad = Eigen::AngleAxisd(error.rotation()).angle();
    sum_translation += error.translation().norm() / travelled_m;
    sum_rotation += angle_rad / travelled_m;
    ++count;
  }
  if (count == 0) return result;
  result.num_segments = count;
  result.translation_pct = 100.0 * sum_translation / static_cast<double>(count);
  result.rotation_deg_per_m = (180.0 / M_PI) * sum_rotation / static_cast<double>(count);
  return result;
}

}  // namespace mmlio::eval
