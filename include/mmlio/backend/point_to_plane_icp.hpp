#pragma once
// Point-to-plane ICP for loop verification: a target cloud with a k-d tree and PCA normals, and a
// coarse-to-fine Gauss-Newton alignment of a source cloud to it.
//
// Per level l the source is voxel-downsampled and correspondences are gated at a distance that
// shrinks geometrically from max_corr_coarse_m to max_corr_fine_m. Each iteration solves
//   min_delta sum_i ( n_i . (Exp(delta) T p_i - q_i) )^2,  delta = (dp, dtheta), left update,
// with J_i = n_i^T [I, -hat(T p_i)]. The result reports the quality at the finest gate
// (fitness, overlap) and the normalised Hessian, whose weakest translation eigenvalue tells
// whether the geometry constrains every direction (a featureless corridor does not).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "mmlio/map/kd_tree.hpp"

namespace mmlio::backend {

/// A registration target: points, a k-d tree over them and a normal per point (PCA of its
/// neighbours; invalid where the neighbourhood is not a plane: edges, corners, scan lines).
/// Normals are fitted when first asked for, so a target serves one alignment at a time (not
/// thread-safe).
class IcpTarget {
 public:
  /// normal_neighbours: k of the PCA neighbourhood (>= 3). min_patch_width_m: a neighbourhood
  /// gets a normal only if its second principal standard deviation exceeds this (not a line).
  explicit IcpTarget(std::vector<Eigen::Vector3d> points, int normal_neighbours = 10, double min_patch_width_m = 0.04);
  ~IcpTarget();
  IcpTarget(IcpTarget&&) noexcept;
  IcpTarget& operator=(IcpTarget&&) noexcept;

  std::size_t size() const;
  const std::vector<Eigen::Vector3d>& points() const;
  const Eigen::Vector3d& normal(std::size_t i) const;
  bool hasNormal(std::size_t i) const;
  /// Nearest target point to q closer than sqrt(max_dist_sq), or -1: the bound prunes the search.
  int nearestWithin(const Eigen::Vector3d& q, double max_dist_sq) const;
  /// The same answer, searched only as far as target point `hint` (any index, or -1): ICP's
  /// previous match of a source point bounds its next search to a few centimetres.
  int nearestWithin(const Eigen::Vector3d& q, double max_dist_sq, int hint) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct IcpConfig {
  double max_corr_coarse_m = 1.0;  // correspondence gate at the first level
  double max_corr_fine_m = 0.25;   // ... at the last level (also the overlap gate)
  double voxel_coarse_m = 0.5;     // source downsampling at the first level
  double voxel_fine_m = 0.1;       // ... at the last level
  int levels = 3;                  // gates and voxels interpolate geometrically
  // Asked after each level but the last with the pose so far: false stops the alignment there
  // (not converged). It only looks: an alignment it lets run is the one without it.
  std::function<bool(int level, const Eigen::Isometry3d& T_target_source)> continue_after_level;
  int max_iterations_per_level = 20;
  double converged_translation_m = 1e-4;  // stop a level when the update is below both
  double converged_rotation_rad = 1e-5;
  int min_correspondences = 30;  // fewer: the alignment fails
  // At most this many source points per level, evenly spaced in the downsampled cloud (0: all): a
  // 60 m hall keyframe at 0.1 m is tens of thousands of points, and the pose, fitness and overlap
  // of a rigid alignment are as well determined by a spread-out fraction of them.
  std::size_t max_source_points = 0;
};

struct IcpResult {
  bool converged = false;  // enough correspondences at every level
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  double fitness_m = 0;     // mean |point-to-plane residual| of the final correspondences
  double overlap = 0;       // fraction of fine source points within max_corr_fine_m of the target
  int correspondences = 0;  // final, with a valid normal
  int iterations = 0;       // over all levels
  Eigen::Matrix<double, 6, 6> hessian_normalised = Eigen::Matrix<double, 6, 6>::Zero();  // J^T J / N
  double min_translation_eigenvalue = 0;  // of its translation block: 0 = unconstrained, 1/3 = isotropic
  Eigen::Vector3d weakest_translation_direction = Eigen::Vector3d::UnitX();  // in the target frame
};

IcpResult alignPointToPlane(const std::vector<Eigen::Vector3d>& source, const IcpTarget& target,
                            const Eigen::Isometry3d& T_target_source_guess, const IcpConfig& cfg = IcpConfig());

}  // namespace mmlio::backend
