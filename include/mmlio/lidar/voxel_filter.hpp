#pragma once
// Voxel-grid downsampling of a point cloud: one point per occupied cubic voxel.

#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::lidar {

/// One point per voxel of edge `leaf_m`: the centroid of the voxel's points, with their mean
/// intensity; time_s and ring are those of the voxel's first point. Output in order of first
/// occupation (deterministic). leaf_m <= 0 returns the input unchanged.
std::vector<Point> voxelDownsample(const std::vector<Point>& pts, double leaf_m);

}  // namespace mmlio::lidar
