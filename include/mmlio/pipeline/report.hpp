#pragma once
// The run report at the edge: report.json (machine-readable), report.md (a summary that points to
// the page) and report.html (the page: summary, 3D map, plots, every field).
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/eval/evaluation.hpp"
#include "mmlio/pipeline/report_html.hpp"
#include "mmlio/pipeline/run_report.hpp"

namespace mmlio::pipeline {

/// Debian's three.js for the page's 3D view, from MMLIO_JS_DIR (environment, else the build's).
HtmlScripts loadHtmlScripts();

/// Writes dir/report.json, dir/report.md, dir/report.html and dir/config_used.yaml; with gt_path,
/// fills report.evaluation first.
void writeReports(const std::string& dir, RunReport& report, const Trajectory& trajectory,
                  const std::vector<Point>& map_world, const std::string& gt_path);

}  // namespace mmlio::pipeline
