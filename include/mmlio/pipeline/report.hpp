#pragma once
// The run report: report.json (machine-readable), report.md (for people) and its pictures:
// map_top.png (a horizontal slice of the map around the trajectory, seen from above, with the
// trajectory) and, with ground truth, evaluation.png (top view + error over time).
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/eval/evaluation.hpp"
#include "mmlio/pipeline/run_report.hpp"

namespace mmlio::pipeline {

/// Draws the map slice |z - mean trajectory z| < slice_half_height_m with the trajectory on top.
void plotMapTopView(const std::string& png_path, const std::vector<Point>& map_world, const Trajectory& trajectory,
                    double slice_half_height_m = 0.8);

/// Writes dir/report.json, dir/report.md, dir/map_top.png and (with gt_path) dir/evaluation.png;
/// fills report.figures and (with gt_path) report.evaluation.
void writeReports(const std::string& dir, RunReport& report, const Trajectory& trajectory,
                  const std::vector<Point>& map_world, const std::string& gt_path);

}  // namespace mmlio::pipeline
