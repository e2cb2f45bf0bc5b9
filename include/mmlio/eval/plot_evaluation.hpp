#pragma once
// Figures of a trajectory evaluation as SVG: a top view (x-y, equal aspect) of ground truth and
// estimate, and the absolute position error over time.

#include <string>

#include "mmlio/eval/evaluation.hpp"

namespace mmlio::eval {

/// Top view of ground truth and the aligned estimate, with the start marked.
std::string topViewSvg(const EvalResult& result);
/// Position error over time with the RMSE as a reference line.
std::string errorOverTimeSvg(const EvalResult& result);
/// Both figures with the metrics: a self-contained HTML page (path ends in .html) or one SVG.
std::string evaluationFigure(const EvalResult& result, bool html);

}  // namespace mmlio::eval
