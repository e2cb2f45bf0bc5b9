#pragma once
// How a map sits on a simulated scene's static surfaces: what lies off them (ghosts of people,
// blur) and how much of them it keeps. Maps in the ground-truth frame.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {

/// A map point this close to a static surface lies on it.
inline constexpr double kOnSurfaceM = 0.1;

struct MapScore {
  std::size_t points = 0;
  double median_m = 0.0, p90_m = 0.0;       // distance to the nearest static surface
  double off_surface_fraction = 0.0;        // share of points farther than kOnSurfaceM
  std::size_t static_voxels = 0;            // kOnSurfaceM voxels holding an on-surface point
  std::vector<Eigen::Vector3d> on_surface;  // the points within kOnSurfaceM of a surface
  std::vector<std::size_t> off_surface;     // indices of the others
};

MapScore scoreMap(const Scene& scene, const std::vector<Eigen::Vector3d>& map);

/// The kOnSurfaceM voxel a point lies in.
std::uint64_t surfaceVoxelOf(const Eigen::Vector3d& p);

/// The share of `reference` points with a point of `points` within kOnSurfaceM. With the
/// on-surface points of a run without people as the reference and those of the same scene with
/// people as `points`: the static surface the people run keeps, point by point. (A count of
/// covered voxels differs between two runs that keep the same surface: how many voxels a
/// surface's points touch depends on how their noise straddles voxel borders.)
double staticPointsKept(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& reference);

}  // namespace mmlio::sim
