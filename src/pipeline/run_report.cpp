#include "mmlio/pipeline/run_report.hpp"

#include "mmlio/eval/svg_plot.hpp"

#include <vector>

namespace mmlio::pipeline {
namespace {

Json vec3(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

Json refinedCalibrationJson(const std::vector<RunReport::RefinedCalibration>& calibrations) {
  Json refined = Json::object();
  for (const RunReport::RefinedCalibration& c : calibrations) {
    const estimator::LidarCalibrationEstimate& e = c.last;
    Json series = Json::array();
    for (const auto& s : c.series)
      series.push_back({{"t_s", s.t_s},
                        {"time_offset_correction_ms", 1e3 * s.estimate.time_offset_s},
                        {"time_offset_sigma_ms", 1e3 * s.estimate.time_offset_sigma_s},
                        {"rotation_correction_deg", s.estimate.rotation_rad.norm() * 180.0 / M_PI},
                        {"translation_correction_mm", 1e3 * s.estimate.translation_m.norm()}});
    refined[c.given.name] = {{"sweeps", e.sweeps},
                             {"time_offset_s", c.given.time_offset_s + e.settled_time_offset_s},
                             {"time_offset_correction_ms", 1e3 * e.time_offset_s},
                             {"time_offset_sigma_ms", 1e3 * e.time_offset_sigma_s},
                             {"rotation_correction_deg", vec3(e.rotation_rad * 180.0 / M_PI)},
                             {"rotation_sigma_deg", vec3(e.rotation_sigma_rad * 180.0 / M_PI)},
                             {"translation_correction_mm", vec3(1e3 * e.translation_m)},
                             {"translation_sigma_mm", vec3(1e3 * e.translation_sigma_m)},
                             {"T_imu_sensor", matrixRows(c.T_imu_sensor)},
                             {"series", series}};
  }
  return refined;
}

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
  j["tilt_rmse_deg"] = ev.tilt_rmse_deg;  // against gravity, not aligned (eval::EvalResult)
  j["tilt_max_deg"] = ev.tilt_max_deg;
  j["height_error_max_m"] = ev.height_error_max_m;
  return j;
}

/// What went missing from the LiDARs' streams, one clause per LiDAR ("" when nothing did).
std::string lidarStreamLosses(const RunReport::Input& in) {
  std::string out;
  for (const auto& [name, st] : in.lidar_streams) {
    std::string clause;
    if (st.received == 0)
      clause = name + " sent no scan with a valid point (the run used the other sensors only)";
    else if (st.missing > 0)
      clause = std::to_string(st.missing) + " of " + std::to_string(st.expected()) + " " + name +
               " scans missing (never arrived, or without a valid point)";
    if (!clause.empty()) out += (out.empty() ? "" : "; ") + clause;
  }
  return out;
}

/// IMU samples missing in gaps that cost a sweep its motion prediction (0.05 s or more); a lone
/// lost sample now and then does not.
std::size_t imuGapSamples(const RunReport::Input& in) {
  constexpr double kImuGapS = 0.05;
  std::size_t missing = 0;
  for (const StreamTally::Gap& g : in.imu_stream.gaps)
    if (static_cast<double>(g.missing) * in.imu_stream.period_s >= kImuGapS) missing += g.missing;
  return missing;
}

}  // namespace

bool RunReport::inputDegraded() const {
  return input.imu_dropped.total() + input.scans_out_of_order + input.scans_stamp_jumps + input.skipped_messages +
                 input.queue_dropped_imu + input.queue_dropped_scans + imuGapSamples(input) >
             0 ||
         input.truncated || input.damaged_chunks > 0 || !input.time_base_jumps.empty() ||
         !lidarStreamLosses(input).empty();
}

std::string RunReport::inputStatus() const {
  if (!inputDegraded()) return "complete";
  std::vector<std::string> causes;
  const auto count = [&](std::size_t n, const std::string& what) {
    if (n > 0) causes.push_back(std::to_string(n) + " " + what);
  };
  const std::string losses = lidarStreamLosses(input);
  if (!losses.empty()) causes.push_back(losses + " (input.lidar_streams)");
  const std::size_t imu_gaps = imuGapSamples(input);
  if (input.imu_dropped.total() > 0) {
    std::string imu = std::to_string(input.imu_dropped.total()) + " IMU samples dropped (input.imu_dropped)";
    if (input.imu_stream.missing > 0)
      imu += ", " + std::to_string(input.imu_stream.missing) + " missing (input.imu_stream.gaps)";
    causes.push_back(imu);
  } else if (imu_gaps > 0) {
    causes.push_back(std::to_string(imu_gaps) +
                     " IMU samples missing in gaps of 0.05 s or more (input.imu_stream.gaps)");
  }
  count(input.scans_out_of_order + input.scans_stamp_jumps,
        "LiDAR scans out of order or off in time (input.scans_dropped)");
  count(input.queue_dropped_scans + input.queue_dropped_imu,
        "messages dropped by the node's queue, behind the sensors (input.queue_dropped)");
  count(input.skipped_messages, "messages that did not decode (input.skipped_messages)");
  count(input.damaged_chunks, "damaged stretches of the bag skipped (input.damaged_chunks)");
  count(input.time_base_jumps.size(), "jumps of the whole stream's time base (input.time_base_jumps)");
  if (input.truncated) causes.emplace_back("the bag is truncated (input.truncated)");
  std::string out = "degraded: ";
  for (std::size_t i = 0; i < causes.size(); ++i) out += (i > 0 ? "; " : "") + causes[i];
  return out;
}

Json toJson(const RunReport& r) {
  Json rep = Json::object();
  rep["status"] = r.status;
  rep["trustworthy"] = r.untrusted.empty();
  if (!r.untrusted.empty()) rep["untrusted_because"] = r.untrusted;
  Json& run = rep["run"];
  run["schema_version"] = RunReport::Provenance::kSchemaVersion;
  run["mmlio_version"] = r.run.mmlio_version;
  run["commit"] = r.run.commit;
  run["calibration"] = r.run.calibration;
  run["config_yaml"] = r.run.config_yaml;

  Json& in = rep["input"];
  in["source"] = r.input.source;
  in["config"] = r.input.config.empty() ? std::string("(built-in defaults)") : r.input.config;
  in["mode"] = r.input.mode;
  in["duration_s"] = r.input.duration_s;
  in["imu_messages"] = r.input.imu_messages;
  in["imu_acc_scale"] = r.input.imu_acc_scale;
  in["skipped_messages"] = r.input.skipped_messages;
  in["truncated"] = r.input.truncated;
  in["damaged_chunks"] = r.input.damaged_chunks;
  // Where drops happened: stream seconds (the last accepted stamp) of the first and the last one.
  const auto span = [](Stamp from, Stamp to) { return Json::array({toSec(from), toSec(to)}); };
  in["imu_dropped"] = {{"non_finite", r.input.imu_dropped.non_finite},
                       {"beyond_range", r.input.imu_dropped.out_of_range},
                       {"out_of_order", r.input.imu_dropped.out_of_order},
                       {"stamp_jumps", r.input.imu_dropped.jumped}};
  if (r.input.imu_dropped.total() > 0)
    in["imu_dropped"]["between_s"] = span(r.input.imu_dropped.first_at_ns, r.input.imu_dropped.last_at_ns);
  in["scans_dropped"] = {{"out_of_order", r.input.scans_out_of_order}, {"stamp_jumps", r.input.scans_stamp_jumps}};
  if (r.input.scans_out_of_order + r.input.scans_stamp_jumps > 0)
    in["scans_dropped"]["between_s"] = span(r.input.scans_dropped_from_ns, r.input.scans_dropped_to_ns);
  const auto streamJson = [](const StreamTally::Stream& st) {
    Json gaps = Json::array();
    for (const StreamTally::Gap& g : st.gaps) gaps.push_back({{"after_s", toSec(g.after_ns)}, {"missing", g.missing}});
    return Json{{"received", st.received},
                {"expected", st.expected()},
                {"missing", st.missing},
                {"period_s", st.period_s},
                {"first_s", toSec(st.first_ns)},
                {"last_s", toSec(st.last_ns)},
                {"gaps", gaps}};
  };
  Json streams = Json::object();
  for (const auto& [name, st] : r.input.lidar_streams) streams[name] = streamJson(st);
  in["lidar_streams"] = streams;
  // Counted, not a degradation by itself: a missing sample or two is bridged by the preintegration,
  // and a longer gap degrades the sweeps it falls in.
  in["imu_stream"] = streamJson(r.input.imu_stream);
  Json jumps = Json::array();
  for (const auto& j : r.input.time_base_jumps) jumps.push_back({{"at_s", j.at_s}, {"shift_s", j.shift_s}});
  in["time_base_jumps"] = jumps;
  if (r.input.queue_dropped_imu + r.input.queue_dropped_scans > 0 || r.input.source == "live")
    in["queue_dropped"] = {{"imu", r.input.queue_dropped_imu}, {"scans", r.input.queue_dropped_scans}};
  Json decoded = Json::object();
  for (const auto& [name, st] : r.input.decoded)
    decoded[name] = {{"points_kept", st.kept},
                     {"dropped_nan", st.dropped_nan},
                     {"dropped_zero", st.dropped_zero},
                     {"dropped_range", st.dropped_range}};
  in["decoded"] = decoded;

  rep["imu_init"] = {{"ok", r.imu_init.ok},
                     {"forced", r.imu_init.forced},
                     {"gravity_norm_m_s2", r.imu_init.gravity_norm_m_s2},
                     {"gyro_bias_rad_s", vec3(r.imu_init.gyro_bias)},
                     {"acc_scale", r.input.imu_acc_scale},
                     {"message", r.imu_init.message}};
  if (!r.mount_check.lidar.empty())
    rep["mount_check"] = {{"lidar", r.mount_check.lidar},         {"checked", r.mount_check.checked},
                          {"agrees", r.mount_check.agrees},       {"moved_m", r.mount_check.moved_m},
                          {"moved_deg", r.mount_check.moved_deg}, {"seen_through", r.mount_check.seen_through},
                          {"overlap", r.mount_check.overlap},     {"message", r.mount_check.message}};
  rep["imu_bias"] = {
      {"acc_end_m_s2", vec3(r.imu_bias.acc_end_m_s2)}, {"gyro_end_rad_s", vec3(r.imu_bias.gyro_end_rad_s)},
      {"max_acc_m_s2", r.imu_bias.max_acc_m_s2},       {"max_acc_at_s", r.imu_bias.max_acc_at_s},
      {"max_gyro_rad_s", r.imu_bias.max_gyro_rad_s},   {"max_gyro_at_s", r.imu_bias.max_gyro_at_s}};
  rep["sweeps"] = {{"processed", r.sweeps.processed},
                   {"tracked", r.sweeps.tracked},
                   {"degraded", r.sweeps.degraded},
                   {"initialising", r.sweeps.initialising},
                   {"keyframes", r.sweeps.keyframes},
                   {"degenerate", r.sweeps.degenerate},
                   {"degraded_fraction", r.sweeps.degraded_fraction},
                   {"coverage", r.sweeps.coverage}};
  rep["degeneracy"] = r.degeneracy;
  rep["online_calibration"] = refinedCalibrationJson(r.online_calibration);
  if (!r.online_calibration_first_pass.empty())
    rep["online_calibration_first_pass"] = refinedCalibrationJson(r.online_calibration_first_pass);

  if (r.localization.enabled) {
    const RunReport::Localization& l = r.localization;
    Json lost = Json::array();
    for (const auto& [from, to] : l.lost_s) lost.push_back({{"from_s", from}, {"to_s", to}});
    rep["localization"] = {{"session", l.session},
                           {"localized", l.localized},
                           {"localized_at_end", l.localized_at_end},
                           {"first_localized_s", l.first_localized_s},
                           {"relocalizations", l.relocalizations},
                           {"relocalization_attempts", l.relocalization_attempts},
                           {"pose_hints", l.pose_hints},
                           {"pose_hints_refuted", l.pose_hints_refuted},
                           {"keyframes", l.keyframes},
                           {"keyframes_fitting_the_map", l.keyframes_fitted},
                           {"keyframes_degenerate", l.keyframes_degenerate},
                           {"last_fitness_m", l.last_fitness_m},
                           {"last_overlap", l.last_overlap},
                           {"lost", lost},
                           {"last_reason", l.last_reason}};
  }

  if (r.extension.enabled) {
    const RunReport::Extension& e = r.extension;
    rep["extension"] = {{"session", e.session},
                        {"session_keyframes", e.session_keyframes},
                        {"session_map_points", e.session_map_points},
                        {"keyframes_added", e.keyframes_added},
                        {"keyframes_tied", e.keyframes_tied},
                        {"localized_at_s", e.localized_at_s},
                        {"T_map_odom", matrixRows(e.T_map_odom)}};
  }

  Json features = Json::object();
  for (const auto& [name, t] : r.features) {
    const double n = static_cast<double>(std::max<std::size_t>(t.sweeps, 1));
    features[name] = {{"sweeps", t.sweeps},
                      {"mean_points", static_cast<double>(t.points) / n},
                      {"mean_edges", static_cast<double>(t.edges) / n},
                      {"mean_planes", static_cast<double>(t.planes) / n},
                      {"bad_frames", t.bad_frames}};
  }
  rep["features"] = features;
  rep["timing"] = r.timing.toJson();
  rep["wall_time_s"] = r.wall_time_s;
  rep["realtime_factor"] = r.realtime_factor;
  Json& mapping = rep["mapping"];
  mapping = {{"enabled", r.mapping.enabled},
             {"keyframes", r.mapping.keyframes},
             {"loop_attempts", r.mapping.attempts},
             {"loops_accepted", r.mapping.accepted},
             {"candidates_rejected", r.mapping.candidates_rejected},
             {"loops", Json::array()}};
  for (const backend::ClosedLoop& l : r.mapping.loops)
    mapping["loops"].push_back(
        {{"query_s", l.query_s}, {"match_s", l.match_s}, {"fitness_m", l.fitness_m}, {"overlap", l.overlap}});
  if (!r.mapping_error.empty()) mapping["error"] = r.mapping_error;
  rep["timing_backend"] = r.timing_backend.toJson();
  rep["memory"] = {{"sweeps_waiting_for_imu_max", r.memory.sweeps_waiting_for_imu_max},
                   {"mapping_queue_max", r.memory.mapping_queue_max},
                   {"mapping_queue_capacity", r.memory.mapping_queue_capacity},
                   {"peak_rss_mb", r.memory.peak_rss_mb}};

  const RunReport::Dynamic& d = r.dynamic;
  rep["dynamic"] = {{"enabled", d.enabled},
                    {"sweeps_judged", d.sweeps_judged},
                    {"feature_points_rejected", d.feature_points_rejected},
                    {"sweeps_with_rejections", d.sweeps_with_rejections},
                    {"local_map_points_carved", d.local_map_points_carved},
                    {"clean_map", d.clean_map},
                    {"map_points_judged", d.map_points_judged},
                    {"map_points_removed", d.map_points_removed},
                    {"dynamic_map_points", d.dynamic_map_points},
                    {"map_assembly_s", d.map_assembly_s}};

  if (!r.outputs.trajectory.empty()) {
    Json& out = rep["outputs"];
    out["trajectory"] = r.outputs.trajectory;
    out["poses"] = r.outputs.poses;
    out["map"] = r.outputs.map;
    out["map_points"] = r.outputs.map_points;
    out["map_voxel_m"] = r.outputs.map_voxel_m;
    if (!r.outputs.per_lidar_maps.empty()) out["per_lidar_maps"] = r.outputs.per_lidar_maps;
    if (!r.outputs.dynamic_map.empty()) out["dynamic_map"] = r.outputs.dynamic_map;
    if (!r.outputs.session.empty()) {
      out["session"] = r.outputs.session;
      out["session_keyframes"] = r.outputs.session_keyframes;
    }
  }
  if (r.evaluation) rep["evaluation"] = evaluationJson(*r.evaluation);
  return rep;
}

std::string toMarkdown(const RunReport& r) {
  const auto fixed = eval::fixedText;
  std::string md = "# mmlio run: " + (r.input.source.empty() ? std::string("live") : r.input.source) + "\n\n";
  md += "**" + r.status + "**, " + (r.untrusted.empty() ? "trusted" : "**untrusted**: " + r.untrusted) + "\n\n";
  md += "| | |\n|---|---|\n";
  md += "| mode | " + r.input.mode + " |\n";
  md += "| duration | " + fixed(r.input.duration_s, 1) + " s (" + fixed(r.realtime_factor, 1) + "x real time) |\n";
  if (r.evaluation) {
    const eval::EvalResult& e = *r.evaluation;
    md += "| ATE | " + fixed(100.0 * e.ate_rmse_m, 2) + " cm (end to end " + fixed(100.0 * e.end_to_end_m, 1) +
          " cm over " + fixed(e.path_length_m, 1) + " m) |\n";
  }
  md += "| sweeps | " + std::to_string(r.sweeps.tracked) + " tracked, " + std::to_string(r.sweeps.degraded) +
        " degraded, " + std::to_string(r.sweeps.degenerate) + " degenerate |\n";
  md += "| loops closed | " + std::to_string(r.mapping.accepted) + " of " + std::to_string(r.mapping.attempts) +
        " tried |\n";
  md += "| input | " + r.inputStatus() + " |\n";
  if (!r.mapping_error.empty()) md += "| mapping | failed: " + r.mapping_error + " |\n";
  md += "| map | " + std::to_string(r.outputs.map_points) + " points |\n";
  md += "| peak memory | " + fixed(r.memory.peak_rss_mb, 0) + " MB |\n";
  md +=
      "\nThe map in 3D, the plots and every field: [report.html](report.html); the data: report.json; the "
      "settings that rerun it: config_used.yaml.\n";
  return md;
}

}  // namespace mmlio::pipeline
