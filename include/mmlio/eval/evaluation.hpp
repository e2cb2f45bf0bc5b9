#pragma once
// Trajectory evaluation against ground truth: association, alignment, absolute trajectory
// error (ATE), relative pose error over path-length segments (RPE), end-to-end error and
// coverage. Pure computation; reading files and drawing live elsewhere.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::eval {

struct EvalOptions {
  double max_gap_s = 0.05;  // max distance from an estimate stamp to the nearest GT sample, s
  double segment_m = 10.0;  // RPE segment length along the GT path, m
  bool align = true;        // Umeyama-align the estimate onto GT before ATE (else identity)
  bool scale = false;       // also estimate a scale in the alignment (monocular-style)
};

struct EvalResult {
  size_t num_associated = 0;  // estimate poses paired with (interpolated) GT
  double ate_rmse_m = 0.0;    // absolute position error after alignment: RMSE
  double ate_mean_m = 0.0;
  double ate_median_m = 0.0;
  double ate_max_m = 0.0;
  double ate_rot_rmse_deg = 0.0;   // attitude error (RMSE of the rotation angle) after T_gt_est_pose
  double rpe_10m_pct = 0.0;        // RPE translation over `segment_m` segments, % (NaN if path too short)
  double rpe_10m_deg_per_m = 0.0;  // RPE rotation, deg/m (NaN if path too short)
  size_t rpe_num_segments = 0;
  double end_to_end_m = 0.0;     // ||p_est(last) - p_est(first)|| over the whole estimate (times scale)
  double gt_end_to_end_m = 0.0;  // the same for the whole GT, for reference
  double coverage = 0.0;         // (last - first associated estimate stamp) / GT time span
  double path_length_m = 0.0;    // GT path length over the associated poses
  double scale = 1.0;            // alignment scale (1 unless EvalOptions::scale)
  // Against gravity, before any alignment (which turns a tilted run level and hides it): both worlds
  // must have z up, as mmlio's estimate has. The tilt is the angle between the body's "up" in the
  // estimate and in GT; the height error compares each pose's climb since the first associated one.
  double tilt_rmse_deg = 0.0;
  double tilt_max_deg = 0.0;
  double height_error_max_m = 0.0;

  double gt_start_s = 0.0;                                     // stamp of the first GT pose, s
  std::vector<double> times_s;                                 // per associated pose: seconds since the first GT pose
  std::vector<double> errors_m;                                // per associated pose: position error after alignment
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();  // estimate world -> GT world (positions)
  Eigen::Isometry3d T_gt_est_pose = Eigen::Isometry3d::Identity();  // ... from positions and attitudes
  std::vector<Eigen::Vector3d> gt_xyz;                              // associated GT positions
  std::vector<Eigen::Vector3d> est_xyz_aligned;                     // associated estimate positions, aligned
};

/// Evaluates `est` against `gt`. Throws mmlio::Error when fewer than 3 poses associate
/// (the message gives both time spans, since the usual cause is a clock or offset mismatch).
EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options = {});

/// One line of JSON with the scalar metrics (non-finite values become null).
std::string toJsonLine(const EvalResult& result);

}  // namespace mmlio::eval
