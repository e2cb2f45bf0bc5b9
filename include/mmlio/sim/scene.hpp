#pragma once
// Synthetic scenes: solids as axis-aligned boxes with a reflectivity, ray cast through a uniform
// 2-D grid of columns (x, y) so a ray tests only the boxes of the cells it crosses.
// World frame: z up, floor at z = 0.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

namespace mmlio::sim {

/// An axis-aligned solid box, lo < hi componentwise.
struct Box {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();  // m, world
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();  // m, world
  float reflectivity = 100.f;                    // 0..255, returned as intensity
};

/// Entry distance t > min_t along o + t d (d need not be unit) into box b; +inf on a miss.
/// Slab test. A ray starting inside the box returns +inf (boxes are solid, seen from outside).
double rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b, double min_t = 1e-9);

/// Nearest intersection of a ray with a scene.
struct RayHit {
  double range_m = std::numeric_limits<double>::infinity();  // distance along the unit ray
  int box = -1;                                              // index into Scene::boxes(), -1 on a miss
  int axis = -1;                                             // 0/1/2: the face normal's axis
};

struct SceneConfig {
  double cell_size_m = 1.0;  // side of the (x, y) grid cells
  int large_box_cells = 32;  // boxes covering more cells are tested once per ray instead
};

class Scene {
 public:
  Scene() = default;
  explicit Scene(std::vector<Box> boxes, SceneConfig config = SceneConfig());

  const std::vector<Box>& boxes() const { return boxes_; }
  Eigen::Vector3d lo() const { return lo_; }
  Eigen::Vector3d hi() const { return hi_; }

  /// Nearest hit along o + t d, d a unit vector, t in (0, max_range_m]. Thread-safe.
  RayHit cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m) const;
  /// Same answer by testing every box (reference for tests).
  RayHit castBruteForce(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m) const;
  /// Distance from p to the nearest box surface (0 inside a box).
  double distanceToSurface(const Eigen::Vector3d& p) const;

 private:
  std::vector<Box> boxes_;
  SceneConfig config_;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero(), hi_ = Eigen::Vector3d::Zero();
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> cell_start_;  // CSR: boxes of cell (ix, iy) are
  std::vector<std::uint32_t> cell_boxes_;  // cell_boxes_[cell_start_[c] .. cell_start_[c+1])
  std::vector<std::uint32_t> large_boxes_;
};

}  // namespace mmlio::sim
