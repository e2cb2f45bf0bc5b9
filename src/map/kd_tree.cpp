#include "mmlio/map/kd_tree.hpp"

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"

namespace mmlio::map {

std::vector<Eigen::Vector3d> voxelCentroids(const std::vector<Eigen::Vector3d>& pts, double leaf_m) {
  if (leaf_m <= 0) return pts;
  const double inv = 1.0 / leaf_m;
  thread_local FlatKeyIndex index;  // loop checks voxelize clouds of about the same size again and again
  index.reset();
  std::vector<Eigen::Vector3d> sum;
  thread_local std::vector<int> count;
  count.clear();
  for (const auto& p : pts) {
    const auto [slot, inserted] = index.insert(scaledVoxelKeyOf(p, inv), static_cast<std::uint32_t>(sum.size()));
    if (inserted) {
      sum.push_back(p);
      count.push_back(1);
    } else {
      sum[slot] += p;
      ++count[slot];
    }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] /= count[i];
  return sum;
}

}  // namespace mmlio::map
