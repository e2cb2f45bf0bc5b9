#pragma once
// Generalized ICP (Segal, Haehnel, Thrun 2009): plane-to-plane registration of a source cloud
// onto a target cloud.
//
// Every point gets a covariance from its k nearest neighbours, regularised to a plane: the
// eigenvalues of the neighbourhood scatter are replaced by (1, 1, plane_epsilon) so that the
// covariance is a thin disc along the local surface. A correspondence i (source p_i, nearest
// target q_i within the gate) contributes
//   r_i = q_i - T p_i,   C_i = C_q + R C_p R^T,   cost = sum_i r_i^T C_i^-1 r_i.
// Gauss-Newton with a left update T <- Exp(delta) T, delta = (dp, dtheta):
//   d r_i / d delta = [-I, hat(T p_i)].
// The gate shrinks geometrically from max_corr_dist_coarse_m to max_corr_dist_fine_m over
// `levels` levels; the reported quality is at the finest gate.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "mmlio/map/kd_tree.hpp"

namespace mmlio::calib {

struct GicpConfig {
  int covariance_neighbours = 20;       // k of the neighbourhood of each point's covariance
  double plane_epsilon = 1e-3;          // smallest normalised eigenvalue (thickness of the disc)
  bool source_covariances = true;       // false: source points are exact (point-to-distribution);
                                        // use it for sparse sources such as 16-ring sweeps
  double max_corr_dist_coarse_m = 1.0;  // correspondence gate at the first level
  double max_corr_dist_fine_m = 0.2;    // ... at the last level (also the overlap gate)
  int levels = 3;                       // gates interpolate geometrically
  int max_iterations_per_level = 30;
  double converged_translation_m = 1e-5;  // a level stops when the update is below both
  double converged_rotation_rad = 1e-6;
  double settled_factor = 10;    // the last iteration's update within this many times both: converged too
  int min_correspondences = 50;  // fewer at any iteration: not converged
};

struct GicpResult {
  bool converged = false;  // enough correspondences throughout and the last update small
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  double fitness_m = 0;  // mean Euclidean distance of the final inliers
  double overlap = 0;    // fraction of source points with a target point within the fine gate
  int inliers = 0;       // correspondences at the fine gate
  int iterations = 0;    // over all levels
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();  // J^T C^-1 J at the end,
                                                                              // tangent (dp, dtheta), left perturbation
};

/// Plane-regularised covariance of every point from its k nearest neighbours in `points`.
std::vector<Eigen::Matrix3d> planeCovariances(const std::vector<Eigen::Vector3d>& points, int k, double plane_epsilon);

/// A target cloud with its search tree and covariances (cfg's neighbours and plane epsilon), built
/// once for many registrations onto it (a yaw search runs dozens).
class GicpTarget {
 public:
  GicpTarget(std::vector<Eigen::Vector3d> points, const GicpConfig& cfg);
  GicpTarget(const GicpTarget&) = delete;  // the tree refers to points_
  GicpTarget& operator=(const GicpTarget&) = delete;

  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  const std::vector<Eigen::Matrix3d>& covariances() const { return covariances_; }
  const map::KdTree3d& tree() const { return tree_; }

 private:
  std::vector<Eigen::Vector3d> points_;
  map::CloudAdaptor adaptor_;
  map::KdTree3d tree_;
  std::vector<Eigen::Matrix3d> covariances_;
};

GicpResult gicp(const std::vector<Eigen::Vector3d>& source, const GicpTarget& target,
                const Eigen::Isometry3d& T_target_source_guess, const GicpConfig& cfg = GicpConfig());
GicpResult gicp(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                const Eigen::Isometry3d& T_target_source_guess, const GicpConfig& cfg = GicpConfig());

}  // namespace mmlio::calib
