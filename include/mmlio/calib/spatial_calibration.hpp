#pragma once
// Spatial LiDAR-to-LiDAR calibration on a stationary start (paper, "Spatial calibration"): the
// solid-state LiDAR's frames, accumulated while the rig stands still, fill its narrow field of
// view densely; a spinning sweep taken in the same window is registered onto them by GICP on the
// overlapping region. T_solid_spinning then chains with the factory IMU-to-solid-state
// extrinsic: T_imu_spinning = T_imu_solid * T_solid_spinning.
//
// Without a usable initial guess a yaw search runs GICP from every yaw_step_deg about the solid
// LiDAR's vertical axis (mounts differ mostly by yaw on real rigs), measures its best few again on
// the view their own results give, and keeps the one that explains most spinning points without
// putting any where the solid-state LiDAR sees through; two mounts that explain about as much are
// refused (a symmetric view), not guessed between.
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
  bool yaw_search = true;                      // false: only the guess is tried (checking a given mount)
  double yaw_step_deg = 15.0;                  // yaw search grid
  double max_fitness_m = 0.05;                 // accept: mean inlier distance at most this ...
  double min_overlap = 0.5;                    // ... and this fraction of cropped spinning points matched
  double max_seen_through = 0.02;              // ... and at most this fraction of the spinning points in view
                                               // in front of the solid-state LiDAR's return (see through)
  double seen_through_bin_deg = 0.5;           // direction bins of the solid-state returns
  double seen_through_margin_m = 0.2;          // a point is seen through when the return behind it is this
  double seen_through_margin_fraction = 0.05;  // much (plus this fraction of its range) farther
  int yaw_finalists = 4;                       // distinct best starts of the yaw search measured again
  double distinct_translation_m = 0.1;         // finalists closer than this and ...
  double distinct_rotation_deg = 5.0;          // ... this are the same mount
  double ambiguity_ratio = 0.8;                // the runner-up explains this fraction of the winner's points: refuse
  bool probe_quarter_turns = true;             // a guess that fits: its quarter turns fitting as well refuse too
  int sigma_groups = 10;                       // the stated uncertainty covers leaving out any one of this many
                                               // azimuth strips of the spinning points in view ...
  double sigma_floor_translation_m = 0.0015;   // ... plus what no strip reveals, a bias they all share (the
  double sigma_floor_rotation_deg = 0.015;     // voxel filter, mixed pixels at edges), per axis
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

/// One distinct finalist of the yaw search, best first.
struct MountCandidate {
  Eigen::Isometry3d T_solid_spinning = Eigen::Isometry3d::Identity();
  double yaw_deg = 0;  // the spinning LiDAR's x axis in the solid-state frame
  double fitness_m = 0, overlap = 0;
  int inliers = 0, points_in_view = 0;
  double seen_through = 0;
  bool agrees = false;  // passes fitness, overlap and seen-through
};

struct SpatialCalibrationResult {
  // Why it was refused: the start cannot tell (too few points, no overlap, degenerate, ambiguous)
  // or the clouds contradict the mount found (not converged, seen through, disagree).
  enum class Refusal {
    kNone,
    kTooFewPoints,
    kNoOverlap,
    kNotConverged,
    kSeenThrough,
    kDisagree,
    kDegenerate,
    kAmbiguous
  };
  bool ok = false;
  Refusal refusal = Refusal::kNone;
  std::string message;  // what was found, or why it was refused
  Eigen::Isometry3d T_solid_spinning = Eigen::Isometry3d::Identity();
  double fitness_m = 0, overlap = 0;
  int spinning_points = 0, solid_points = 0;  // used, after cropping and voxel filtering
  bool yaw_searched = false;
  double seen_through = 0;                 // fraction of the spinning points in view the solid-state LiDAR sees through
  std::vector<MountCandidate> candidates;  // the yaw search's finalists, best first
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();  // GICP, (dp, dtheta)
  // The stated uncertainty of T_solid_spinning: (translation, rotation about the solid-state axes),
  // m and rad, from leaving out parts of the scene (SpatialCalibrationConfig::sigma_groups).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

/// Whether a registration of the two views passes the calibration's tests of agreement: fitness,
/// overlap and the fraction seen through (convergence aside).
bool cloudsAgree(double fitness_m, double overlap, double seen_through, const SpatialCalibrationConfig& cfg);

/// What the solid-state LiDAR saw, in its frame at the still start. A still start alone is one
/// frame; the first seconds of motion (the solid-state LiDAR's own odometry placing its frames)
/// see the room around. The frames' returns together are the cloud the spinning sweeps are
/// registered onto, their fields of view the overlap region, their rays the seen-through test.
struct SolidView {
  struct Frame {
    Eigen::Isometry3d T_start_sensor = Eigen::Isometry3d::Identity();
    std::vector<Eigen::Vector3d> returns;  // in the frame's own sensor frame
  };
  std::vector<Frame> frames;
};

/// spinning: one (or a few stacked) stationary sweep(s), spinning-sensor frame; solid: the
/// accumulated stationary frames, solid-sensor frame. guess: T_solid_spinning from the config, or
/// none for the yaw search.
SpatialCalibrationResult calibrateSpinningToSolid(const std::vector<Eigen::Vector3d>& spinning,
                                                  const std::vector<Eigen::Vector3d>& solid,
                                                  const std::optional<Eigen::Isometry3d>& guess,
                                                  const SpatialCalibrationConfig& cfg = SpatialCalibrationConfig());
/// The same onto a solid-state view of several poses (spinning: still sweeps at the start).
SpatialCalibrationResult calibrateSpinningToSolid(const std::vector<Eigen::Vector3d>& spinning, const SolidView& view,
                                                  const std::optional<Eigen::Isometry3d>& guess,
                                                  const SpatialCalibrationConfig& cfg = SpatialCalibrationConfig());

}  // namespace mmlio::calib
