#include "mmlio/eval/plot_evaluation.hpp"

#include <cmath>
#include <cstdio>

#include "mmlio/eval/plot2d.hpp"

namespace mmlio::eval {
namespace {

constexpr int kWidthPx = 1000;
constexpr int kTopViewHeightPx = 820;
constexpr int kErrorHeightPx = 360;

std::vector<Eigen::Vector2d> topView(const std::vector<Eigen::Vector3d>& xyz) {
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(xyz.size());
  for (const Eigen::Vector3d& p : xyz) xy.emplace_back(p.x(), p.y());
  return xy;
}

Plot2D topViewPlot(const std::vector<Eigen::Vector3d>& gt_xyz, const std::vector<Eigen::Vector3d>& est_xyz,
                   const std::string& title) {
  Plot2D::Config config;
  config.title = title;
  config.x_label = "x [m]";
  config.y_label = "y [m]";
  config.equal_aspect = true;
  Plot2D plot(config);
  plot.addLine(topView(gt_xyz), colors::kGroundTruth, 3.0, "ground truth");
  plot.addLine(topView(est_xyz), colors::kEstimate, 2.0, "estimate");
  if (!gt_xyz.empty())
    plot.addMarker(Eigen::Vector2d(gt_xyz.front().x(), gt_xyz.front().y()), colors::kGreen, 5.0, "start");
  return plot;
}

std::string format(const char* pattern, double value) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}

}  // namespace

void plotTrajectories(const std::string& png_path, const std::vector<Eigen::Vector3d>& gt_xyz,
                      const std::vector<Eigen::Vector3d>& est_xyz, const std::string& title) {
  Canvas canvas(kWidthPx, kTopViewHeightPx);
  topViewPlot(gt_xyz, est_xyz, title).draw(canvas, 0, 0, kWidthPx, kTopViewHeightPx);
  canvas.savePng(png_path);
}

Canvas renderEvaluation(const EvalResult& r) {
  Canvas canvas(kWidthPx, kTopViewHeightPx + kErrorHeightPx);
  const std::string top_title = "Top view  -  ATE RMSE " + format("%.3f", r.ate_rmse_m) + " m,  RPE " +
                                format("%.2f", r.rpe_10m_pct) + " % " + format("%.4f", r.rpe_10m_deg_per_m) + " deg/m";
  topViewPlot(r.gt_xyz, r.est_xyz_aligned, top_title).draw(canvas, 0, 0, kWidthPx, kTopViewHeightPx);

  Plot2D::Config config;
  config.title = "Position error after alignment  -  coverage " + format("%.1f", 100.0 * r.coverage) +
                 " %,  end-to-end " + format("%.2f", r.end_to_end_m) + " m";
  config.x_label = "time since GT start [s]";
  config.y_label = "error [m]";
  config.legend_corner = Plot2D::Config::Corner::kTopLeft;
  Plot2D errors(config);
  std::vector<Eigen::Vector2d> series;
  series.reserve(r.times_s.size());
  for (size_t i = 0; i < r.times_s.size() && i < r.errors_m.size(); ++i)
    series.emplace_back(r.times_s[i], r.errors_m[i]);
  double t_lo = 0.0, t_hi = 1.0, e_hi = 0.0;
  if (!series.empty()) {
    t_lo = series.front().x();
    t_hi = series.back().x();
  }
  for (double e : r.errors_m) e_hi = std::max(e_hi, e);
  if (t_hi > t_lo) errors.setXRange(t_lo, t_hi);
  // Errors are >= 0, so the axis starts at 0; the headroom above keeps the legend off the curve.
  errors.setYRange(0.0, e_hi > 0.0 ? 1.35 * e_hi : 1.0);
  if (std::isfinite(r.ate_rmse_m) && t_hi > t_lo)
    errors.addLine({{t_lo, r.ate_rmse_m}, {t_hi, r.ate_rmse_m}}, colors::kGrey, 1.0, "RMSE");
  errors.addLine(std::move(series), colors::kEstimate, 2.0, "ATE");
  errors.draw(canvas, 0, kTopViewHeightPx, kWidthPx, kErrorHeightPx);
  return canvas;
}

void plotEvaluation(const EvalResult& result, const std::string& png_path) {
  renderEvaluation(result).savePng(png_path);
}

}  // namespace mmlio::eval
