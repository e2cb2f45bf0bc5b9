#pragma once
// Figures of a trajectory evaluation, as PNG: a top view (x-y, equal aspect) of ground truth
// and estimate, and the absolute position error over time.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mmlio/eval/canvas.hpp"
#include "mmlio/eval/evaluation.hpp"

namespace mmlio::eval {

/// Top view of GT (colors::kGroundTruth) and estimate (colors::kEstimate) with start markers.
void plotTrajectories(const std::string& png_path, const std::vector<Eigen::Vector3d>& gt_xyz,
                      const std::vector<Eigen::Vector3d>& est_xyz, const std::string& title);

/// The two-panel evaluation figure (top view over error-vs-time, metrics in the titles), in memory.
Canvas renderEvaluation(const EvalResult& result);
/// renderEvaluation written to `png_path`.
void plotEvaluation(const EvalResult& result, const std::string& png_path);

}  // namespace mmlio::eval
