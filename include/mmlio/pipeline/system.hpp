#pragma once
// mmlio as one system: IMU samples and LiDAR scans in (any interleaving), a pose out for every
// tracked sweep, the mapping back end (loop closure, corrected trajectory, submaps, ghost removal)
// on its own thread, and the run's report. `mmlio run` (a bag) and `mmlio_node` (live topics) are
// feeders of it: they differ only in where the data comes from and where the results go.
//
// Threads: addImu/addScan/flush/finish and the observer run on the feeding thread. The live
// queries (trajectory, map, mapFromOdom, report) may be called from it at any time: they read the
// back end between two of its sweeps.
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mmlio/backend/map_localizer.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/pose_log.hpp"
#include "mmlio/core/timer.hpp"
#include "mmlio/pipeline/degeneracy_tally.hpp"
#include "mmlio/pipeline/mapping_thread.hpp"
#include "mmlio/pipeline/online_pipeline.hpp"
#include "mmlio/pipeline/run_report.hpp"

namespace mmlio::pipeline {

/// When outputs are not to be trusted (RunReport::untrusted says why).
struct TrustLimits {
  double max_degraded_fraction = 0.25;  // more degraded sweeps than this, or poses covering less than
                                        // 1 - this of the stream after initialisation
  double max_drift_sigma_m = 0.3;       // ... or the position's uncertainty along what the LiDARs had not
                                        // observed for a while above this (degeneracy.max_drift_sigma_m)
};

class System {
 public:
  /// Every sweep after IMU initialisation, as soon as it is tracked (the node publishes from it).
  using SweepObserver = std::function<void(const estimator::SweepResult&)>;
  /// Every tracked sweep's stamp and stage times, after its hand-off (no copy of the sweep).
  using TimingObserver = std::function<void(Stamp sweep_end_ns, const StageTimes& times_ms)>;

  /// Throws mmlio::Error on a bad mode or a config with no active LiDAR.
  System(const config::RigConfig& cfg, const std::string& mode, SweepObserver observer = {});

  void addImu(const ImuSample& sample) {
    if (first_imu_ns_ == 0) first_imu_ns_ = sample.stamp_ns;
    online_.addImu(sample);
  }
  /// scan.sensor names a configured LiDAR (others are ignored); its clock offset is applied here.
  void addScan(LidarScan scan) { online_.addScan(std::move(scan)); }
  void setTimingObserver(TimingObserver observer) { timing_observer_ = std::move(observer); }
  /// Localize in a saved session instead of mapping anew (before the first sample): the trajectory
  /// is then in the session's map frame, and neither a map nor a session is written.
  /// initial_pose: T_map_body at the start, roughly, or none.
  void localizeIn(std::shared_ptr<const Session> session, const std::string& session_dir,
                  const std::optional<Eigen::Isometry3d>& initial_pose = std::nullopt);
  /// Map on in a saved session instead of a new world (before the first sample): this run's
  /// odometry frame lies at T_map_odom in the session's (found by localizing the bag's start in
  /// it, localized_at_s in). The trajectory, the map and the session come out in the session's
  /// frame, the map and the session merged with it; what the session maps is not mapped again.
  void extend(std::shared_ptr<const Session> session, const std::string& session_dir,
              const Eigen::Isometry3d& T_map_odom, double localized_at_s);
  /// While localizing: the rig is roughly at T_map_body now (an operator's hint, rviz's "2D Pose
  /// Estimate"), tried at the next keyframe (without height: see MapLocalizer::hint). False when
  /// not localizing.
  bool hintPose(const Eigen::Isometry3d& T_map_body, bool with_height = true);
  /// While localizing, where it stands; null otherwise.
  const backend::LocalizationStatus* localization() const { return localizer_ ? &localizer_->status() : nullptr; }
  /// End of the stream: the sweeps still waiting for IMU are processed.
  void flush() { online_.flush(); }
  /// Waits for the back end and runs its final loop check. A failing back end is logged and
  /// stated in the report; the trajectory and the map so far stay available. Idempotent.
  void finish();

