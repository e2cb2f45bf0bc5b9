#pragma once
// Tightly-coupled multi-LiDAR-inertial odometry (the paper's front end and sliding window).
//
// Per sweep window (all LiDARs cut to the reference LiDAR's sweep by lidar::SweepAligner):
//   IMU propagation -> de-skew of every point to the window end -> unified features per LiDAR
//   -> solid-state bad-frame check -> merge in the IMU frame, voxel filter
//   -> scan-to-map registration with an IMU preintegration factor (pose of every sweep)
//   -> keyframe? -> sliding-window optimisation over the last keyframes (edge, plane, IMU
//      factors, marginalisation prior) -> local map update.
// Core code: no ROS, no files. Feed IMU samples first, then sweeps whose end is covered by IMU.

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mmlio/core/timer.hpp"
#include "mmlio/core/types.hpp"
#include "mmlio/estimator/degeneracy.hpp"
#include "mmlio/estimator/free_space.hpp"
#include "mmlio/estimator/online_calibration.hpp"
#include "mmlio/imu/imu_noise.hpp"
#include "mmlio/imu/initializer.hpp"
#include "mmlio/lidar/bad_frame.hpp"
#include "mmlio/lidar/features.hpp"
#include "mmlio/lidar/sweep_aligner.hpp"

namespace mmlio::estimator {

/// Which LiDARs contribute every return as a plane candidate instead of only their scan-line plane
/// features. A scan line crosses a far surface (a corridor's end wall 50 m away) in fewer points
/// than a curvature neighbourhood needs, so line features never reach far; every return does, and
/// the map's local plane fit (k nearest map points, residual and 2-D spread checks) decides which
/// returns lie on a surface, whatever the scan pattern.
enum class SurfacePoints { kNone, kSolidState, kAll };

struct OdometryConfig {
  imu::ImuNoise imu_noise;
  imu::ImuInitConfig imu_init;
  double gravity_m_s2 = 9.81;
  lidar::FeatureConfig features;
  lidar::BadFrameConfig bad_frame;
  double edge_voxel_m = 0.2;   // downsampling of merged edge features
  double plane_voxel_m = 0.3;  // downsampling of merged plane features
  // Registration of a sweep matches at most this many features (thinned on a coarser grid; 0: all);
  // keyframes' window optimisation and the map use all. Off by default: it costs accuracy (docs/speed_history.md).
  int registration_max_edges = 0;
  int registration_max_planes = 0;
  SurfacePoints surface_points = SurfacePoints::kSolidState;
  double map_voxel_m = 0.2;                    // local map resolution
  bool voxel_planes = true;                    // planar local-map cells match by their plane, not a kNN fit
  double local_map_radius_m = 60.0;            // local map kept around the current pose
  int window_size = 4;                         // keyframes in the sliding window
  double keyframe_rotation_deg = 30.0;         // new keyframe after this rotation ...
  double keyframe_translation_m = 1.0;         // ... or this translation ...
  double keyframe_interval_s = 2.0;            // ... or this time
  int max_iterations = 10;                     // solver iterations per optimisation
  double huber_loss_m = 0.05;                  // robust loss scale of point-to-edge/plane residuals
  double lidar_sigma_m = 0.05;                 // point-to-map residual standard deviation
  int match_rounds = 2;                        // correspondence re-association rounds per sweep
  double prior_sigma_v_m_s = 0.05;             // registration: how far the previous sweep's velocity may move
  double prior_sigma_ba = 0.005;               // ... its accelerometer bias, m/s^2
  double prior_sigma_bg = 0.0005;              // ... its gyroscope bias, rad/s
  bool keep_points = true;                     // return de-skewed points for the map
  DegeneracyConfig degeneracy;                 // when a sweep's LiDAR information is too weak in a direction
  bool remap_degenerate = true;                // keep the IMU prediction along the directions found degenerate
  DynamicConfig dynamic;                       // returns on moving objects: rejected, and carved from the local map
  OnlineCalibrationConfig online_calibration;  // spinning LiDARs' extrinsic and clock refined while running
};

/// One LiDAR of the rig as the estimator sees it.
struct LidarSetup {
  LidarExtrinsic extrinsic;  // name, kind, T_imu_sensor (time offset applied by the caller)
  int num_rings = 16;
  bool refine_online = true;  // a spinning LiDAR's calibration is refined against the solid-state one's
};

struct LidarFrameStats {
  std::string sensor;
  std::size_t points = 0, edges = 0;
  std::size_t planes = 0;  // plane candidates: scan-line plane features, or every return (surface points)
  bool bad_frame = false;
  int counted_edges = 0;  // solid state: edges beyond the bad-frame range
  // This LiDAR's own map matches (registered sweeps only): weakest translation direction in
  // effective points (-1: not registered).
  double translation_points = -1.0;
};

struct SweepResult {
  enum class Status { kInitializing, kTracking, kDegraded };
  Status status = Status::kInitializing;
  NavState state;  // IMU state at the window end (valid unless initialising)
  bool keyframe = false;
  std::vector<LidarFrameStats> lidars;
  std::size_t correspondences = 0;
  Degeneracy degeneracy;        // of the scan-to-map registration (valid when registered)
  bool registered = false;      // matched against the map (not the first sweep, not degraded)
  int remapped_directions = 0;  // directions where the IMU prediction was kept
  // How far the position may have drifted along what the LiDARs have not observed lately: the
  // largest standard deviation of PredictionDrift after this sweep, m (0 when drift_m_s2 is 0).
  double drift_sigma_m = 0.0;
  std::vector<Point> points_body;          // de-skewed points in the body frame at the window end
  bool points_body_thinned = false;        // ... only those the map takes (the mapping back end's hand-off)
  std::vector<Point> points_dynamic_body;  // ... those on things that moved in (left out of points_body)
  bool judged_for_movers = false;          // its features were tested against earlier views (MoverWatch)
  std::size_t dynamic_points = 0;          // feature points rejected as moved in (registration, window, map)
  std::size_t carved_points = 0;           // local map points this sweep saw through (keyframes)
  // World positions where something moved this sweep: rejected features (with their neighbours)
  // and carved local-map points. The map's ghost removal judges only near these.
  std::vector<Eigen::Vector3d> moved_world;
  std::shared_ptr<const SweepView> view;  // what each LiDAR saw, placed at the final state (dynamic.enabled)
  // Extending a saved session: where its map places this keyframe (the world frame's pose), for the
  // mapping back end to tie it there. Set after the odometry, by the run that tracks the session.
  std::optional<Eigen::Isometry3d> T_world_body_measured;
  std::string note;  // why degraded
  StageTimes times_ms;
};

class Odometry {
 public:
  Odometry(OdometryConfig cfg, std::vector<LidarSetup> lidars);
  ~Odometry();

  void addImu(const ImuSample& sample);
  /// Processes one fused sweep. Requires IMU up to sweep.end_ns (else propagates at constant velocity).
  SweepResult process(lidar::AlignedSweep sweep);

  bool initialized() const;
  const imu::ImuInitResult& imuInit() const;
  std::size_t keyframes() const;
  Stamp lastImuNs() const;
  /// The online calibration's corrections of the refined LiDARs (empty when it is off).
  std::vector<LidarCalibrationEstimate> calibration() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mmlio::estimator
