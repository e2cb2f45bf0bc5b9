#pragma once
// Local map as a voxel hash (KISS-ICP style): each voxel keeps at most N points, so memory is
// bounded by the occupied volume; kNN scans the voxels around the query ring by ring.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/huge_page_allocator.hpp"

namespace mmlio::map {

class VoxelHashMap {
 public:
  /// voxel_m: voxel edge (m); max_points_per_voxel: further points falling in a full voxel are
  /// dropped; fit_planes: keep a plane per voxel whose points form one (planeAt).
  VoxelHashMap(double voxel_m, int max_points_per_voxel, bool fit_planes = false);

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

  /// With fit_planes, the plane through the points of q's voxel if they form one: at least
  /// kPlaneMinPoints, all within kPlaneMaxResidualM of it. Null otherwise, and for a voxel changed
  /// since the last refitPlanes().
  struct VoxelPlane {
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
    double d = 0.0;                                     // n.x + d = 0
  };
  static constexpr std::uint32_t kPlaneMinPoints = 10;
  static constexpr double kPlaneMaxResidualM = 0.05;
  const VoxelPlane* planeAt(const Eigen::Vector3d& q) const;
  /// Fits the planes of the voxels changed since the last call (once per map update: queries
  /// run in parallel and only read).
  void refitPlanes();

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
  // A kNN query looks up 27 to 125 neighbouring voxels, most of them empty where features are far
  // and sparse. Voxels are indexed in bricks of 4x4x4: one hash lookup finds a brick, whose 64
  // slots are an array, so a query's neighbourhood costs a few hash lookups (each a likely cache
  // miss) instead of one per voxel.
  // A hall's plane map holds ~600k points (15 MB): most of a query's time was waiting for memory.
  // All points live in one arena, each voxel's in a span of it; the arena is rewritten brick by
  // brick now and then, so the voxels a query visits (and the next query's, a few decimetres on)
  // lie together in memory instead of in one heap block each.
  struct Voxel {
    Key key;
    std::uint32_t begin = 0, count = 0, capacity = 0;  // span of points_
    enum class Plane : std::uint8_t { kStale, kNone, kFitted } plane = Plane::kStale;
    VoxelPlane fit;
  };
  static constexpr int kBrickShift = 2;  // bricks of 4 voxels a side
  static constexpr int kBrickMask = (1 << kBrickShift) - 1;
  using Brick = std::array<std::uint32_t, 1 << (3 * kBrickShift)>;  // voxel index per slot, or kNone
  static constexpr std::uint32_t kNone = FlatKeyIndex::kNone;
  static std::uint64_t brickKey(const Key& k);
  static int slotInBrick(const Key& k) {
    return (k.x & kBrickMask) | (k.y & kBrickMask) << kBrickShift | (k.z & kBrickMask) << (2 * kBrickShift);
  }
  /// The voxel at k: its index, and whether it was created.
  std::pair<std::uint32_t, bool> findOrAdd(const Key& k);
  void rebuildIndex();         // after voxels were emptied: drops them from the index
  void compactBrickByBrick();  // rewrites the arena in brick order, dropping unowned slots
  const Eigen::Vector3d* pointsOf(const Voxel& v) const { return points_.data() + v.begin; }
  Eigen::Vector3d* pointsOf(const Voxel& v) { return points_.data() + v.begin; }

  double voxel_m_;
  double inv_voxel_;
  int max_points_per_voxel_;
  bool fit_planes_;
  std::size_t num_points_ = 0;
  std::vector<Voxel> voxels_;
  using Arena = std::vector<Eigen::Vector3d, HugePageAllocator<Eigen::Vector3d>>;
  Arena points_;  // the voxels' spans
  Arena spare_;   // the previous arena's buffer, for the next rewrite
  std::vector<Brick> bricks_;
  FlatKeyIndex brick_index_;  // packed brick key -> index into bricks_
};

}  // namespace mmlio::map
