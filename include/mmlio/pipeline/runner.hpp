#pragma once
// The main job: a ROS1 bag in; trajectory.tum, map.pcd and report.json (and report.md) out.
//
// A feeder of pipeline::System: io::BagSource (time order) -> System -> outputs. A failure mid-bag
// still writes what was computed (marked incomplete in the report) before the error is reported.
#include <functional>
#include <memory>
#include <optional>
#include <atomic>
#include <string>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/types.hpp"
#include "mmlio/pipeline/mount_check.hpp"
#include "mmlio/pipeline/run_report.hpp"
#include "mmlio/pipeline/stage_stats.hpp"
#include "mmlio/pipeline/system.hpp"

namespace mmlio::pipeline {

struct RunOptions {
  std::string bag_path;
  std::string out_dir;                      // empty: write nothing (bench)
  config::RigConfig config;                 // calibration already applied
  std::string mode;                         // empty: config.mode
  bool progress = true;                     // progress bar on stderr
  std::string gt_path;                      // optional TUM ground truth: evaluation in the report
  double max_duration_s = 0.0;              // > 0: stop after this much bag time
  int replays = 1;                          // > 1: the bag is played this many times back to back, shifted in
                                            // time, as ONE sequence (long-run memory and drift checks)
  const std::atomic<bool>* stop = nullptr;  // set (e.g. by a signal handler): stop reading, write
                                            // what was computed, status "interrupted"
  TrustLimits trust;                        // beyond them RunResult::untrusted says why
  // `mmlio localize`: a session folder to localize in instead of mapping (no loop closure, no
  // second pass; the trajectory in the session's map frame), and optionally where the rig starts
  // in it (T_map_body, roughly).
  std::shared_ptr<const Session> session;  // io::readSession's
  std::string session_dir;                 // where it was read from (the report names it)
  std::optional<Eigen::Isometry3d> initial_pose;
  // `mmlio run --extend`: with a session, localize the bag's start in it first, then map as
  // usual in its frame; the map and the session written are the session's grown by this run.
  bool extend = false;
  // A second pass with the calibration a first one refined (online_calibration.rerun): what the
  // first pass found (the report keeps it), and the outputs are left alone if it is interrupted.
  std::vector<RunReport::RefinedCalibration> first_pass_calibration;
  int pass = 1;
  bool write_if_interrupted = true;
  // HVI: check the spinning LiDAR's mount on the bag's still start first (checkMountAtStart); one
  // that the start's clouds contradict makes the outputs untrusted.
  bool check_mount = false;
  std::optional<MountCheck> mount_check;  // its result, carried into every pass's report
  /// Every tracked sweep's stamp, stage times and pass of the bag (0 unless replayed), on the
  /// reading thread (bench records its time-and-memory curve).
  std::function<void(Stamp sweep_end_ns, const StageTimes& times_ms, int replay)> on_sweep;
};

struct RunResult {
  Trajectory trajectory;      // IMU pose at the end of every tracked sweep
  StageStats timing;          // the sweep loop (odometry and hand-off), per sweep
  StageStats backend_timing;  // the mapping back end, per sweep, on its own thread
  RunReport report;
  std::size_t map_points = 0;
  bool complete = true;      // false: the bag ended in an error after `trajectory`
  bool interrupted = false;  // options.stop was set: the outputs hold the run so far
  std::string error;
  std::string untrusted;  // non-empty: why the outputs should not be trusted (also in the report)
};

/// Runs the whole pipeline. Throws mmlio::Error for unusable input (no bag, no topic, ...);
/// an error after tracking started is returned in RunResult::error with outputs written.
RunResult runBag(const RunOptions& options);

}  // namespace mmlio::pipeline
