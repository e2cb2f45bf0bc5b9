#pragma once
// Correspondences of body-frame feature points with the local map, found at a pose estimate:
// each edge point gets the line through its k nearest edge-map points, each plane point the
// plane through its k nearest plane-map points (paper eqs. edge_cost / plane_cost), or, in a map
// that keeps voxel planes, the plane of its voxel when it lies near one. The residuals
// themselves are PointToEdgeFactor / PointToPlaneFactor (lidar_factors.hpp).
#include <ceres/cost_function.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "mmlio/map/voxel_hash_map.hpp"

namespace mmlio::estimator {

/// Body-frame features of one sweep.
struct Features {
  std::vector<Eigen::Vector3d> edges, planes;           // matched against the map (and added to it)
  std::vector<std::uint8_t> edge_source, plane_source;  // the LiDAR of each (empty: all from LiDAR 0)
};

/// A residual against the local map, found at the current estimate.
struct MapMatch {
  enum class Kind { kPlane, kEdge };
  Kind kind = Kind::kPlane;
  std::uint8_t source = 0;  // the LiDAR whose point this is
  Eigen::Vector3d p_body;
  Eigen::Vector3d a, b;  // plane: a = unit normal, b.x() = d (n.x + d = 0); edge: a = point, b = direction
};

struct MapMatchConfig {
  double max_distance_m = 1.0;      // farther map neighbours make no correspondence
  int neighbours = 5;               // map points per line / plane fit
  double voxel_plane_gate_m = 0.1;  // a point takes its map voxel's plane only if this near it
  // A point farther than this from its fitted plane or line (at the pose it is matched at) is left
  // unmatched: infinity for a pose that may be far off (after a gap in the data).
  double max_residual_m = std::numeric_limits<double>::infinity();
};

/// Matches found at one pose hold at another until the pose has moved this far from where they
/// were found: smaller moves leave each point's k nearest map points the same.
struct Reassociation {
  double translation_m = 0.03;
  double rotation_rad = 0.1 * M_PI / 180.0;
  bool needed(const Eigen::Isometry3d& found_at, const Eigen::Isometry3d& now) const;
};

std::vector<MapMatch> findMapMatches(const Features& f, const Eigen::Isometry3d& T_world_body,
                                     const map::VoxelHashMap& edge_map, const map::VoxelHashMap& plane_map,
                                     const MapMatchConfig& cfg = MapMatchConfig());

/// The metric distance of the match's point, placed by T_world_body, from its plane or line.
double matchDistance(const MapMatch& m, const Eigen::Isometry3d& T_world_body);

/// The point-to-plane / point-to-edge residual of a match on one pose block, whitened by weight.
ceres::CostFunction* mapMatchCost(const MapMatch& m, double weight);

/// All matches of one pose as ONE residual block, each match whitened by weight and robust with
/// its own Huber loss of scale huber (whitened units; <= 0: none). The loss is applied as
/// r' = sqrt(rho(|r|^2)) r / |r|, so |r'|^2 is exactly the robust cost and the Gauss-Newton
/// model is that of the robust cost (Ceres' own correction differs only in the curvature it
/// gives a match beyond the Huber scale: half of it far out, the same at the scale).
///
/// Ceres sees the block reduced to 7 rows: with the stacked matches' Jacobian J and residuals r,
/// J^T J = V D V^T, the rows are sqrt(D) V^T with residuals D^-1/2 V^T J^T r, and a seventh row
/// without Jacobian carries the rest of |r|^2. Cost, gradient J^T r and Gauss-Newton matrix J^T J
/// are those of the stacked matches, so Levenberg-Marquardt takes the same steps, but the solver
/// no longer stores, scales and eliminates thousands of Jacobian rows per iteration (per-row
/// solver work cost more than evaluating the matches).
class MapMatchesFactor final : public ceres::CostFunction {
 public:
  MapMatchesFactor(const std::vector<MapMatch>& matches, double weight, double huber);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  static constexpr int kReducedRows = 6;
  static constexpr double kRankTolerance = 1e-12;  // of the largest eigenvalue of J^T J

  /// Cost |r|^2, gradient J^T r and J^T J of the stacked robust matches at the pose (tangent
  /// order: translation, then rotation as a right perturbation).
  struct NormalEquations {
    Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> Jtr = Eigen::Matrix<double, 6, 1>::Zero();
    double cost = 0.0;
  };
  NormalEquations normalEquations(const double* pose, bool with_jacobian) const;
  struct Plane {
    Eigen::Vector3d p_body, normal;  // normal and d carry the weight
    double d;
  };
  struct Edge {
    Eigen::Vector3d p_body, line_point;
    Eigen::Matrix3d perp;  // weight * (I - u u^T)
  };
  std::vector<Plane> planes_;
  std::vector<Edge> edges_;
  double huber_;
};

}  // namespace mmlio::estimator
