#include "mmlio/pipeline/system.hpp"

#include <sys/resource.h>

#include <filesystem>

#include "mmlio/backend/pose_graph.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/io/pcd_io.hpp"
#include "mmlio/io/session_io.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/map/kd_tree.hpp"
#include "mmlio/pipeline/odometry_setup.hpp"
#include "mmlio/pipeline/report.hpp"
#include "mmlio/version.hpp"

namespace mmlio::pipeline {

namespace {

// How well the localization that places an extending run is known: a verified ICP onto the
// session's map (its tracking holds its keyframes within about a centimetre).
constexpr double kExtensionTieSigmaM = 0.01;
constexpr double kExtensionTieSigmaRad = 0.2 * M_PI / 180.0;

/// The process's resident memory high-water mark so far, MB (0 if unknown).
double peakRssMb() {
  rusage usage{};
  return getrusage(RUSAGE_SELF, &usage) == 0 ? usage.ru_maxrss / 1024.0 : 0.0;  // KiB on Linux
}

/// The back end keeps keyframe clouds for loop closure, and for the session a later run relocalizes in.
backend::MappingConfig mappingConfig(const config::RigConfig& cfg) {
  backend::MappingConfig m = cfg.mapping;
  m.keep_keyframe_clouds = cfg.output.write_session;
  return m;
}

}  // namespace

System::System(const config::RigConfig& cfg, const std::string& mode, SweepObserver observer)
    : cfg_(cfg),
      mode_(mode.empty() ? cfg.mode : mode),
      observer_(std::move(observer)),
      mapping_(mappingConfig(cfg)),
      degeneracy_(cfg.estimator.degeneracy.min_points, cfg.estimator.remap_degenerate),
      online_(cfg, mode_, [this](estimator::SweepResult r) { onSweep(std::move(r)); }) {
  dynamic_.enabled = cfg.estimator.dynamic.enabled;
  dynamic_.clean_map = cfg.mapping.clean_map;
  config::RigConfig effective = cfg_;  // as run: the mode chosen, the extrinsics already applied
  effective.mode = mode_;
  effective.calibration = "config";
  effective_config_yaml_ = config::toYaml(effective);  // once: every report (the node's too) carries it
}

void System::localizeIn(std::shared_ptr<const Session> session, const std::string& session_dir,
                        const std::optional<Eigen::Isometry3d>& initial_pose) {
  session_ = std::move(session);
  session_dir_ = session_dir;
  localizer_ = std::make_unique<backend::MapLocalizer>(*session_, backend::MapLocalizerConfig(), initial_pose);
}

void System::extend(std::shared_ptr<const Session> session, const std::string& session_dir,
                    const Eigen::Isometry3d& T_map_odom, double localized_at_s) {
  session_ = std::move(session);
  session_dir_ = session_dir;
  T_map_odom_ = T_map_odom;
  extension_localized_at_s_ = localized_at_s;
  mapping_.update([this](backend::MappingBackend& b) { b.coverAlready(session_->map, T_map_odom_->inverse()); });
  tracker_ = std::make_unique<backend::MapLocalizer>(*session_);
}

Trajectory System::inSession(Trajectory trajectory) const {
  if (!T_map_odom_) return trajectory;
  for (StampedPose& p : trajectory) p.T_world_body = *T_map_odom_ * p.T_world_body;
  return trajectory;
}

std::vector<Point> System::inSession(std::vector<Point> points) const {
  if (!T_map_odom_) return points;
  const Eigen::Isometry3f T = T_map_odom_->cast<float>();
  for (Point& p : points) p.xyz = T * p.xyz;
  return points;
}

Session System::mergedSession(Session added) const {
  if (!T_map_odom_) return added;
  Session merged;
  merged.map_voxel_m = added.map_voxel_m;
  merged.cloud_voxel_m = added.cloud_voxel_m;
  merged.keyframes = session_->keyframes;
  merged.loops = session_->loops;
  const int first_added = static_cast<int>(merged.keyframes.size());
  for (SessionKeyframe& k : added.keyframes) {
    k.T_map_body = *T_map_odom_ * k.T_map_body;
    merged.keyframes.push_back(std::move(k));
  }
  for (SessionLoop l : added.loops) {
    l.from += first_added;
    l.to += first_added;
    merged.loops.push_back(l);
  }
  // One graph: the first keyframe added is tied where the localization put it to the session's
  // keyframe nearest to it.
  if (first_added > 0 && static_cast<int>(merged.keyframes.size()) > first_added) {
    const Eigen::Isometry3d& T_new = merged.keyframes[static_cast<std::size_t>(first_added)].T_map_body;
    int nearest = 0;
    for (int k = 1; k < first_added; ++k)
      if ((merged.keyframes[static_cast<std::size_t>(k)].T_map_body.translation() - T_new.translation()).norm() <
          (merged.keyframes[static_cast<std::size_t>(nearest)].T_map_body.translation() - T_new.translation()).norm())
        nearest = k;
    merged.loops.push_back({nearest, first_added,
                            merged.keyframes[static_cast<std::size_t>(nearest)].T_map_body.inverse() * T_new,
                            backend::isotropicInformation(kExtensionTieSigmaM, kExtensionTieSigmaRad)});
  }
  return merged;
}

bool System::hintPose(const Eigen::Isometry3d& T_map_body, bool with_height) {
  if (!localizer_) return false;
  localizer_->hint(T_map_body, with_height);
  return true;
}

void System::onSweep(estimator::SweepResult r) {
  if (r.status == estimator::SweepResult::Status::kInitializing) {
    ++sweeps_.initialising;
    return;
  }
  if (r.status == estimator::SweepResult::Status::kDegraded)
    ++sweeps_.degraded;
  else
    ++sweeps_.tracked;
  Stopwatch handoff;
  sampleCalibration(r.state.stamp_ns);
  trackImuBias(r);
  if (r.keyframe) keyframe_poses_.push_back(odometry_poses_.size());
  odometry_poses_.push_back({r.state.stamp_ns, r.state.pose()});
  if ((localizer_ || tracker_) && r.keyframe && r.status == estimator::SweepResult::Status::kTracking) {
    std::vector<Eigen::Vector3d> cloud;
    cloud.reserve(r.points_body.size());
    for (const Point& p : r.points_body) cloud.emplace_back(p.xyz.cast<double>());
    backend::MapLocalizer& l = localizer_ ? *localizer_ : *tracker_;
    l.addKeyframe(r.state.stamp_ns, r.state.pose(), map::voxelCentroids(cloud, session_->cloud_voxel_m));
    // Extending: the keyframe the session's map places is tied there in this run's world.
    if (tracker_)
      if (const std::optional<Eigen::Isometry3d> T_map_body = tracker_->placed(r.state.stamp_ns, r.state.pose()))
        r.T_world_body_measured = T_map_odom_->inverse() * *T_map_body;
  }
  degeneracy_.add(r);
  dynamic_.sweeps_judged += r.judged_for_movers;
  dynamic_.feature_points_rejected += r.dynamic_points;
  dynamic_.sweeps_with_rejections += r.dynamic_points > 0;
  dynamic_.local_map_points_carved += r.carved_points;
  for (const auto& l : r.lidars) {
    RunReport::LidarFigures& f = lidars_[l.sensor];
    ++f.sweeps;
    f.points += l.points;
    f.edges += l.edges;
    f.planes += l.planes;
    f.bad_frames += l.bad_frame ? 1 : 0;
  }
  StageTimes times = r.times_ms;
  const Stamp stamp_ns = r.state.stamp_ns;
  RunReport::SweepSample sample;
  sample.stamp_ns = online_.externalStamp(stamp_ns);
  for (const auto& l : r.lidars) {
    sample.edges += static_cast<float>(l.edges);
    sample.planes += static_cast<float>(l.planes);
  }
  sample.weakest_points = static_cast<float>(r.degeneracy.translation_points);
  sample.degenerate = r.registered && r.degeneracy.any();
  sample.degraded = r.status == estimator::SweepResult::Status::kDegraded;
  sample.keyframe = r.keyframe;
  // The back end works on the sweep on its own thread: it takes it, or a copy if an observer (the
  // live node publishing the sweep's points) still needs it.
  // Localizing, the map is the session's: nothing is mapped (memory stays that of the odometry).
  if (!finished_ && !localizer_) {
    if (observer_)
      mapping_.addSweep(r);
    else
      mapping_.addSweep(std::move(r));
  }
  times.emplace_back("mapping_handoff", handoff.lapMs());
  for (const auto& [stage, ms] : times)
    if (stage != "total") sample.total_ms += static_cast<float>(ms);
  timeline_.push_back(sample);
  timing_.add(times);
  if (timing_observer_) timing_observer_(stamp_ns, times);
  // r was moved to the back end only without an observer.
  if (observer_) observer_(r);  // NOLINT(bugprone-use-after-move)
}

void System::trackImuBias(const estimator::SweepResult& r) {
  if (r.status != estimator::SweepResult::Status::kTracking) return;
  const ImuBias& b = r.state.bias;
  imu_bias_.acc_end_m_s2 = b.acc_m_s2;
  imu_bias_.gyro_end_rad_s = b.gyro_rad_s;
  if (b.acc_m_s2.norm() > imu_bias_.max_acc_m_s2) {
    imu_bias_.max_acc_m_s2 = b.acc_m_s2.norm();
    imu_bias_.max_acc_at_s = toSec(r.state.stamp_ns - first_imu_ns_);
  }
  if (b.gyro_rad_s.norm() > imu_bias_.max_gyro_rad_s) {
    imu_bias_.max_gyro_rad_s = b.gyro_rad_s.norm();
    imu_bias_.max_gyro_at_s = toSec(r.state.stamp_ns - first_imu_ns_);
  }
}

void System::sampleCalibration(Stamp stamp_ns) {
  constexpr Stamp kIntervalNs = 1000000000;
  if (stamp_ns < next_calibration_sample_ns_) return;
  next_calibration_sample_ns_ = stamp_ns + kIntervalNs;
  const double t_s = first_imu_ns_ > 0 ? toSec(stamp_ns - first_imu_ns_) : 0.0;
  for (const estimator::LidarCalibrationEstimate& e : odometry().calibration()) calibration_series_.push_back({t_s, e});
}

std::vector<RunReport::RefinedCalibration> System::refinedCalibration() const {
  std::vector<RunReport::RefinedCalibration> out;
  for (const estimator::LidarCalibrationEstimate& e : odometry().calibration()) {
    RunReport::RefinedCalibration c;
    for (const config::LidarConfig& l : cfg_.lidars)
      if (l.name == e.sensor) c.given = config::toExtrinsic(l);
    c.last = e;
    c.T_imu_sensor = c.given.T_imu_sensor;
    c.T_imu_sensor.linear() = so3::exp(e.settled_rotation_rad).toRotationMatrix() * c.T_imu_sensor.linear();
    c.T_imu_sensor.translation() += e.settled_translation_m;
    for (const RunReport::RefinedCalibration::Sample& s : calibration_series_)
      if (s.estimate.sensor == e.sensor) c.series.push_back(s);
    out.push_back(std::move(c));
  }
  return out;
}

void System::finish() {
  if (finished_) return;
  finished_ = true;
  try {
    mapping_.finish();                 // after an early stop too: what was queued still reaches the map
  } catch (const std::exception& e) {  // a failed back end must not cost the trajectory
    backend_error_ = e.what();
    log::warn("mapping back end failed: ", e.what(), " (odometry trajectory and the map so far are written)");
  }
}

Trajectory System::inputTime(Trajectory trajectory) const {
  if (online_.timeBaseJumps().empty()) return trajectory;
  for (StampedPose& p : trajectory) p.stamp_ns = online_.externalStamp(p.stamp_ns);
  return trajectory;
}

Trajectory System::trajectory() const {
  if (localizer_) return inputTime(localizer_->inMap(odometry_poses_.trajectory()));
  return inSession(
      inputTime(mapping_.read([this](const backend::MappingBackend& b) { return b.corrected(odometry_poses_); })));
}

Trajectory System::route() const {
  Trajectory odometry;
  odometry.reserve(keyframe_poses_.size() + 1);
  for (const std::size_t i : keyframe_poses_) odometry.push_back(odometry_poses_[i]);
  if (!odometry_poses_.empty() && (keyframe_poses_.empty() || keyframe_poses_.back() + 1 != odometry_poses_.size()))
    odometry.push_back(odometry_poses_.back());
  if (localizer_) return inputTime(localizer_->inMap(odometry));
  return inSession(
      inputTime(mapping_.read([&](const backend::MappingBackend& b) { return b.corrected(std::move(odometry)); })));
}

Stamp System::externalStamp(Stamp internal_ns) const { return online_.externalStamp(internal_ns); }

Eigen::Isometry3d System::mapFromOdom() const {
  if (localizer_) {
    const std::optional<Eigen::Isometry3d> T =
        localizer_->mapFromOdom(odometry_poses_.empty() ? 0 : odometry_poses_.back().stamp_ns);
    return T ? *T : Eigen::Isometry3d::Identity();
  }
  const Eigen::Isometry3d correction = mapping_.read([](const backend::MappingBackend& b) { return b.correction(); });
  return T_map_odom_ ? *T_map_odom_ * correction : correction;
}

std::size_t System::loops() const {
  return mapping_.read([](const backend::MappingBackend& b) { return b.loops(); });
}

std::vector<Point> System::map() const {
  if (localizer_) return session_->map;
  return withSessionMap(mapping_.read([](const backend::MappingBackend& b) { return b.map(); }));
}

std::vector<Point> System::withSessionMap(std::vector<Point> added) const {
  added = inSession(std::move(added));
  if (!T_map_odom_) return added;
  std::vector<Point> merged = session_->map;
  merged.insert(merged.end(), added.begin(), added.end());
  return merged;
}

RunReport System::report(Stamp stream_end_ns, const TrustLimits& limits) const {
  RunReport r;
  r.run.mmlio_version = kVersion;
  r.run.commit = kCommit;
  r.run.calibration = cfg_.calibration;
  r.run.config_yaml = effective_config_yaml_;
  r.input.mode = mode_;
  r.input.config = cfg_.source_path;
  r.input.imu_dropped = online_.imuGate().counts();
  r.input.scans_out_of_order = online_.scanDrops().out_of_order;
  r.input.scans_stamp_jumps = online_.scanDrops().jumped;
  r.input.scans_dropped_from_ns = online_.scanDrops().first_at_ns;
  r.input.scans_dropped_to_ns = online_.scanDrops().last_at_ns;
  const Stamp end_ns = stream_end_ns > 0 ? stream_end_ns : externalStamp(odometry().lastImuNs());
  r.input.lidar_streams = online_.lidarStreams(end_ns);
  r.input.imu_stream = online_.imuStream(end_ns);
  for (const OnlinePipeline::TimeBaseJump& j : online_.timeBaseJumps())
    r.input.time_base_jumps.push_back({toSec(j.at_ns), toSec(j.shift_ns)});
  r.imu_init = odometry().imuInit();
  r.imu_bias = imu_bias_;
  r.sweeps = sweeps_;
  r.sweeps.processed = online_.sweepsProcessed();
  r.sweeps.keyframes = odometry().keyframes();
  r.sweeps.degenerate = degeneracy_.degenerateSweeps();
  r.degeneracy = degeneracy_.toJson(first_imu_ns_);
  r.features = lidars_;
  r.timing = timing_;
  r.timeline = timeline_;
  r.timing_backend = mapping_.timing();
  r.wall_time_s = wall_.elapsedMs() * 1e-3;
  const double sensor_s = first_imu_ns_ > 0 ? toSec(odometry().lastImuNs() - first_imu_ns_) : 0.0;
  r.realtime_factor = r.wall_time_s > 0 ? sensor_s / r.wall_time_s : 0.0;
  r.dynamic = dynamic_;
  mapping_.read([&r](const backend::MappingBackend& b) {
    r.mapping = b.loopFigures();
    r.dynamic.map_points_judged = b.ghostRemoval().judged_points;
    r.dynamic.map_points_removed = b.ghostRemoval().removed_points;
  });
  r.mapping_error = backend_error_;
  r.online_calibration = refinedCalibration();
  r.memory.sweeps_waiting_for_imu_max = online_.waitingHighWater();
  r.memory.mapping_queue_max = mapping_.queueHighWater();
  r.memory.mapping_queue_capacity = mapping_.capacity();
  r.memory.peak_rss_mb = peakRssMb();
  judgeTrust(&r, online_.internalStamp(end_ns), limits);
  if (localizer_) reportLocalization(&r);
  if (T_map_odom_) {
    RunReport::Extension& e = r.extension;
    e.enabled = true;
    e.session = session_dir_;
    e.session_keyframes = session_->keyframes.size();
    e.session_map_points = session_->map.size();
    mapping_.read([&e](const backend::MappingBackend& b) {
      e.keyframes_added = b.keyframes();
      e.keyframes_tied = b.sessionTies();
    });
    e.localized_at_s = extension_localized_at_s_;
    e.T_map_odom = *T_map_odom_;
  }
  return r;
}

void System::reportLocalization(RunReport* r) const {
  const backend::LocalizationStatus& s = localizer_->status();
  RunReport::Localization& l = r->localization;
  const auto since_start = [this](Stamp t) { return t == 0 ? -1.0 : toSec(externalStamp(t) - first_imu_ns_); };
  l.enabled = true;
  l.session = session_dir_;
  l.localized = s.first_localized_ns.has_value();
  l.localized_at_end = s.localized;
  l.first_localized_s = s.first_localized_ns ? since_start(*s.first_localized_ns) : -1.0;
  l.relocalizations = s.relocalizations;
  l.relocalization_attempts = s.relocalization_attempts;
  l.pose_hints = s.pose_hints;
  l.pose_hints_refuted = s.pose_hints_refuted;
  l.keyframes = s.keyframes;
  l.keyframes_fitted = s.keyframes_fitted;
  l.keyframes_degenerate = s.keyframes_degenerate;
  l.last_fitness_m = s.last_fitness_m;
  l.last_overlap = s.last_overlap;
  l.last_reason = s.last_reason;
  for (const auto& [from, to] : s.lost_spells) l.lost_s.emplace_back(since_start(from), since_start(to));
  // A trajectory that never found itself in the map claims nothing there: not to be trusted.
  if (!l.localized && r->untrusted.empty())
    r->untrusted = "not localized in the session's map (" + l.last_reason + ")";
  else if (!s.localized && r->untrusted.empty())
    r->untrusted = "lost in the session's map at the end";
}

// Trust: the stream after initialisation is covered by poses, few of them were degraded, and the
// IMU never carried the position alone long enough to drift far.
// Judged in the estimator's time, in which a stream whose time base jumped (a bag played again) runs
// on without a jump.
void System::judgeTrust(RunReport* r, Stamp stream_end_ns, const TrustLimits& limits) const {
  const PoseLog& poses = odometry_poses_;
  if (poses.empty()) return;
  const Stamp first_ns = poses.front().stamp_ns, last_ns = poses.back().stamp_ns;
  const double span_s = toSec(stream_end_ns - first_ns);
  // The last sweep may end just past the stream's end (a --duration cut): never more than all of it covered.
  r->sweeps.coverage = span_s > 0 ? std::min(1.0, toSec(last_ns - first_ns) / span_s) : 1.0;
  r->sweeps.degraded_fraction =
      static_cast<double>(r->sweeps.degraded) / static_cast<double>(std::max<std::size_t>(poses.size(), 1));
  const double limit = limits.max_degraded_fraction;
  char why[160] = "";
  if (r->sweeps.degraded_fraction > limit)
    std::snprintf(why, sizeof why, "%.0f %% of the sweeps degraded (limit %.0f %%)",
                  100.0 * r->sweeps.degraded_fraction, 100.0 * limit);
  else if (r->sweeps.coverage < 1.0 - limit)
    std::snprintf(why, sizeof why, "poses cover %.0f %% of the stream after initialisation (limit %.0f %%)",
                  100.0 * r->sweeps.coverage, 100.0 * (1.0 - limit));
  else if (const double drift = r->degeneracy.value("max_drift_sigma_m", 0.0); drift > limits.max_drift_sigma_m)
    std::snprintf(
        why, sizeof why,
        "the IMU carried the position alone long enough to drift by %.2f m (1 sigma, at %.0f s; limit %.2f m)", drift,
        r->degeneracy.value("max_drift_at_s", 0.0), limits.max_drift_sigma_m);
  r->untrusted = why;
}

RunReport System::writeOutputs(const std::string& dir_path, RunReport report, const std::string& gt_path) const {
  std::filesystem::create_directories(dir_path);
  const std::string dir = dir_path + "/";
  // One consistent snapshot of the back end: trajectory, maps and their figures.
  Trajectory trajectory;
  std::vector<Point> map_points, dynamic_map;
  std::map<std::string, std::vector<Point>> lidar_maps;
  Session session;
  Stopwatch assembly;
  mapping_.read([&](const backend::MappingBackend& b) {
    if (localizer_) return;  // the map is the session's; the trajectory is in its frame
    trajectory = inputTime(b.corrected(odometry_poses_));
    map_points = b.map();
    session = b.session();
    if (cfg_.mapping.dynamic_map) dynamic_map = b.dynamicMap();
    for (const std::string& lidar : b.lidarNames()) lidar_maps[lidar] = b.lidarMap(lidar);
  });
  report.dynamic.map_assembly_s = assembly.elapsedMs() * 1e-3;
  report.dynamic.dynamic_map_points = dynamic_map.size();

  if (localizer_) {
    trajectory = this->trajectory();
    map_points = session_->map;  // for the page's 3D view, in the frame of the trajectory
  } else if (T_map_odom_) {
    trajectory = inSession(std::move(trajectory));
    map_points = withSessionMap(std::move(map_points));
    dynamic_map = inSession(std::move(dynamic_map));
    for (auto& [lidar, points] : lidar_maps) points = inSession(std::move(points));
  }
  io::writeTum(dir + "trajectory.tum", trajectory);
  io::writeTum(dir + "trajectory_odometry.tum", odometryTrajectory());  // before loop correction
  if (cfg_.output.write_kitti) {
    io::writeKitti(dir + "trajectory.kitti", trajectory);
    io::writeKittiTimes(dir + "times.txt", trajectory);
  }
  RunReport::Outputs& out = report.outputs;
  out.trajectory = dir + "trajectory.tum";
  out.poses = trajectory.size();
  if (!localizer_) {
    io::writePcdBinary(dir + "map.pcd", map_points);
    out.map = dir + "map.pcd";
    out.map_points = map_points.size();
  }
  out.map_voxel_m = cfg_.mapping.map_leaf_m;
  for (const auto& [lidar, points] : lidar_maps) {
    const std::string path = dir + "map_" + lidar + ".pcd";
    io::writePcdBinary(path, points);
    out.per_lidar_maps[lidar] = path;
  }
  if (cfg_.mapping.dynamic_map) {
    io::writePcdBinary(dir + "map_dynamic.pcd", dynamic_map);
    out.dynamic_map = dir + "map_dynamic.pcd";
  }
  const std::vector<Point>* page_map = &map_points;
  if (cfg_.output.write_session && !localizer_) {
    for (SessionKeyframe& k : session.keyframes) k.stamp_ns = online_.externalStamp(k.stamp_ns);
    session = mergedSession(std::move(session));
    session.map = std::move(map_points);  // not copied (a hall's is 80 MB): the page reads it there
    page_map = &session.map;
    out.session = dir + "session";
    out.session_keyframes = session.keyframes.size();
    io::writeSession(out.session, session,
                     {io::kSessionFormatVersion, report.run.mmlio_version, report.run.commit, report.input.mode,
                      report.run.config_yaml});
  }
  report.memory.peak_rss_mb = peakRssMb();  // with the map's assembly and the session's writing
  writeReports(dir, report, trajectory, *page_map, gt_path);
  return report;
}

}  // namespace mmlio::pipeline
