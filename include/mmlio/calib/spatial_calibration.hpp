#pragma once
// Spatial LiDAR-to-LiDAR calibration on a stationary start (paper, "Spatial calibration"): the
// solid-state LiDAR's frames, accumulated while the rig stands still, fill its narrow field of
// view densely; a spinning sweep taken in the same window is registered onto them by GICP on the
// overlapping region. T_solid_spinning then chains with the factory IMU-to-solid-state
// extrinsic: T_imu_spinning = T_imu_solid * T_solid_spinning.
//
// Without a usable initial guess a yaw search runs GICP from every yaw_step_deg about the solid
// LiDAR's vertical axis and keeps the best (mounts differ mostly by yaw on real rigs).
#include <optional>
#include <string>
#include <vector>

#include "mmlio/calib/gicp.hpp"

namespace mmlio::calib {

struct SpatialCalibrationConfig {
  double solid_fov_horizontal_deg = 81.7;  // the solid-state field of view: the overlap region
  double solid_fov_vertical_deg = 25.1;
  double fov_margin_deg = 5.0;  // spinning points this far outside the FOV are kept too
  double min_range_m = 1.0;     // closer returns are dropped (rig, operator)
  double max_range_m = 40.0;
  double target_voxel_m = 0.05;                // accumulated solid-state cloud
  double source_voxel_m = 0.05;                // spinning sweep
  double yaw_step_deg = 15.0;                  // yaw search grid
  double max_fitness_m = 0.05;                 // accept: mean inlier distance at most this ...
  double min_overlap = 0.5;                    // ... and this fraction of cropped spinning points matched
  int min_points = 500;                        // fewer points on either side: refuse
  double min_translation_conditioning = 0.05;  // weakest / strongest translation eigenvalue of the GICP
                                               // Hessian below this: degenerate overlap (a wall), refuse
  GicpConfig gicp = [] {
    GicpConfig g;
    g.source_covariances = false;  // a 16-ring sweep is too sparse across rings for its own covariances
    g.max_corr_dist_coarse_m = 0.5;
    g.max_corr_dist_fine_m = 0.05;  // measured: 0.1 m left a 5 mm bias along the view (the office start), 0.05 m 2-4 mm
    return g;
  }();
};

struct SpatialCalibrationResult {
  bool ok = false;
  std::string message;  // what was found, or why it was refused
  Eigen::Isometry3d T_solid_spinning = Eigen::Isometry3d::Identity();
  double fitness_m = 0, overlap = 0;
  int spinning_points = 0, solid_points = 0;  // used, after cropping and voxel filtering
  bool yaw_searched = false;
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();  // GICP, (dp, dtheta)
};

/// spinning: one (or a few stacked) stationary sweep(s), spinning-sensor frame; solid: the
/// accumulated stationary frames, solid-sensor frame. guess: T_solid_spinning from the config, or
/// none for the yaw search.
SpatialCalibrationResult calibrateSpinningToSolid(const std::vector<Eigen::Vector3d>& spinning,
                                                  const std::vector<Eigen::Vector3d>& solid,
                                                  const std::optional<Eigen::Isometry3d>& guess,
                                                  const SpatialCalibrationConfig& cfg = SpatialCalibrationConfig());

}  // namespace mmlio::calib
