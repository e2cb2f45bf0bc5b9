#include "mmlio/pipeline/runner.hpp"

#include <cmath>
#include <limits>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/timer.hpp"
#include "mmlio/estimator/odometry.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/io/pcd_io.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/pipeline/online_pipeline.hpp"
#include "mmlio/pipeline/mapping_thread.hpp"
#include "mmlio/pipeline/odometry_setup.hpp"
#include "mmlio/pipeline/degeneracy_tally.hpp"
#include "mmlio/pipeline/progress.hpp"
#include "mmlio/pipeline/report.hpp"

namespace mmlio::pipeline {
namespace {

/// Running per-LiDAR figures for the report.
struct LidarTally {
  std::size_t sweeps = 0, points = 0, edges = 0, planes = 0, bad_frames = 0;
};

Json vec3(const Eigen::Vector3d& v) {
  Json a = Json::array();
  for (int i = 0; i < 3; ++i) a.push_back(v[i]);
  return a;
}

// Found before hours of work, not after: the output folder exists (or is created) and takes a file.
void checkWritable(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(dir, error);
  if (!fs::is_directory(dir, error))
    throw Error("cannot create output directory '" + dir + "'" + (error ? ": " + error.message() : std::string()));
  const fs::path probe = fs::path(dir) / ".mmlio-write-test";
  {
    std::ofstream out(probe);
    if (!(out << "ok")) throw Error("cannot write to output directory '" + dir + "'");
  }
  fs::remove(probe, error);
}

}  // namespace

RunResult runBag(const RunOptions& options) {
  const io::RigConfig& cfg = options.config;
  if (!options.out_dir.empty()) checkWritable(options.out_dir);
  const std::string mode = options.mode.empty() ? cfg.mode : options.mode;
  if (!io::isValidMode(mode)) throw Error("unknown mode '" + mode + "' (expected hvi, vi or hi)");

  io::BagSource source(options.bag_path, io::bagSourceOptions(cfg, mode));
  MappingThread mapping(mappingBackendConfig(cfg));

  RunResult result;
  std::map<std::string, LidarTally> tally;
  std::size_t tracked = 0, degraded = 0, initialising = 0;
  std::size_t dynamic_points = 0, dynamic_sweeps = 0, carved_points = 0;
  DegeneracyTally degeneracy(cfg.odometry.degenerate_min_points, cfg.odometry.remap_degenerate);
  auto onSweep = [&](const estimator::SweepResult& r) {
    if (r.status == estimator::SweepResult::Status::kInitializing) {
      ++initialising;
      return;
    }
    if (r.status == estimator::SweepResult::Status::kDegraded) ++degraded;
    else ++tracked;
    Stopwatch t;
    result.trajectory.push_back({r.state.stamp_ns, r.state.pose()});
    degeneracy.add(r);
    dynamic_points += r.dynamic_points;
    dynamic_sweeps += r.dynamic_points > 0;
    carved_points += r.carved_points;
    mapping.addSweep(r);  // a copy: the back end works on it on its own thread
    StageTimes times = r.times_ms;
    times.emplace_back("mapping_handoff", t.lapMs());
    result.timing.add(times);
    for (const auto& l : r.lidars) {
      LidarTally& lt = tally[l.sensor];
      ++lt.sweeps;
      lt.points += l.points;
      lt.edges += l.edges;
      lt.planes += l.planes;
      lt.bad_frames += l.bad_frame ? 1 : 0;
    }
  };
  OnlinePipeline online(cfg, mode, onSweep);
  const estimator::Odometry& odometry = online.odometry();
  ProgressBar progress("mmlio run", options.progress);
  Stopwatch wall;

  const Stamp stop_ns = options.max_duration_s > 0 ? source.beginNs() + fromSec(options.max_duration_s)
                                                   : std::numeric_limits<Stamp>::max();
  try {
    io::SensorEvent event;
    std::size_t events = 0;
    const Stamp period_ns = source.endNs() - source.beginNs() + fromSec(1.0);
    for (int replay = 0; replay < std::max(1, options.replays); ++replay) {
      // Replays re-open the bag and shift its stamps past the previous pass.
      std::unique_ptr<io::BagSource> again;
      if (replay > 0) again = std::make_unique<io::BagSource>(options.bag_path, io::bagSourceOptions(cfg, mode));
      io::BagSource& src = replay > 0 ? *again : source;
      const Stamp shift = replay * period_ns;
      while (!(options.stop && options.stop->load()) && src.next(&event)) {
        if (event.kind == io::SensorEvent::Kind::kImu) {
          event.imu.stamp_ns += shift;
          if (event.imu.stamp_ns > stop_ns) break;
          online.addImu(event.imu);
        } else {
          event.scan.start_ns += shift;
          online.addScan(std::move(event.scan));
        }
        if (++events % 50 == 0) {
          std::ostringstream status;
          const double bag_s = toSec(odometry.lastImuNs() - source.beginNs());
          status.precision(3);
          status << online.sweepsProcessed() << " sweeps, " << odometry.keyframes() << " kf, "
                 << degeneracy.degenerateSweeps() << " degenerate, "
                 << bag_s / std::max(1e-3, wall.elapsedMs() * 1e-3) << "x rt";
          progress.update((replay + src.progress()) / std::max(1, options.replays), status.str());
        }
      }
    }
    result.interrupted = options.stop && options.stop->load();
    if (result.interrupted) log::warn("interrupted: writing the trajectory, map and report computed so far");
    else online.flush();  // an interrupted run's last sweeps may lack IMU: they are left out
  } catch (const Error& e) {
    if (result.trajectory.empty()) throw;
    result.complete = false;
    result.error = e.what();
    log::emit(log::Level::kError, "stopped early: ", e.what(), " (writing the ", result.trajectory.size(),
              " poses computed so far)");
  }
  try {
    mapping.finish();  // after an early stop: what was queued still reaches the map
  } catch (const std::exception& e) {  // a failed back end must not cost the trajectory
    log::warn("mapping back end failed: ", e.what(), " (odometry trajectory and the map so far are written)");
  }
  MappingBackend& backend = mapping.backend();
  const std::size_t sweeps = online.sweepsProcessed();
  const double wall_s = wall.elapsedMs() * 1e-3;
  progress.finish(std::to_string(sweeps) + " sweeps, " + std::to_string(result.trajectory.size()) + " poses");

  if (result.trajectory.empty() && result.complete) {
    throw Error(odometry.initialized()
                    ? "no sweep could be tracked in " + options.bag_path
                    : "IMU initialisation never succeeded in " + options.bag_path + ": " + odometry.imuInit().message);
  }

  // ---- report ----
  Json& rep = result.report;
  rep = Json::object();
  const ImuGate::Counts& imu_dropped = online.imuGate().counts();
  if (imu_dropped.total() > 0)
    log::warn("IMU: ", imu_dropped.total(), " samples dropped (non-finite ", imu_dropped.non_finite, ", beyond range ",
              imu_dropped.out_of_range, ", out of order ", imu_dropped.out_of_order, ", stamp jumps ", imu_dropped.jumped,
              ")");
  const OnlinePipeline::ScanDrops& scans_dropped = online.scanDrops();
  const std::size_t scan_drops = scans_dropped.out_of_order + scans_dropped.jumped;
  if (scan_drops > 0)
    log::warn("LiDAR: ", scan_drops, " scans dropped (out of order ", scans_dropped.out_of_order, ", stamp jumps ",
              scans_dropped.jumped, ")");
  rep["status"] = !result.complete ? "incomplete: " + result.error
                  : result.interrupted ? std::string("interrupted")
                  : imu_dropped.total() + scan_drops + source.skippedMessages() > 0 || source.truncated()
                      ? std::string("degraded: input dropped (see input.imu_dropped, input.scans_dropped, "
                                    "input.skipped_messages, input.truncated)")
                      : std::string("complete");
  Json input = Json::object();
  input["bag"] = options.bag_path;
  input["config"] = cfg.source_path;
  input["mode"] = mode;
  input["bag_duration_s"] = toSec(source.endNs() - source.beginNs());
  input["imu_messages"] = source.imuCount();
  input["imu_acc_scale"] = source.accScale();
  input["skipped_messages"] = source.skippedMessages();
  Json imu_gate = Json::object();
  imu_gate["non_finite"] = imu_dropped.non_finite;
  imu_gate["beyond_range"] = imu_dropped.out_of_range;
  imu_gate["out_of_order"] = imu_dropped.out_of_order;
  imu_gate["stamp_jumps"] = imu_dropped.jumped;
  input["imu_dropped"] = imu_gate;
  Json scans_gate = Json::object();
  scans_gate["out_of_order"] = scans_dropped.out_of_order;
  scans_gate["stamp_jumps"] = scans_dropped.jumped;
  input["scans_dropped"] = scans_gate;
  input["truncated"] = source.truncated();
  Json lidars_in = Json::object();
  for (const auto& [name, st] : source.stats()) {
    Json s = Json::object();
    s["points_kept"] = st.kept;
    s["dropped_nan"] = st.dropped_nan;
    s["dropped_zero"] = st.dropped_zero;
    s["dropped_range"] = st.dropped_range;
    lidars_in[name] = s;
  }
  input["decoded"] = lidars_in;
  rep["input"] = input;

  const auto& init = odometry.imuInit();
  Json imu = Json::object();
  imu["ok"] = init.ok;
  imu["gravity_norm_m_s2"] = init.gravity_norm_m_s2;
  imu["gyro_bias_rad_s"] = vec3(init.gyro_bias);
  imu["acc_scale"] = source.accScale();
  imu["message"] = init.message;
  rep["imu_init"] = imu;

  Json sw = Json::object();
  sw["processed"] = sweeps;
  sw["tracked"] = tracked;
  sw["degraded"] = degraded;
  sw["initialising"] = initialising;
  sw["keyframes"] = odometry.keyframes();
  sw["degenerate"] = degeneracy.degenerateSweeps();
  rep["sweeps"] = sw;
  rep["degeneracy"] = degeneracy.toJson(source.beginNs());

  Json per_lidar = Json::object();
  for (const auto& [name, t] : tally) {
    Json l = Json::object();
    const double n = std::max<std::size_t>(t.sweeps, 1);
    l["sweeps"] = t.sweeps;
    l["mean_points"] = t.points / n;
    l["mean_edges"] = t.edges / n;
    l["mean_planes"] = t.planes / n;
    l["bad_frames"] = t.bad_frames;
    per_lidar[name] = l;
  }
  rep["features"] = per_lidar;
  rep["timing"] = result.timing.toJson();
  rep["wall_time_s"] = wall_s;
  rep["realtime_factor"] = wall_s > 0 ? toSec(odometry.lastImuNs() - source.beginNs()) / wall_s : 0.0;

  rep["mapping"] = backend.toJson();
  result.backend_timing = mapping.timing();
  rep["timing_backend"] = result.backend_timing.toJson();

  // ---- outputs ----
  result.trajectory = backend.correctedTrajectory();
  Stopwatch assembly;
  const std::vector<Point> map_points = backend.map();
  const std::vector<Point> dynamic_map = backend.dynamicMap();
  const MappingBackend::GhostRemoval& ghosts = backend.ghostRemoval();
  const double map_s = assembly.elapsedMs() * 1e-3;
  result.map_points = map_points.size();
  Json dyn = Json::object();
  dyn["enabled"] = cfg.dynamic.enabled;
  dyn["feature_points_rejected"] = dynamic_points;
  dyn["sweeps_with_rejections"] = dynamic_sweeps;
  dyn["local_map_points_carved"] = carved_points;
  dyn["clean_map"] = cfg.dynamic.clean_map;
  dyn["map_points_judged"] = ghosts.judged_points;
  dyn["map_points_removed"] = ghosts.removed_points;
  dyn["dynamic_map_points"] = dynamic_map.size();
  dyn["map_assembly_s"] = map_s;  // merging the submaps (ghosts were removed during the run)
  rep["dynamic"] = dyn;
  if (!options.out_dir.empty()) {
    namespace fs = std::filesystem;
    fs::create_directories(options.out_dir);
    const std::string dir = options.out_dir + "/";
    io::writeTum(dir + "trajectory.tum", result.trajectory);
    if (cfg.output.write_kitti) {
      io::writeKitti(dir + "trajectory.kitti", result.trajectory);
      io::writeKittiTimes(dir + "times.txt", result.trajectory);
    }
    io::writePcdBinary(dir + "map.pcd", map_points);
    Json out = Json::object();
    out["trajectory"] = dir + "trajectory.tum";
    out["poses"] = result.trajectory.size();
    out["map"] = dir + "map.pcd";
    out["map_points"] = map_points.size();
    out["map_voxel_m"] = cfg.output.map_voxel_m;
    Json per_lidar_maps = Json::object();
    for (const std::string& lidar : backend.lidarNames()) {
      const std::string path = dir + "map_" + lidar + ".pcd";
      const std::vector<Point> points = backend.lidarMap(lidar);
      io::writePcdBinary(path, points);
      per_lidar_maps[lidar] = path;
    }
    if (!backend.lidarNames().empty()) out["per_lidar_maps"] = per_lidar_maps;
    if (cfg.output.dynamic_map) {
      io::writePcdBinary(dir + "map_dynamic.pcd", dynamic_map);
      out["dynamic_map"] = dir + "map_dynamic.pcd";
    }
    rep["outputs"] = out;
    writeReports(dir, rep, result.trajectory, map_points, options.gt_path);
  }
  return result;
}

}  // namespace mmlio::pipeline
