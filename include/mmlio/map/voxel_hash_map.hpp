#pragma once
// Local map as a voxel hash (KISS-ICP style): each voxel keeps at most N points, so memory is
// bounded by the occupied volume; kNN scans the voxels around the query ring by ring.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "mmlio/core/flat_key_index.hpp"

namespace mmlio::map {

class VoxelHashMap {
 public:
  /// voxel_m: voxel edge (m); max_points_per_voxel: further points falling in a full voxel are dropped.
  VoxelHashMap(double voxel_m, int max_points_per_voxel);

  void add(const std::vector<Eigen::Vector3d>& world_points);
  /// Drops every voxel whose first point lies farther than radius_m from center.
  void removeFarFrom(const Eigen::Vector3d& center, double radius_m);
  /// Removes the points within radius_m of center for which `remove` is true (called in
  /// parallel, so it must be thread-safe), appending them to *removed if given. Returns how many
  /// were removed.
  std::size_t removeIf(const Eigen::Vector3d& center, double radius_m,
                       const std::function<bool(const Eigen::Vector3d&)>& remove,
                       std::vector<Eigen::Vector3d>* removed = nullptr);

  /// The (up to) k nearest points within max_dist_m of q, sorted by distance, into *out (cleared).
  /// Exact: scans the 27 voxels around q, then further rings until no closer point can exist.
  /// Returns the number found.
  int knn(const Eigen::Vector3d& q, int k, double max_dist_m, std::vector<Eigen::Vector3d>* out) const;

  std::size_t size() const { return num_points_; }  // points stored
  bool empty() const { return num_points_ == 0; }
  void clear();
  std::vector<Eigen::Vector3d> points() const;
  std::size_t numVoxels() const { return voxels_.size(); }
  double voxelSizeM() const { return voxel_m_; }

 private:
  struct Key {
    int x, y, z;
  };
  Key keyOf(const Eigen::Vector3d& p) const;
  // A kNN query looks up to 125 voxels, most of them empty where features are far and sparse:
  // the index is a FlatKeyIndex. Voxels live in `voxels_` in insertion order.
  struct Voxel {
    std::uint64_t key;
    std::vector<Eigen::Vector3d> points;
  };
  static constexpr std::uint32_t kNone = FlatKeyIndex::kNone;
  std::uint32_t find(std::uint64_t key) const { return index_.find(key); }
  void rebuildIndex();  // after voxels were removed (compacts them)

  double voxel_m_;
  double inv_voxel_;
  int max_points_per_voxel_;
  std::size_t num_points_ = 0;
  std::vector<Voxel> voxels_;
  FlatKeyIndex index_;  // packed voxel key -> index into voxels_
};

}  // namespace mmlio::map
