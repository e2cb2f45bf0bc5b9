#include "mmlio/eval/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <sstream>

#include "mmlio/core/error.hpp"
#include "mmlio/eval/alignment.hpp"
#include "mmlio/eval/association.hpp"
#include "mmlio/eval/relative_error.hpp"

namespace mmlio::eval {
namespace {

std::pair<Stamp, Stamp> timeSpan(const Trajectory& trajectory) {
  Stamp lo = trajectory.front().stamp_ns, hi = lo;
  for (const StampedPose& pose : trajectory) {
    lo = std::min(lo, pose.stamp_ns);
    hi = std::max(hi, pose.stamp_ns);
  }
  return {lo, hi};
}

/// Distance between the positions of the earliest and the latest pose.
double endToEnd(const Trajectory& trajectory) {
  const auto by_stamp = [](const StampedPose& a, const StampedPose& b) { return a.stamp_ns < b.stamp_ns; };
  const auto first = std::min_element(trajectory.begin(), trajectory.end(), by_stamp);
  const auto last = std::max_element(trajectory.begin(), trajectory.end(), by_stamp);
  return (last->T_world_body.translation() - first->T_world_body.translation()).norm();
}

std::string spanText(const std::pair<Stamp, Stamp>& span) {
  char text[96];
  std::snprintf(text, sizeof(text), "[%.3f, %.3f] s", toSec(span.first), toSec(span.second));
  return text;
}

void appendNumber(std::ostringstream& os, const char* key, double value, bool first = false) {
  os << (first ? "" : ",") << '"' << key << "\":";
  if (!std::isfinite(value)) {
    os << "null";
    return;
  }
  char text[40];
  std::snprintf(text, sizeof(text), "%.9g", value);
  os << text;
}

void appendCount(std::ostringstream& os, const char* key, size_t value) { os << ",\"" << key << "\":" << value; }

}  // namespace

EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options) {
  if (gt.empty()) throw Error("evaluate: the ground-truth trajectory is empty");
  if (est.empty()) throw Error("evaluate: the estimated trajectory is empty");
  const std::vector<AssociatedPose> pairs = associate(gt, est, options.max_gap_s);
  const auto gt_span = timeSpan(gt);
  if (pairs.size() < 3) {
    std::ostringstream os;
    os << "evaluate: only " << pairs.size() << " estimate poses fall within " << options.max_gap_s
       << " s of ground truth (need 3); GT spans " << spanText(gt_span) << ", estimate spans "
       << spanText(timeSpan(est)) << " -- check that both use the same clock (bag time vs. wall "
       << "time, time offsets) or raise --max-gap";
    throw Error(os.str());
  }

  EvalResult result;
  result.num_associated = pairs.size();
  std::vector<Eigen::Vector3d> p_est(pairs.size());
  result.gt_xyz.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    result.gt_xyz[i] = pairs[i].T_world_gt.translation();
    p_est[i] = pairs[i].T_world_est.translation();
  }

  const Alignment alignment = options.align ? alignUmeyama(result.gt_xyz, p_est, options.scale) : Alignment{};
  result.T_gt_est = alignment.T_gt_est;
  result.scale = alignment.scale;

  std::vector<Eigen::Isometry3d> gt_poses(pairs.size()), est_poses(pairs.size());
  result.est_xyz_aligned.resize(pairs.size());
  result.errors_m.resize(pairs.size());
  result.gt_start_s = toSec(gt_span.first);
  result.times_s.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    gt_poses[i] = pairs[i].T_world_gt;
    est_poses[i] = alignment.apply(pairs[i].T_world_est);
    result.est_xyz_aligned[i] = est_poses[i].translation();
    result.errors_m[i] = (result.est_xyz_aligned[i] - result.gt_xyz[i]).norm();
    result.times_s[i] = toSec(pairs[i].stamp_ns - gt_span.first);
  }

  const std::vector<double>& errors = result.errors_m;
  const double n = static_cast<double>(errors.size());
  result.ate_rmse_m =
      std::sqrt(std::accumulate(errors.begin(), errors.end(), 0.0, [](double s, double e) { return s + e * e; }) / n);
  result.ate_mean_m = std::accumulate(errors.begin(), errors.end(), 0.0) / n;
  result.ate_max_m = *std::max_element(errors.begin(), errors.end());
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const size_t mid = sorted.size() / 2;
  result.ate_median_m = sorted.size() % 2 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  // Attitude error and map frame: positions alone leave the rotation about a straight walk's axis
  // undetermined (a corridor, the office's back-and-forth), so this alignment also matches the tips
  // of each pose's unit axes.
  std::vector<Eigen::Vector3d> gt_tips, est_tips;
  for (size_t i = 0; i < pairs.size(); ++i) {
    for (int a = -1; a < 3; ++a) {
      const Eigen::Vector3d u =
          a < 0 ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(Eigen::Vector3d::Unit(a));
      gt_tips.push_back(pairs[i].T_world_gt * u);
      est_tips.push_back(pairs[i].T_world_est * u);
    }
  }
  result.T_gt_est_pose =
      options.align ? alignUmeyama(gt_tips, est_tips, false).T_gt_est : Eigen::Isometry3d::Identity();
  // ... and against gravity, unaligned: how far "up" in the body differs, how far the climb.
  double rot_sq = 0.0, tilt_sq = 0.0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const Eigen::Matrix3d R_est = result.T_gt_est_pose.linear() * pairs[i].T_world_est.linear();
    const double a = Eigen::AngleAxisd(pairs[i].T_world_gt.linear().transpose() * R_est).angle() * 180.0 / M_PI;
    rot_sq += a * a;
    const Eigen::Vector3d up_gt = pairs[i].T_world_gt.linear().transpose() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d up_est = pairs[i].T_world_est.linear().transpose() * Eigen::Vector3d::UnitZ();
    const double tilt_deg = std::atan2(up_gt.cross(up_est).norm(), up_gt.dot(up_est)) * 180.0 / M_PI;
    tilt_sq += tilt_deg * tilt_deg;
    result.tilt_max_deg = std::max(result.tilt_max_deg, tilt_deg);
    const double climbed_est = p_est[i].z() - p_est.front().z(),
                 climbed_gt = result.gt_xyz[i].z() - result.gt_xyz.front().z();
    result.height_error_max_m =
        std::max(result.height_error_max_m, std::abs(alignment.scale * climbed_est - climbed_gt));
  }
  result.ate_rot_rmse_deg = std::sqrt(rot_sq / n);
  result.tilt_rmse_deg = std::sqrt(tilt_sq / n);

  const RelativeError rpe = relativePoseError(gt_poses, est_poses, options.segment_m);
  result.rpe_10m_pct = rpe.translation_pct;
  result.rpe_10m_deg_per_m = rpe.rotation_deg_per_m;
  result.rpe_num_segments = rpe.num_segments;

  result.end_to_end_m = alignment.scale * endToEnd(est);
  result.gt_end_to_end_m = endToEnd(gt);
  const double gt_duration_s = toSec(gt_span.second - gt_span.first);
  const double est_duration_s = toSec(pairs.back().stamp_ns - pairs.front().stamp_ns);
  result.coverage = gt_duration_s > 0.0 ? est_duration_s / gt_duration_s : 0.0;
  result.path_length_m = cumulativePathLength(gt_poses).back();
  return result;
}

