#pragma once
// Rig configuration: one YAML file per rig (config/hvi.yaml, vi.yaml, hi.yaml), read strictly —
// an unknown key, a wrong type, an invalid value or a missing file is an mmlio::Error naming the
// file and the key path (e.g. `lidars[1].topic`).
//
// Adding a field = one struct member with its default here + one `b.field(...)` line in the
// matching bind function in rig_config.cpp (its doc string becomes the YAML comment).

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/io/calib_file.hpp"

namespace mmlio::io {

struct LidarConfig {
  std::string name;   // unique, e.g. "velodyne", "livox"; calibration files key on it
  std::string type;   // velodyne | ouster | hesai | generic_spinning (PointCloud2) | livox (CustomMsg)
  std::string topic;  // ROS topic of the point clouds
  Eigen::Isometry3d T_imu_sensor = Eigen::Isometry3d::Identity();  // sensor -> IMU frame
  double time_offset_s = 0.0;  // t_imu = t_stamp + time_offset_s
  double min_range_m = 0.5;    // returns closer than this are dropped (rig, vehicle)
  double max_range_m = 100.0;  // returns farther than this are dropped
  int num_rings = 16;          // laser rings (VLP-16: 16) or Livox scan lines (Horizon: 6)
  bool enabled = true;         // false: ignored in every mode

  LidarKind kind() const;  // livox -> kSolidState, the others -> kSpinning
};

struct ImuConfig {
  std::string topic = "/livox/imu";
  std::string acc_unit = "auto";           // auto | g | m/s2 (Livox reports g)
  double acc_noise_density = 0.05;         // m/s^2/sqrt(Hz)
  double gyro_noise_density = 0.005;       // rad/s/sqrt(Hz)
  double acc_bias_random_walk = 0.001;     // m/s^3/sqrt(Hz)
  double gyro_bias_random_walk = 0.0001;   // rad/s^2/sqrt(Hz)
  double gravity_m_s2 = 9.81;
  double init_duration_s = 1.0;            // standstill used to estimate gravity and gyro bias
};

struct FeatureConfig {
  int neighbours = 5;               // points each side for curvature / scatter
  double edge_threshold = 1.0;      // curvature above which a point is an edge
  double plane_threshold = 0.1;     // curvature below which a point is a plane
  double continuity_jump_m = 0.3;   // depth jump that breaks a neighbourhood (occlusion)
};

struct BadFrameConfig {
  bool enabled = true;              // drop solid-state frames too poor in structure
  std::string criterion = "information";  // information | edges
  double min_edge_range_m = 2.0;    // only edges beyond this range count
  int min_edge_points = 100;        // tau_e: fewer counted edges -> bad frame
};

struct OdometryConfig {
  double edge_voxel_m = 0.2;             // downsampling of edge features
  double plane_voxel_m = 0.3;            // downsampling of plane features
  std::string surface_points = "solid_state";  // solid_state | all | none: every return is a plane candidate
  double degenerate_min_points = 30.0;   // weaker LiDAR information along a direction: IMU prediction kept
  bool remap_degenerate = true;          // keep the IMU prediction along degenerate directions
  double map_voxel_m = 0.2;              // local map resolution
  double local_map_radius_m = 60.0;      // local map kept around the current pose
  int window_size = 4;                   // keyframes in the sliding window
  double keyframe_rotation_deg = 30.0;   // new keyframe after this rotation ...
  double keyframe_translation_m = 1.0;   // ... or this translation ...
  double keyframe_interval_s = 2.0;      // ... or this time
  int max_iterations = 10;               // solver iterations per window
  double huber_loss_m = 0.05;            // robust loss scale of point-to-edge/plane residuals
};

struct LoopConfig {
  bool enabled = true;
  double search_radius_m = 10.0;   // candidates: past keyframes within this distance
  double min_time_gap_s = 20.0;    // ... and at least this much older
  double max_fitness_m = 0.1;      // accept: mean ICP residual below this
  double min_overlap = 0.5;        // accept: inlier fraction above this (0..1)
};

struct DynamicObjectsConfig {
  bool enabled = true;             // returns on moving objects leave the odometry and its local map
  bool clean_map = true;           // map.pcd: points later sweeps saw through are removed (ghosts)
};

struct OutputConfig {
  double map_voxel_m = 0.05;       // map.pcd downsampling; 0 = keep every point
  bool per_lidar_maps = false;     // also write map_<lidar>.pcd
  bool write_kitti = false;        // also write trajectory.kitti + times.txt
  bool dynamic_map = true;         // also write map_dynamic.pcd: what was removed as moving
};

/// The two LiDARs of the reference rig (Velodyne VLP-16 + Livox Horizon with its built-in IMU).
std::vector<LidarConfig> defaultLidars();

struct RigConfig {
  std::string mode = "hvi";                // hvi (all LiDARs) | vi (spinning only) | hi (solid state only)
  std::string calibration = "config";      // config | auto | path to a calibration YAML
  std::string reference_lidar = "velodyne";  // its sweeps set the fusion window
  ImuConfig imu;
  std::vector<LidarConfig> lidars = defaultLidars();
  FeatureConfig features;
  BadFrameConfig bad_frame;
  OdometryConfig odometry;
  LoopConfig loop;
  DynamicObjectsConfig dynamic;
  OutputConfig output;
  std::string source_path;                 // file it was loaded from (not a YAML key)
};

/// Loads and validates. A calibration path is resolved against the file's directory and must exist.
RigConfig loadRigConfig(const std::string& path);
/// Same from YAML text; `source_name` names it in errors.
RigConfig parseRigConfig(const std::string& yaml_text, const std::string& source_name = "<config>");
/// Throws mmlio::Error naming cfg.source_path and the key path of the first invalid value.
void validateRigConfig(const RigConfig& cfg);

/// Every field with its doc comment and value, "(default: X)" on each comment; parses back to cfg.
std::string toYaml(const RigConfig& cfg);
/// toYaml(RigConfig{}) with a header: what `mmlio config --dump-defaults` prints.
std::string defaultConfigYaml();

bool isValidMode(const std::string& mode);
/// Enabled LiDARs used by `mode`: hvi all, vi spinning, hi solid state. Throws on a bad mode.
std::vector<const LidarConfig*> activeLidars(const RigConfig& cfg, const std::string& mode);
/// cfg.reference_lidar when active in `mode`, else the first active LiDAR. Throws if none is active.
const LidarConfig& referenceLidar(const RigConfig& cfg, const std::string& mode);
LidarExtrinsic toExtrinsic(const LidarConfig& lidar);

/// Overrides T_imu_sensor and time_offset_s of the LiDARs named in `calibration`; returns the
/// names of configured LiDARs the calibration does not cover. Throws if it names an unknown LiDAR.
std::vector<std::string> applyCalibration(RigConfig& cfg, const Calibration& calibration);

}  // namespace mmlio::io
