#pragma once
// Local map as a voxel hash (KISS-ICP style): each voxel keeps at most N points, so memory is
// bounded by the occupied volume; kNN scans the voxels around the query ring by ring.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

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
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct KeyHash {
    // 21 bits per axis packed, then a splitmix64 finaliser: neighbouring voxels land in unrelated
    // buckets (the classic xor-of-primes hash clusters them and lengthens the bucket chains).
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = ((static_cast<std::uint64_t>(k.x) & 0x1FFFFF) << 42) |
                        ((static_cast<std::uint64_t>(k.y) & 0x1FFFFF) << 21) | (static_cast<std::uint64_t>(k.z) & 0x1FFFFF);
      h ^= h >> 30;
      h *= 0xbf58476d1ce4e5b9ULL;
      h ^= h >> 27;
      h *= 0x94d049bb133111ebULL;
      h ^= h >> 31;
      return static_cast<std::size_t>(h);
    }
  };
  Key keyOf(const Eigen::Vector3d& p) const;

  double voxel_m_;
  double inv_voxel_;
  int max_points_per_voxel_;
  std::size_t num_points_ = 0;
  std::unordered_map<Key, std::vector<Eigen::Vector3d>, KeyHash> voxels_;
  // One bit per hash slot, set when a voxel with that hash exists (rebuilt on removal): a clear
  // bit proves a voxel empty without the hash-table lookup, which is most of a kNN query's cost
  // where the map is sparse (far features in a large hall scan up to 125 voxels, mostly empty).
  static constexpr std::size_t kOccupancyBits = std::size_t{1} << 20;
  std::vector<std::uint64_t> occupancy_ = std::vector<std::uint64_t>(kOccupancyBits / 64, 0);
  void markOccupied(const Key& k);
  bool maybeOccupied(const Key& k) const;
};

}  // namespace mmlio::map
