#include "mmlio/pipeline/report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "mmlio/core/log.hpp"
#include "mmlio/eval/canvas.hpp"
#include "mmlio/eval/plot2d.hpp"
#include "mmlio/eval/plot_evaluation.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace mmlio::pipeline {
namespace {

// Renders a report object generically so report.md never disagrees with report.json:
// scalars as a bullet list, objects of scalars as two-column tables, objects of objects
// (timing, per-LiDAR figures) as one table with a column per inner key, and a section mixing
// both (degeneracy) as its fields' table followed by one subsection per object.
void renderSection(std::string& md, const std::string& title, const Json& section, int level = 2) {
  md += "\n" + std::string(static_cast<std::size_t>(level), '#') + " " + title + "\n\n";
  bool nested = false, all_nested = !section.members().empty();
  for (const auto& [k, v] : section.members()) {
    nested |= v.isObject();
    all_nested &= v.isObject();
  }
  if (!all_nested) {
    md += "| field | value |\n|---|---|\n";
    for (const auto& [k, v] : section.members())
      if (!v.isObject()) md += "| " + k + " | " + (v.isScalar() ? v.text() : v.dump(-1)) + " |\n";
    if (nested)
      for (const auto& [k, v] : section.members())
        if (v.isObject()) renderSection(md, title + " / " + k, v, level + 1);
    return;
  }
  std::vector<std::string> columns;
  std::set<std::string> seen;
  for (const auto& [k, v] : section.members())
    for (const auto& [ik, iv] : v.members())
      if (seen.insert(ik).second) columns.push_back(ik);
  md += "| " + title + " |";
  for (const auto& c : columns) md += " " + c + " |";
  md += "\n|---|";
  for (std::size_t i = 0; i < columns.size(); ++i) md += "---|";
  md += "\n";
  for (const auto& [k, v] : section.members()) {
    md += "| " + k + " |";
    for (const auto& c : columns) {
      std::string cell;
      for (const auto& [ik, iv] : v.members())
        if (ik == c) cell = iv.isScalar() ? iv.text() : iv.dump(-1);
      md += " " + cell + " |";
    }
    md += "\n";
  }
}

}  // namespace

Json evaluationJson(const eval::EvalResult& ev) {
  Json j = Json::object();
  j["ate_rmse_m"] = ev.ate_rmse_m;
  j["ate_max_m"] = ev.ate_max_m;
  j["ate_rot_rmse_deg"] = ev.ate_rot_rmse_deg;
  j["rpe_10m_pct"] = ev.rpe_10m_pct;
  j["rpe_10m_deg_per_m"] = ev.rpe_10m_deg_per_m;
  j["end_to_end_m"] = ev.end_to_end_m;
  j["path_length_m"] = ev.path_length_m;
  j["end_to_end_pct"] = ev.path_length_m > 0 ? 100.0 * ev.end_to_end_m / ev.path_length_m : 0.0;
  j["coverage"] = ev.coverage;
  j["associated_poses"] = ev.num_associated;
  return j;
}

void plotMapTopView(const std::string& png_path, const std::vector<Point>& map_world,
                    const Trajectory& trajectory, double slice_half_height_m) {
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
  for (const auto& p : trajectory) path.emplace_back(p.T_world_body.translation().x(), p.T_world_body.translation().y());

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

void writeReports(const std::string& dir, Json& report, const Trajectory& trajectory,
                  const std::vector<Point>& map_world, const std::string& gt_path) {
  Json figures = Json::object();
  try {
    plotMapTopView(dir + "map_top.png", map_world, trajectory);
    figures["map_top"] = dir + "map_top.png";
    if (!gt_path.empty()) {
      const eval::EvalResult ev = eval::evaluate(io::readTum(gt_path), trajectory);
      report["evaluation"] = evaluationJson(ev);
      eval::plotEvaluation(ev, dir + "evaluation.png");
      figures["evaluation"] = dir + "evaluation.png";
    }
  } catch (const std::exception& e) {
    log::emit(log::Level::kWarn, "report figures skipped: ", e.what());
  }
  report["figures"] = figures;

  io::writeFileAtomically(dir + "report.json", [&](std::ostream& os) { os << report.dump(2) << '\n'; });

  std::string md = "# mmlio run report\n\n";
  for (const auto& [k, v] : report.members())
    if (v.isScalar()) md += "- **" + k + "**: " + v.text() + "\n";
  for (const auto& [k, v] : report.members())
    if (v.isObject() && k != "figures") renderSection(md, k, v);
  md += "\n## figures\n\n![map top view](map_top.png)\n";
  if (!gt_path.empty()) md += "\n![evaluation](evaluation.png)\n";
  io::writeFileAtomically(dir + "report.md", [&](std::ostream& os) { os << md; });
}

}  // namespace mmlio::pipeline
