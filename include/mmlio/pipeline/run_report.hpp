#pragma once
// What a run did, as data: the System fills it, the feeder (`mmlio run`, the ROS node) adds what
// only it knows about its input, and it becomes report.json and report.md at the edge
// (writeReports). Sections whose owners already summarise themselves (degeneracy spells, the
// back end's loops) stay JSON.
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mmlio/backend/loop_figures.hpp"
#include "mmlio/estimator/online_calibration.hpp"
#include "mmlio/eval/evaluation.hpp"
#include "mmlio/imu/initializer.hpp"
#include "mmlio/io/decode_stats.hpp"
#include "mmlio/pipeline/imu_gate.hpp"
#include "mmlio/pipeline/json.hpp"
#include "mmlio/pipeline/mount_check.hpp"
#include "mmlio/pipeline/stage_stats.hpp"
#include "mmlio/pipeline/stream_tally.hpp"

namespace mmlio::pipeline {

struct RunReport {
  struct Input {
    std::string source;  // bag path, or "live" (the node)
    std::string config;  // rig YAML path ("" = built-in defaults)
    std::string mode;
    double duration_s = 0.0;  // bag duration, or the time the node has run (sensor clock)
    std::size_t imu_messages = 0;
    double imu_acc_scale = 1.0;
    std::size_t skipped_messages = 0;  // failed to deserialise
    ImuGate::Counts imu_dropped;
    std::size_t scans_out_of_order = 0, scans_stamp_jumps = 0;
    Stamp scans_dropped_from_ns = 0, scans_dropped_to_ns = 0;    // stream position of the first / last drop
    std::size_t queue_dropped_imu = 0, queue_dropped_scans = 0;  // live: processing queue full
    bool truncated = false;
    std::size_t damaged_chunks = 0;  // damaged stretches of the bag skipped
    struct TimeBaseJump {
      double at_s = 0.0, shift_s = 0.0;  // input stamp where it happened; stamps shifted back by
    };
    std::vector<TimeBaseJump> time_base_jumps;       // the whole stream's time base jumped (see OnlinePipeline)
    std::map<std::string, io::DecodeStats> decoded;  // per LiDAR
    std::map<std::string, StreamTally::Stream> lidar_streams;  // scans received and missing, per LiDAR
    StreamTally::Stream imu_stream;                            // the IMU's accepted samples, and those missing
  };
  struct Sweeps {
    std::size_t processed = 0, tracked = 0, degraded = 0, initialising = 0, keyframes = 0, degenerate = 0;
    double degraded_fraction = 0.0;  // degraded / poses
    double coverage = 1.0;           // first to last pose over first pose to the stream's end
  };
  struct LidarFigures {
    std::size_t sweeps = 0, points = 0, edges = 0, planes = 0, bad_frames = 0;
  };
  struct Dynamic {
    bool enabled = true, clean_map = true;
    std::size_t sweeps_judged = 0;  // tested for movers (every sweep where they were lately, else at intervals)
    std::size_t feature_points_rejected = 0, sweeps_with_rejections = 0, local_map_points_carved = 0;
    std::size_t map_points_judged = 0, map_points_removed = 0, dynamic_map_points = 0;
    double map_assembly_s = 0.0;
  };
  // The IMU biases the estimator settled on: a MEMS IMU's stay within tenths of a m/s^2 and a few
  // hundredths of a rad/s; far beyond, the LiDARs and the IMU disagree on the motion.
  struct ImuBias {
    Eigen::Vector3d acc_end_m_s2 = Eigen::Vector3d::Zero(), gyro_end_rad_s = Eigen::Vector3d::Zero();
    double max_acc_m_s2 = 0.0, max_gyro_rad_s = 0.0;  // largest norms over the tracked sweeps
    double max_acc_at_s = 0.0, max_gyro_at_s = 0.0;   // seconds from the first IMU sample
  };
  // High-water marks of what the run held: the queues are bounded, so the resident memory is too.
  struct Memory {
    std::size_t sweeps_waiting_for_imu_max = 0;                     // at most ~2 s of sweeps (OnlinePipeline)
    std::size_t mapping_queue_max = 0, mapping_queue_capacity = 0;  // sweeps queued for the back end
    double peak_rss_mb = 0.0;                                       // the process's resident memory, MB
  };
  // A spinning LiDAR's calibration as refined while running (online_calibration).
  struct RefinedCalibration {
    LidarExtrinsic given;  // what the run started from
    estimator::LidarCalibrationEstimate last;
    Eigen::Isometry3d T_imu_sensor = Eigen::Isometry3d::Identity();  // given with the correction settled on
    struct Sample {
      double t_s = 0.0;  // seconds from the first IMU sample
      estimator::LidarCalibrationEstimate estimate;
    };
    std::vector<Sample> series;  // about one a second
  };
  struct Outputs {
    std::string trajectory, map, dynamic_map, session;
    std::size_t poses = 0, map_points = 0, session_keyframes = 0;
    double map_voxel_m = 0.0;
    std::map<std::string, std::string> per_lidar_maps;
  };

