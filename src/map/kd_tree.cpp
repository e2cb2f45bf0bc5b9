#include "mmlio/map/kd_tree.hpp"

#include <cmath>
#include <unordered_map>

#include "mmlio/core/voxel_key.hpp"

namespace mmlio::map {

std::vector<Eigen::Vector3d> voxelCentroids(const std::vector<Eigen::Vector3d>& pts, double leaf_m) {
  if (leaf_m <= 0) return pts;
  const double inv = 1.0 / leaf_m;
  const auto idx = [inv](double v) { return static_cast<std::int64_t>(std::floor(v * inv)); };
  std::unordered_map<std::uint64_t, std::size_t> index;
  index.reserve(pts.size());
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  for (const auto& p : pts) {
    auto [it, inserted] = index.emplace(packVoxelKey(idx(p.x()), idx(p.y()), idx(p.z())), sum.size());
    if (inserted) {
      sum.push_back(p);
      count.push_back(1);
    } else {
      sum[it->second] += p;
      ++count[it->second];
    }
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] /= count[i];
  return sum;
}

}  // namespace mmlio::map