  /// Odometry poses (IMU frame, one per tracked sweep), not corrected by loops (in the session's
  /// frame when extending one).
  Trajectory odometryTrajectory() const { return inSession(inputTime(odometry_poses_.trajectory())); }
  std::size_t posesTracked() const { return odometry_poses_.size(); }
  /// The same poses corrected by the loops closed so far.
  Trajectory trajectory() const;
  /// The keyframes' poses and the newest one, corrected as trajectory() is: the live nodes' path
  /// (the whole trajectory rebuilt at every keyframe would cost O(poses) each time).
  Trajectory route() const;
  /// Loop correction at the newest pose, map <- odom (identity before the first loop).
  Eigen::Isometry3d mapFromOdom() const;
  /// The input's stamp of an estimator stamp (SweepResult::state): after a jump of the input's time
  /// base the estimator runs on shifted stamps (see OnlinePipeline::externalStamp).
  Stamp externalStamp(Stamp internal_ns) const;
  std::size_t loops() const;
  /// The map at the corrected poses (the back end pauses while it is assembled).
  std::vector<Point> map() const;
  /// The run so far; the feeder adds what it knows of its input (source, decoding, drops). Coverage,
  /// degraded fraction and trust are judged against a stream that ran to stream_end_ns (the bag's
  /// end, or the last message a live node received; 0: the last IMU sample processed).
  RunReport report(Stamp stream_end_ns = 0, const TrustLimits& limits = {}) const;
  /// trajectory.tum (corrected; + KITTI if configured), trajectory_odometry.tum, map.pcd, per-LiDAR and dynamic maps,
  /// report.json, report.md and figures into dir (created); returns the report as written. The files are replaced
  /// atomically, so a live save never leaves a half-written one.
  RunReport writeOutputs(const std::string& dir, RunReport report, const std::string& gt_path = "") const;

  const estimator::Odometry& odometry() const { return online_.odometry(); }
  std::size_t sweepsProcessed() const { return online_.sweepsProcessed(); }
  const config::RigConfig& config() const { return cfg_; }
  const std::string& mode() const { return mode_; }

 private:
  void onSweep(estimator::SweepResult r);
  void judgeTrust(RunReport* report, Stamp stream_end_ns, const TrustLimits& limits) const;
  void reportLocalization(RunReport* report) const;
  void sampleCalibration(Stamp stamp_ns);
  void trackImuBias(const estimator::SweepResult& r);
  std::vector<RunReport::RefinedCalibration> refinedCalibration() const;
  /// Estimator stamps back in the input's time (they differ after a time-base jump).
  Trajectory inputTime(Trajectory trajectory) const;
  /// Poses and points of this run's world in the session's frame when extending one (else as given).
  Trajectory inSession(Trajectory trajectory) const;
  std::vector<Point> inSession(std::vector<Point> points) const;
  /// This run's map points in the session's frame after the session's own (as they are otherwise).
  std::vector<Point> withSessionMap(std::vector<Point> added) const;
  /// The session extended, then this run's keyframes and loops, in its frame.
  Session mergedSession(Session added) const;

  config::RigConfig cfg_;
  std::string mode_;
  std::string effective_config_yaml_;  // report.json -> run.config_yaml, config_used.yaml
  SweepObserver observer_;
  TimingObserver timing_observer_;
  MappingThread mapping_;
  DegeneracyTally degeneracy_;
  RunReport::Sweeps sweeps_;
  RunReport::Dynamic dynamic_;
  std::map<std::string, RunReport::LidarFigures> lidars_;
  RunReport::ImuBias imu_bias_;
  StageStats timing_;
  std::vector<RunReport::SweepSample> timeline_;
  PoseLog odometry_poses_;                   // estimator stamps: the back end corrects them by its keyframes' stamps
  std::vector<std::size_t> keyframe_poses_;  // indices into odometry_poses_
  Stamp first_imu_ns_ = 0;
  std::vector<RunReport::RefinedCalibration::Sample> calibration_series_;
  Stamp next_calibration_sample_ns_ = 0;
  std::string backend_error_;
  bool finished_ = false;
  Stopwatch wall_;
  // Localization: the session (kept here: the localizer refers to it) and the localizer.
  std::shared_ptr<const Session> session_;
  std::string session_dir_;
  std::unique_ptr<backend::MapLocalizer> localizer_;
  // Extending: where this run's world lies in the session's, and when that was found; the
  // session's map tracked as localization does, to tie the keyframes it places.
  std::optional<Eigen::Isometry3d> T_map_odom_;
  std::unique_ptr<backend::MapLocalizer> tracker_;
  double extension_localized_at_s_ = -1;
  OnlinePipeline online_;  // last: its callback uses the members above
};

}  // namespace mmlio::pipeline
