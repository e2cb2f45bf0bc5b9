#include "mmlio/eval/plot_evaluation.hpp"

#include <algorithm>
#include <cmath>

#include "mmlio/eval/svg_plot.hpp"

namespace mmlio::eval {
namespace {

constexpr int kWidthPx = 900;
constexpr int kTopViewHeightPx = 640;
constexpr int kErrorHeightPx = 320;

std::vector<Eigen::Vector2d> topView(const std::vector<Eigen::Vector3d>& xyz) {
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(xyz.size());
  for (const Eigen::Vector3d& p : xyz) xy.emplace_back(p.x(), p.y());
  return xy;
}

}  // namespace

std::string topViewSvg(const EvalResult& r) {
  SvgPlot::Config c;
  c.id = "eval-top";
  c.title = "Top view: ATE RMSE " + fixedText(100.0 * r.ate_rmse_m, 2) + " cm, RPE " + fixedText(r.rpe_10m_pct, 2) +
            " % / " + fixedText(r.rpe_10m_deg_per_m, 4) + " deg/m";
  c.x_label = "x [m]";
  c.y_label = "y [m]";
  c.width_px = kWidthPx, c.height_px = kTopViewHeightPx;
  c.equal_aspect = true;
  SvgPlot plot(c);
  plot.line(topView(r.gt_xyz), colors::kGroundTruth, 3.0, "ground truth");
  plot.line(topView(r.est_xyz_aligned), colors::kEstimate, 1.5, "estimate");
  if (!r.gt_xyz.empty()) plot.marker(r.gt_xyz.front().head<2>(), colors::kStart, "start");
  return plot.render();
}

std::string errorOverTimeSvg(const EvalResult& r) {
  SvgPlot::Config c;
  c.id = "eval-error";
  c.title = "Position error after alignment: coverage " + fixedText(100.0 * r.coverage, 1) + " %, end to end " +
            fixedText(100.0 * r.end_to_end_m, 1) + " cm";
  c.x_label = "time since the ground truth's start [s]";
  c.y_label = "error [cm]";
  c.width_px = kWidthPx, c.height_px = kErrorHeightPx;
  SvgPlot plot(c);
  std::vector<Eigen::Vector2d> series;
  double e_high = 0.0;
  for (std::size_t i = 0; i < r.times_s.size() && i < r.errors_m.size(); ++i) {
    series.emplace_back(r.times_s[i], 100.0 * r.errors_m[i]);
    e_high = std::max(e_high, 100.0 * r.errors_m[i]);
  }
  const double t_low = series.empty() ? 0.0 : series.front().x(), t_high = series.empty() ? 1.0 : series.back().x();
  if (t_high > t_low) plot.xRange(t_low, t_high);
  plot.yRange(0.0, e_high > 0.0 ? 1.2 * e_high : 1.0);  // errors are >= 0: the axis starts at 0
  if (std::isfinite(r.ate_rmse_m) && t_high > t_low)
    plot.line({{t_low, 100.0 * r.ate_rmse_m}, {t_high, 100.0 * r.ate_rmse_m}}, colors::kReference, 1.0, "RMSE");
  plot.line(std::move(series), colors::kEstimate, 1.5, "error");
  return plot.render();
}

std::string evaluationFigure(const EvalResult& r, bool html) {
  const std::string top = topViewSvg(r), error = errorOverTimeSvg(r);
  if (html)
    return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>mmlio evaluation</title>"
           "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src 'unsafe-inline'\">"
           "<style>body{font-family:system-ui,sans-serif;margin:20px;color:#1d2127}</style></head><body>\n"
           "<h1>ATE " +
           fixedText(100.0 * r.ate_rmse_m, 2) + " cm over " + fixedText(r.path_length_m, 1) + " m</h1>\n" + top +
           error + "</body></html>\n";
  // One SVG holding both, the error plot below the top view.
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(kWidthPx) + "\" height=\"" +
         std::to_string(kTopViewHeightPx + kErrorHeightPx) +
         "\">\n<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>" + top + "<g transform=\"translate(0," +
         std::to_string(kTopViewHeightPx) + ")\">" + error + "</g></svg>\n";
}

}  // namespace mmlio::eval
