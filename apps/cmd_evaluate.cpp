// `mmlio evaluate`: compares an estimated TUM trajectory with ground truth (ATE, RPE per 10 m,
// end-to-end error, coverage), optionally writing the evaluation figure.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/eval/evaluation.hpp"
#include "mmlio/eval/plot_evaluation.hpp"
#include "mmlio/io/pcd_io.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/sim/map_score.hpp"
#include "mmlio/sim/scenarios.hpp"
#include "mmlio/sim/scene.hpp"

namespace mmlio::apps {
namespace {

struct EvaluateArgs {
  std::string gt_path;
  std::string est_path;
  std::string plot_path;
  bool json = false;
  bool no_align = false;
  bool scale = false;
  std::string map_path;
  std::string map_scenario;
  std::string off_surface_path;
  std::string removed_path;
  std::string reference_map_path;
  std::string reference_est_path;
  std::vector<std::string> frame_from;  // GT EST: the frame fixed by aligning another run (localization)
  eval::EvalOptions options;
};

/// How far the points of a map lie from the true static surfaces of a simulated scene, after the
/// trajectory alignment (sim::scoreMap), and how much of them it keeps: against the static surface
/// only the removed points cover, and against the map of a run without people.
struct MapSharpness {
  sim::MapScore score;
  // Static surface voxels only the removed points (map_dynamic.pcd) cover: what the dynamic
  // handling took out of the map, as opposed to what people hid from every view. -1: not asked.
  long static_voxels_removed = -1;
  double static_kept = -1.0;  // sim::staticPointsKept against the reference map; -1: not asked
};

/// A map to compare against, in the ground-truth frame through its own run's alignment.
struct ReferenceMap {
  std::string path;
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();
};

std::vector<Eigen::Vector3d> transformed(const std::vector<Point>& points, const Eigen::Isometry3d& T_gt_est) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const Point& p : points) out.push_back(T_gt_est * p.xyz.cast<double>());
  return out;
}

MapSharpness mapSharpness(const std::string& map_path, const std::string& scenario, const Eigen::Isometry3d& T_gt_est,
                          const std::string& off_surface_path, const std::string& removed_path,
                          const ReferenceMap& reference) {
  const sim::Scene scene(sim::makeScenario(scenario).boxes);
  const std::vector<Point> points = io::readPcd(map_path);
  if (points.empty()) throw Error("evaluate: map '" + map_path + "' has no points");
  const std::vector<Eigen::Vector3d> map = transformed(points, T_gt_est);
  MapSharpness s;
  s.score = sim::scoreMap(scene, map);
  if (!off_surface_path.empty()) {
    std::vector<Point> off;
    for (std::size_t i : s.score.off_surface) {
      off.push_back(points[i]);
      off.back().xyz = map[i].cast<float>();
    }
    io::writePcdBinary(off_surface_path, off);
  }
  if (!removed_path.empty()) {
    FlatKeySet covered, only_removed;
    for (const Eigen::Vector3d& p : s.score.on_surface) covered.insert(sim::surfaceVoxelOf(p));
    for (const Eigen::Vector3d& w : transformed(io::readPcd(removed_path), T_gt_est)) {
      if (scene.distanceToSurface(w) > sim::kOnSurfaceM) continue;
      const std::uint64_t key = sim::surfaceVoxelOf(w);
      if (!covered.contains(key)) only_removed.insert(key);
    }
    s.static_voxels_removed = static_cast<long>(only_removed.size());
  }
  if (!reference.path.empty()) {
    const sim::MapScore ref = sim::scoreMap(scene, transformed(io::readPcd(reference.path), reference.T_gt_est));
    if (ref.on_surface.empty())
      throw Error("evaluate: reference map '" + reference.path + "' has no static-surface points");
    s.static_kept = sim::staticPointsKept(s.score.on_surface, ref.on_surface);
  }
  return s;
}

Trajectory readNonEmptyTum(const std::string& path, const char* what) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw Error(std::string(what) + " trajectory '" + path + "' does not exist or is not a file");
  Trajectory trajectory = io::readTum(path);
  if (trajectory.empty()) throw Error(std::string(what) + " trajectory '" + path + "' has no poses");
  return trajectory;
}

std::string row(const char* name, double value, const char* unit, const char* format = "%.4f") {
  char number[64];
  if (std::isfinite(value))
    std::snprintf(number, sizeof(number), format, value);
  else
    std::snprintf(number, sizeof(number), "n/a");
  char line[160];
  std::snprintf(line, sizeof(line), "  %-22s %12s%s%s\n", name, number, *unit ? " " : "", unit);
  return line;
}

