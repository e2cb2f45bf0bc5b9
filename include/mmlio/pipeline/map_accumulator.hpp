#pragma once
// The output map: world points averaged per voxel (position and intensity), so memory grows
// with the mapped surface, not with the number of sweeps. Leaf 0 keeps every point.
#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::pipeline {

class MapAccumulator {
 public:
  explicit MapAccumulator(double leaf_m);
  /// Adds body-frame points seen from pose T_world_body.
  void add(const std::vector<Point>& points_body, const Eigen::Isometry3d& T_world_body);
  std::size_t size() const;
  /// One point per voxel (centroid, mean intensity).
  std::vector<Point> points() const;

 private:
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double intensity = 0.0;
    std::uint32_t count = 0;
  };
  double leaf_m_;
  std::unordered_map<std::uint64_t, Cell> cells_;
  std::vector<Point> raw_;  // leaf 0
};

}  // namespace mmlio::pipeline
