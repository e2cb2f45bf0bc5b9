#include "mmlio/pipeline/report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "mmlio/core/log.hpp"
#include "mmlio/eval/canvas.hpp"
#include "mmlio/eval/plot2d.hpp"
#include "mmlio/eval/plot_evaluation.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace mmlio::pipeline {

void plotMapTopView(const std::string& png_path, const std::vector<Point>& map_world, const Trajectory& trajectory,
                    double slice_half_height_m) {
  double mean_z = 0.0;
  for (const auto& p : trajectory) mean_z += p.T_world_body.translation().z();
  if (!trajectory.empty()) mean_z /= trajectory.size();

  std::vector<Eigen::Vector2d> xy;
  std::vector<eval::Rgb> colors;
  const std::size_t stride = std::max<std::size_t>(1, map_world.size() / 400000);
  for (std::size_t i = 0; i < map_world.size(); i += stride) {
    const Point& p = map_world[i];
    const double dz = p.xyz.z() - mean_z;
    if (std::abs(dz) > slice_half_height_m) continue;
    // Darker = higher, so furniture stands out from the walls' lower parts.
    const auto g = static_cast<std::uint8_t>(170 - 120 * (dz + slice_half_height_m) / (2 * slice_half_height_m));
    xy.emplace_back(p.xyz.x(), p.xyz.y());
    colors.push_back({g, g, g});
  }
  std::vector<Eigen::Vector2d> path;
  for (const auto& p : trajectory)
    path.emplace_back(p.T_world_body.translation().x(), p.T_world_body.translation().y());

  eval::Plot2D::Config pc;
  pc.title = "map slice (|z - z_traj| < " + std::to_string(slice_half_height_m).substr(0, 3) + " m) and trajectory";
  pc.x_label = "x [m]";
  pc.y_label = "y [m]";
  pc.equal_aspect = true;
  eval::Plot2D plot(pc);
  plot.addScatter(xy, colors, 0.0);
  if (!path.empty()) {
    plot.addLine(path, eval::colors::kEstimate, 2.0, "trajectory");
    plot.addMarker(path.front(), eval::colors::kEstimate, 5.0, "start");
  }
  eval::Canvas canvas(1600, 1200);
  plot.draw(canvas, 0, 0, canvas.width(), canvas.height());
  canvas.savePng(png_path);
}

void writeReports(const std::string& dir, RunReport& report, const Trajectory& trajectory,
                  const std::vector<Point>& map_world, const std::string& gt_path) {
  report.figures.clear();
  try {
    plotMapTopView(dir + "map_top.png", map_world, trajectory);
    report.figures["map_top"] = dir + "map_top.png";
    if (!gt_path.empty()) {
      report.evaluation = eval::evaluate(io::readTum(gt_path), trajectory);
      eval::plotEvaluation(*report.evaluation, dir + "evaluation.png");
      report.figures["evaluation"] = dir + "evaluation.png";
    }
  } catch (const std::exception& e) {
    log::emit(log::Level::kWarn, "report figures skipped: ", e.what());
  }
  if (!report.run.config_yaml.empty())
    io::writeFileAtomically(dir + "config_used.yaml", [&](std::ostream& os) {
      os << "# The effective config of this run (mmlio " << report.run.mmlio_version << ", " << report.run.commit
         << "; extrinsics from " << report.run.calibration << "): mmlio run BAG --config config_used.yaml\n"
         << report.run.config_yaml;
    });
  io::writeFileAtomically(dir + "report.json", [&](std::ostream& os) { os << toJson(report).dump(2) << '\n'; });
  io::writeFileAtomically(dir + "report.md", [&](std::ostream& os) { os << toMarkdown(report); });
}

}  // namespace mmlio::pipeline