void printTable(const eval::EvalResult& r, const EvaluateArgs& args) {
  std::string out;
  out += "trajectory evaluation\n";
  out += "  ground truth           " + args.gt_path + "\n";
  out += "  estimate               " + args.est_path + "\n";
  out += row("associated poses", static_cast<double>(r.num_associated), "", "%.0f");
  out += row("coverage", 100.0 * r.coverage, "% of GT time span", "%.1f");
  out += row("GT path length", r.path_length_m, "m", "%.1f");
  out += std::string("  alignment              ") +
         (!args.frame_from.empty() ? "none (frame fixed by --frame-from)"
          : args.no_align          ? "none"
                                   : (args.scale ? "Umeyama SE(3) + scale" : "Umeyama SE(3)")) +
         "\n";
  if (args.scale) out += row("scale", r.scale, "");
  out += row("ATE RMSE", r.ate_rmse_m, "m");
  out += row("ATE mean", r.ate_mean_m, "m");
  out += row("ATE median", r.ate_median_m, "m");
  out += row("ATE max", r.ate_max_m, "m");
  out += row("ATE rotation RMSE", r.ate_rot_rmse_deg, "deg");
  char segment[64];
  std::snprintf(segment, sizeof(segment), "RPE %g m translation", args.options.segment_m);
  out += row(segment, r.rpe_10m_pct, "%", "%.3f");
  std::snprintf(segment, sizeof(segment), "RPE %g m rotation", args.options.segment_m);
  out += row(segment, r.rpe_10m_deg_per_m, "deg/m", "%.5f");
  out += row("RPE segments", static_cast<double>(r.rpe_num_segments), "", "%.0f");
  out += row("end-to-end (estimate)", r.end_to_end_m, "m");
  out += row("end-to-end (GT)", r.gt_end_to_end_m, "m");
  out += "  against gravity, not aligned (GT's z must be up):\n";
  out += row("tilt RMSE", r.tilt_rmse_deg, "deg", "%.3f");
  out += row("tilt max", r.tilt_max_deg, "deg", "%.3f");
  out += row("height error max", r.height_error_max_m, "m");
  std::cout << out;
}

void runEvaluate(const EvaluateArgs& args) {
  eval::EvalOptions options = args.options;
  options.align = !args.no_align;
  options.scale = args.scale;
  if (!(options.max_gap_s > 0.0))
    throw Error("evaluate: --max-gap must be positive, got " + std::to_string(options.max_gap_s));
  if (!(options.segment_m > 0.0)) throw Error("evaluate: --segment must be positive");
  if (args.no_align && args.scale) throw Error("evaluate: --scale needs alignment; drop --no-align");

  const Trajectory gt = readNonEmptyTum(args.gt_path, "ground-truth");
  Trajectory est = readNonEmptyTum(args.est_path, "estimated");
  if (!args.frame_from.empty()) {
    // A localized trajectory is in the map frame of the run that made the map: that run, aligned
    // once onto its own truth, fixes the frame; the localized poses are then compared as they are.
    if (args.no_align || args.scale) throw Error("evaluate: --frame-from fixes the frame; drop --no-align / --scale");
    eval::EvalOptions once = options;
    const Eigen::Isometry3d T_gt_map = eval::evaluate(readNonEmptyTum(args.frame_from[0], "frame ground-truth"),
                                                      readNonEmptyTum(args.frame_from[1], "frame estimate"), once)
                                           .T_gt_est;
    for (StampedPose& p : est) p.T_world_body = T_gt_map * p.T_world_body;
    options.align = false;
  }
  const eval::EvalResult result = eval::evaluate(gt, est, options);
  if (!args.plot_path.empty()) {
    const bool html = std::filesystem::path(args.plot_path).extension() == ".html";
    io::writeFileAtomically(args.plot_path, [&](std::ostream& os) { os << eval::evaluationFigure(result, html); });
  }

  ReferenceMap reference;
  if (!args.reference_map_path.empty()) {
    reference.path = args.reference_map_path;
    reference.T_gt_est =
        eval::evaluate(gt, readNonEmptyTum(args.reference_est_path, "reference"), options).T_gt_est_pose;
  }
  MapSharpness map;
  if (!args.map_path.empty())
    map = mapSharpness(args.map_path, args.map_scenario, result.T_gt_est_pose, args.off_surface_path, args.removed_path,
                       reference);
  if (args.json) {
    std::string line = eval::toJsonLine(result);
    if (!args.map_path.empty() && !line.empty() && line.back() == '}') {
      char extra[400];
      char kept[64] = "";
      if (map.static_kept >= 0.0) std::snprintf(kept, sizeof(kept), ", \"map_static_kept\": %.5f", map.static_kept);
      std::snprintf(
          extra, sizeof(extra),
          ", \"map_points\": %zu, \"map_median_m\": %.5f, \"map_p90_m\": %.5f, \"map_off_surface_fraction\": %.5f, "
          "\"map_static_voxels\": %zu%s%s}",
          map.score.points, map.score.median_m, map.score.p90_m, map.score.off_surface_fraction,
          map.score.static_voxels,
          map.static_voxels_removed < 0
              ? ""
              : (", \"map_static_voxels_removed\": " + std::to_string(map.static_voxels_removed)).c_str(),
          kept);
      line.pop_back();
      line += extra;
    }
    std::cout << line << '\n';
  } else {
    printTable(result, args);
    if (!args.map_path.empty()) {
      const sim::MapScore& score = map.score;
      std::cout << row("map points", static_cast<double>(score.points), "", "%.0f");
      std::cout << row("map to true surfaces", score.median_m, "m median");
      std::cout << row("map to true surfaces", score.p90_m, "m 90th percentile");
      std::cout << row("map off surfaces", 100.0 * score.off_surface_fraction, "% of points > 10 cm", "%.2f");
      std::cout << row("static surface voxels", static_cast<double>(score.static_voxels), "(10 cm)", "%.0f");
      if (map.static_voxels_removed >= 0)
        std::cout << row("... only removed", static_cast<double>(map.static_voxels_removed), "(only --removed covers)",
                         "%.0f");
      if (map.static_kept >= 0.0)
        std::cout << row("static points kept", 100.0 * map.static_kept, "% of the reference map's (within 10 cm)",
                         "%.1f");
    }
    if (!args.plot_path.empty()) std::cout << "  plot                   " << args.plot_path << '\n';
  }
}

}  // namespace