std::string toJsonLine(const EvalResult& r) {
  std::ostringstream os;
  os << '{';
  appendNumber(os, "ate_rmse_m", r.ate_rmse_m, true);
  appendNumber(os, "ate_mean_m", r.ate_mean_m);
  appendNumber(os, "ate_median_m", r.ate_median_m);
  appendNumber(os, "ate_max_m", r.ate_max_m);
  appendNumber(os, "ate_rot_rmse_deg", r.ate_rot_rmse_deg);
  appendNumber(os, "rpe_10m_pct", r.rpe_10m_pct);
  appendNumber(os, "rpe_10m_deg_per_m", r.rpe_10m_deg_per_m);
  appendCount(os, "rpe_num_segments", r.rpe_num_segments);
  appendNumber(os, "end_to_end_m", r.end_to_end_m);
  appendNumber(os, "gt_end_to_end_m", r.gt_end_to_end_m);
  appendNumber(os, "coverage", r.coverage);
  appendCount(os, "num_associated", r.num_associated);
  appendNumber(os, "path_length_m", r.path_length_m);
  appendNumber(os, "scale", r.scale);
  appendNumber(os, "tilt_rmse_deg", r.tilt_rmse_deg);
  appendNumber(os, "tilt_max_deg", r.tilt_max_deg);
  appendNumber(os, "height_error_max_m", r.height_error_max_m);
  os << '}';
  return os.str();
}

}  // namespace mmlio::eval
