#pragma once
// Online refinement of the rig's calibration while the odometry runs: each spinning LiDAR's
// extrinsic and clock offset, relative to the solid-state LiDAR (the anchor, whose built-in IMU is
// the body frame).
//
// A LiDAR whose extrinsic or clock is off places its points rigidly off from the anchor's: by the
// extrinsic error, and by the motion over the clock error (a point taken at t + dt but de-skewed as
// taken at t sits off by (v + w x p) dt in the body frame). So each tracked sweep, both LiDARs'
// features are matched against a map of the anchor's own features (keyframes at their optimised
// poses), and the sweep's pose is eliminated (Schur complement) from the normal equations of
// [pose, rotation, translation, clock] of every refined LiDAR: what is left is what this sweep
// says about the calibration alone. A single sweep cannot tell a clock error from an extrinsic one
// (its clock column is a rigid motion); sweeps with different motion can, and the information
// adds up where the motion makes them observable and nowhere else. The information fades over
// memory_s (a calibration that drifts, a map that does), never below the prior's.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/estimator/map_matching.hpp"
#include "mmlio/map/voxel_hash_map.hpp"

namespace mmlio::estimator {

struct OnlineCalibrationConfig {
  bool enabled = true;
  double prior_sigma_time_s = 0.05;           // how far the given clock offset may be off
  double prior_sigma_rotation_deg = 2.0;      // ... the given extrinsic's rotation
  double prior_sigma_translation_m = 0.05;    // ... its translation along the IMU's x and y (0: kept as given)
  double prior_sigma_translation_z_m = 0.05;  // ... and along z (0: kept as given)
  double memory_s = 60.0;                     // older sweeps' information fades with this time constant
  // Offline (mmlio run): when the run ends with a calibration that differs from the given one (2 ms,
  // 0.1 deg, 5 mm), the bag is measured again from it (measure_only), then run from what that found.
  // Read by the runner, not the odometry.
  bool rerun = true;
  // Corrections go into the de-skew and placement as they are determined. Off by default: applied
  // mid-run, a correction leaves the map built before it inconsistent with what follows (a stairs
  // run went from 4.8 cm ATE with the same calibration fixed to 47 cm); mmlio run re-runs the bag
  // instead (rerun), the live nodes report the estimate. Ignored by mmlio run while rerun is on.
  bool apply = false;
  // The refined LiDARs' points stay out of the odometry (registration, window, map): the pass
  // measures their calibration against the anchor alone, unpulled by their own error.
  bool measure_only = false;
};

/// One refined LiDAR's correction of its given calibration, and its standard deviations.
struct LidarCalibrationEstimate {
  std::string sensor;
  // T_imu_sensor = [R(rotation) R0, t0 + translation]: rotation about the sensor's origin, in the
  // IMU frame; time_offset_s adds to the given clock offset.
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();
  double time_offset_s = 0.0;
  // The estimate: applied (above) once the motion has determined it.
  Eigen::Vector3d estimate_rotation_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d estimate_translation_m = Eigen::Vector3d::Zero();
  double estimate_time_offset_s = 0.0;
  // What a next run should start from: the estimate where it is roughly determined, else what was applied.
  Eigen::Vector3d settled_rotation_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d settled_translation_m = Eigen::Vector3d::Zero();
  double settled_time_offset_s = 0.0;
  Eigen::Vector3d rotation_sigma_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_sigma_m = Eigen::Vector3d::Zero();
  double time_offset_sigma_s = 0.0;
  std::size_t sweeps = 0;  // sweeps that informed it
};

class OnlineCalibration {
 public:
  /// One entry per LiDAR of the odometry (its index is the features' source): refine[i] marks the
  /// refined ones, anchor the solid-state LiDAR they are refined against (-1: none, inactive).
  OnlineCalibration(OnlineCalibrationConfig cfg, std::vector<LidarExtrinsic> lidars, std::vector<char> refine,
                    int anchor, double map_voxel_m, double lidar_sigma_m, double map_radius_m);

  /// Features of each LiDAR a sweep hands over (the anchor's keyframes build the anchor map from
  /// them), and how many of those are matched per sweep.
  static constexpr std::size_t kFeaturesPerLidar = 4000;
  static constexpr std::size_t kMatchedPerLidar = 1000;

  bool active() const { return active_; }
  std::size_t anchor() const { return static_cast<std::size_t>(anchor_); }
  bool refines(std::size_t lidar) const { return active_ && refine_[lidar]; }
  /// LiDAR i only measured, not used by the odometry (measure_only).
  bool measuresOnly(std::size_t lidar) const { return refines(lidar) && cfg_.measure_only; }

  /// LiDAR i's calibrated extrinsic with the current correction (the given one where not refined).
  Eigen::Isometry3d extrinsic(std::size_t lidar) const;
  /// How this sweep's de-skewed points of LiDAR i move for its clock correction: a body-frame
  /// rigid motion over the correction at the body's velocity and turn rate (identity if not refined).
  Eigen::Isometry3d clockShift(std::size_t lidar, const Eigen::Vector3d& v_body, const Eigen::Vector3d& w_body) const;

  /// A keyframe: the anchor's features (body frame) at its optimised pose join the anchor map.
  void addAnchorKeyframe(const Features& f, const Eigen::Isometry3d& T_world_body);
  /// A tracked sweep: its features (each LiDAR thinned on its own, placed with the correction
  /// current when they were extracted, the clock shift made at v_body / w_body) at its registered
  /// pose. Returns whether it informed the calibration.
  bool observe(const Features& f, const Eigen::Isometry3d& T_world_body, const Eigen::Vector3d& v_body,
               const Eigen::Vector3d& w_body, Stamp stamp_ns);

  std::vector<LidarCalibrationEstimate> estimates() const;

 private:
  Eigen::MatrixXd priorInfo() const;
  /// f with each refined LiDAR's points moved from where the applied corrections placed them to
  /// where the estimated ones do.
  Features placedAtEstimate(Features f, const Eigen::Vector3d& v_body, const Eigen::Vector3d& w_body) const;
  void applyDetermined();

  static constexpr int kParams = 7;  // rotation 3, translation 3, clock 1
  using Vec = Eigen::Matrix<double, kParams, 1>;
  using Mat = Eigen::Matrix<double, kParams, kParams>;
  struct Refined {
    std::size_t lidar = 0;
    std::size_t sweeps = 0;
  };

  OnlineCalibrationConfig cfg_;
  std::vector<LidarExtrinsic> given_;
  std::vector<char> refine_;
  int anchor_ = -1;
  bool active_ = false;
  double lidar_sigma_m_, map_radius_m_;
  Mat prior_info_ = Mat::Zero();  // of one refined LiDAR
  std::vector<Refined> refined_;
  Eigen::VectorXd x_;         // the corrections applied, kParams per refined LiDAR
  Eigen::VectorXd estimate_;  // the corrections estimated (applied where determined)
  Eigen::MatrixXd info_;      // the estimate's information
  Eigen::VectorXd info_x_;    // info_ * estimate_, as accumulated
  map::VoxelHashMap edge_map_, plane_map_;
  Stamp last_ns_ = 0;
  int anchor_keyframes_ = 0;
};

}  // namespace mmlio::estimator