void registerEvaluateCommand(CLI::App& app) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate",
      "Compare an estimated trajectory with ground truth (TUM files): ATE, RPE per 10 m, end-to-end, coverage");
  cmd->add_option("--gt", args->gt_path, "Ground-truth trajectory, TUM format")->required();
  cmd->add_option("--est", args->est_path, "Estimated trajectory, TUM format")->required();
  cmd->add_option(
      "--plot", args->plot_path,
      "Write the evaluation figures (top view, error over time) to this SVG, or an HTML page if it ends in .html");
  cmd->add_flag("--json", args->json, "Print exactly one line of JSON instead of the table");
  cmd->add_option("--max-gap", args->options.max_gap_s,
                  "Max distance from an estimate stamp to the nearest GT sample, s")
      ->capture_default_str();
  cmd->add_option("--segment", args->options.segment_m, "RPE segment length along the GT path, m")
      ->capture_default_str();
  cmd->add_flag("--no-align", args->no_align, "Compare in the raw frames (no Umeyama alignment)");
  cmd->add_option("--frame-from", args->frame_from,
                  "GT EST: fix the frame once by aligning EST (e.g. the mapping run) onto GT, then compare --est "
                  "(e.g. a localization in its map) without further alignment")
      ->expected(2)
      ->check(CLI::ExistingFile);
  cmd->add_flag("--scale", args->scale, "Also estimate a scale in the alignment (Sim(3))");
  cmd->add_option("--map", args->map_path,
                  "Also score this map (PCD, estimate frame) against the true surfaces of --scenario (simulated runs)");
  cmd->add_option("--scenario", args->map_scenario, "Simulated scenario whose surfaces --map is scored against")
      ->check(CLI::IsMember(sim::scenarioNames()));
  cmd->get_option("--map")->needs(cmd->get_option("--scenario"));
  cmd->add_option(
         "--off-surface", args->off_surface_path,
         "With --map: write its points farther than 10 cm from every true surface to this PCD (ground-truth frame)")
      ->needs(cmd->get_option("--map"));
  cmd->add_option(
         "--removed", args->removed_path,
         "With --map: the points the run removed (map_dynamic.pcd); counts the static surface voxels only they "
         "cover (what the dynamic handling took out of the map)")
      ->check(CLI::ExistingFile)
      ->needs(cmd->get_option("--map"));
  cmd->add_option(
         "--reference-map", args->reference_map_path,
         "With --map: the map of the same scene run without people (PCD, its run's estimate frame); reports the "
         "share of its static-surface points that --map still has within 10 cm")
      ->check(CLI::ExistingFile)
      ->needs(cmd->get_option("--map"));
  cmd->add_option("--reference-est", args->reference_est_path,
                  "The trajectory of --reference-map's run (TUM), to align that map to --gt")
      ->check(CLI::ExistingFile);
  cmd->get_option("--reference-map")->needs(cmd->get_option("--reference-est"));
  cmd->get_option("--reference-est")->needs(cmd->get_option("--reference-map"));
  cmd->callback([args] { runEvaluate(*args); });
}

}  // namespace mmlio::apps