  // What reproduces the run: which mmlio, with which settings (report.json: run).
  struct Provenance {
    static constexpr int kSchemaVersion = 2;  // of report.json; raised when a field changes meaning
    std::string mmlio_version, commit;
    std::string calibration;  // where the extrinsics came from: config, a calibration file, auto
    std::string config_yaml;  // the effective config, extrinsics applied (also written as config_used.yaml)
  };

  // `mmlio localize`: finding the rig in a saved session's map (report.json: localization).
  struct Localization {
    bool enabled = false;
    std::string session;
    bool localized = false;         // found itself at some point
    bool localized_at_end = false;  // and was not lost at the end
    double first_localized_s = -1;  // seconds from the first IMU sample; -1: never
    int relocalizations = 0, relocalization_attempts = 0;
    int pose_hints = 0, pose_hints_refuted = 0;  // given while running (/initialpose), and not confirmed
    int keyframes = 0, keyframes_fitted = 0, keyframes_degenerate = 0;
    double last_fitness_m = 0, last_overlap = 0;
    std::vector<std::pair<double, double>> lost_s;  // spells, seconds from the first IMU sample (end -1: still)
    std::string last_reason;
  };

  // `mmlio run --extend`: mapping on in a saved session's frame (report.json: extension).
  struct Extension {
    bool enabled = false;
    std::string session;
    std::size_t session_keyframes = 0, session_map_points = 0;  // as loaded
    std::size_t keyframes_added = 0;
    std::size_t keyframes_tied = 0;  // ... placed by the session's map (tracked onto it) and tied there
    double localized_at_s = -1;      // when the localization that placed this run found it (first IMU sample: 0)
    Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();  // this run's odometry frame in the session's
  };

  std::string status = "complete";  // complete | degraded: ... | interrupted | incomplete: <error>
  std::string untrusted;            // empty, or why the outputs should not be trusted (exit code 3)
  Provenance run;
  Localization localization;
  Extension extension;
  Input input;
  MountCheck mount_check;  // HVI runs from a rig file: the spinning LiDAR's mount on the still start
  imu::ImuInitResult imu_init;
  ImuBias imu_bias;
  Sweeps sweeps;
  Json degeneracy = Json::object();
  std::map<std::string, LidarFigures> features;
  StageStats timing, timing_backend;
  double wall_time_s = 0.0, realtime_factor = 0.0;
  backend::LoopFigures mapping;
  std::string mapping_error;  // why the back end stopped, if it failed
  Dynamic dynamic;
  Memory memory;
  std::vector<RefinedCalibration> online_calibration;             // empty when off
  std::vector<RefinedCalibration> online_calibration_first_pass;  // when the bag was run again with it
  Outputs outputs;
  std::optional<eval::EvalResult> evaluation;  // with ground truth

  // One sample per tracked or degraded sweep, for report.html's plots over time (not in report.json).
  struct SweepSample {
    Stamp stamp_ns = 0;  // input clock, as the trajectory's
    float edges = 0.f, planes = 0.f;
    float weakest_points = 0.f;  // effective points along the least constrained translation
    float total_ms = 0.f;
    bool degenerate = false, degraded = false, keyframe = false;
  };
  std::vector<SweepSample> timeline;

  /// True when input was dropped, skipped, re-timed or cut short (the status then says "degraded").
  bool inputDegraded() const;
  /// "complete", or "degraded: ..." naming where the report says what happened to the input.
  std::string inputStatus() const;
};

Json toJson(const RunReport& report);
/// report.md: the summary (status, trust, ATE, sweeps, loops, input), pointing to report.html.
std::string toMarkdown(const RunReport& report);

}  // namespace mmlio::pipeline
