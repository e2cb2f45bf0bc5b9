#pragma once
// One 64-bit key for a voxel's integer indices: 21 bits per axis, offset by 2^20, so indices in
// +-1,048,576 (+-1 km at 1 mm, +-52 km at 5 cm) pack without collision. Callers compute the
// indices (floor of coordinate / voxel size) the way their grid is defined.
#include <Eigen/Core>
#include <cstdint>

#include "mmlio/core/floor_to.hpp"

namespace mmlio {

inline std::uint64_t packVoxelKey(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
  const auto axis = [](std::int64_t i) { return static_cast<std::uint64_t>(i + (1 << 20)) & 0x1FFFFFu; };
  return (axis(ix) << 42) | (axis(iy) << 21) | axis(iz);
}

/// Key of the voxel of edge leaf_m that holds p (indices floor(coordinate / leaf_m)), or of the one
/// (dx, dy, dz) voxels from it. Grids indexed by coordinate * (1 / leaf) round differently at
/// voxel borders: they use scaledVoxelKeyOf.
inline std::uint64_t voxelKeyOf(const Eigen::Vector3d& p, double leaf_m, int dx = 0, int dy = 0, int dz = 0) {
  const auto idx = [leaf_m](double v) { return floorTo<std::int64_t>(v / leaf_m); };
  return packVoxelKey(idx(p.x()) + dx, idx(p.y()) + dy, idx(p.z()) + dz);
}

/// The same for the grids indexed by coordinate * inv_leaf (a multiplication per axis instead of a
/// division).
inline std::uint64_t scaledVoxelKeyOf(const Eigen::Vector3d& p, double inv_leaf, int dx = 0, int dy = 0, int dz = 0) {
  const auto idx = [inv_leaf](double v) { return floorTo<std::int64_t>(v * inv_leaf); };
  return packVoxelKey(idx(p.x()) + dx, idx(p.y()) + dy, idx(p.z()) + dz);
}

}  // namespace mmlio
