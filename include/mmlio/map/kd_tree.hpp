#pragma once
// A nanoflann k-d tree over a std::vector<Eigen::Vector3d> (kept by pointer: the vector must
// outlive the tree and not change while it is used). For the registrations that need exact
// k-nearest neighbours on a fixed cloud (loop ICP, calibration GICP); the odometry's local map
// uses its voxel hash instead.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <nanoflann.hpp>
#include <vector>

namespace mmlio::map {

struct CloudAdaptor {
  const std::vector<Eigen::Vector3d>* pts = nullptr;
  std::size_t kdtree_get_point_count() const { return pts->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return (*pts)[i][static_cast<int>(d)]; }
  template <class BBox> bool kdtree_get_bbox(BBox&) const { return false; }
};

using KdTree3d = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, CloudAdaptor>, CloudAdaptor,
                                                     3, std::uint32_t>;

/// Leaf size 10: measured fastest for the few-thousand-point clouds the registrations query.
inline nanoflann::KDTreeSingleIndexAdaptorParams kdTreeParams() {
  return nanoflann::KDTreeSingleIndexAdaptorParams(10);
}

/// One point per occupied voxel of edge leaf_m (the centroid), in first-occupation order.
/// leaf_m <= 0 returns the input.
std::vector<Eigen::Vector3d> voxelCentroids(const std::vector<Eigen::Vector3d>& pts, double leaf_m);

}  // namespace mmlio::map
