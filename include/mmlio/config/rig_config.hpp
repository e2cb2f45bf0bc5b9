#pragma once
// Rig configuration: one YAML file per rig (config/hvi.yaml, vi.yaml, hi.yaml), read strictly —
// an unknown key, a wrong type, an invalid value or a missing file is an mmlio::Error naming the
// file and the key path (e.g. `lidars[1].topic`).
//
// The estimator's and the back end's settings are their own Config structs (RigConfig::estimator,
// ::mapping), bound here from the YAML sections users know (imu, features, bad_frame, odometry,
// loop, dynamic, output). Exposing a stage parameter = one `b.field(...)` line in rig_config.cpp
// (its doc string becomes the YAML comment); its default stays in the stage's struct.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "mmlio/backend/mapping_config.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/core/types.hpp"
#include "mmlio/estimator/odometry.hpp"

namespace mmlio::config {

struct LidarConfig {
  std::string name;   // unique, e.g. "velodyne", "livox"; calibration files key on it
  std::string type;   // velodyne | ouster | hesai | generic_spinning (PointCloud2) | livox (CustomMsg)
  std::string topic;  // ROS topic of the point clouds
  Eigen::Isometry3d T_imu_sensor = Eigen::Isometry3d::Identity();  // sensor -> IMU frame
  double time_offset_s = 0.0;                                      // t_imu = t_stamp + time_offset_s
  double min_range_m = 0.5;    // returns closer than this are dropped (rig, vehicle)
  double max_range_m = 100.0;  // returns farther than this are dropped
  int num_rings = 16;          // laser rings (VLP-16: 16) or Livox scan lines (Horizon: 6)
  bool enabled = true;         // false: ignored in every mode
  bool refine_online = true;   // spinning: extrinsic and clock refined while running (online_calibration)

  LidarKind kind() const;  // livox -> kSolidState, the others -> kSpinning
};

/// How the IMU arrives. Its noise model, gravity and initialisation window are the estimator's
/// (RigConfig::estimator), bound under the same `imu:` section.
struct ImuConfig {
  std::string topic = "/livox/imu";
  std::string acc_unit = "auto";  // auto | g | m/s2 (Livox reports g)
};

struct OutputConfig {
  bool write_kitti = false;   // also write trajectory.kitti + times.txt
  bool write_session = true;  // OUT/session/: keyframes, clouds, loops and map for a later run
};

/// The two LiDARs of the reference rig (Velodyne VLP-16 + Livox Horizon with its built-in IMU).
std::vector<LidarConfig> defaultLidars();

struct RigConfig {
  std::string mode = "hvi";                  // hvi (all LiDARs) | vi (spinning only) | hi (solid state only)
  std::string calibration = "config";        // config | auto | path to a calibration YAML
  std::string reference_lidar = "velodyne";  // its sweeps set the fusion window
  ImuConfig imu;
  std::vector<LidarConfig> lidars = defaultLidars();
  // The stages' own settings, bound from YAML directly (one default per parameter, in the stage):
  // imu noise / gravity / init, features, bad_frame, odometry, dynamic.enabled ...
  estimator::OdometryConfig estimator;
  // ... loop, dynamic.clean_map, output.map_voxel_m / per_lidar_maps / dynamic_map.
  backend::MappingConfig mapping;
  OutputConfig output;
  std::string source_path;  // file it was loaded from (not a YAML key)
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
/// The active spinning LiDARs of `mode` still on the presets' placeholder mount (0.2 m above the
/// IMU, axes aligned): fused with it, a real rig's two LiDARs disagree by the mount's error.
std::vector<std::string> placeholderExtrinsics(const RigConfig& cfg, const std::string& mode);
/// cfg.reference_lidar when active in `mode`, else the first active LiDAR. Throws if none is active.
const LidarConfig& referenceLidar(const RigConfig& cfg, const std::string& mode);
LidarExtrinsic toExtrinsic(const LidarConfig& lidar);

/// Overrides T_imu_sensor and time_offset_s of the LiDARs named in `calibration`; returns the
/// names of configured LiDARs the calibration does not cover. Throws if it names an unknown LiDAR.
std::vector<std::string> applyCalibration(RigConfig& cfg, const Calibration& calibration);

}  // namespace mmlio::config
