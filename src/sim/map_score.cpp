#include "mmlio/sim/map_score.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"
#include "mmlio/map/kd_tree.hpp"

namespace mmlio::sim {

std::uint64_t surfaceVoxelOf(const Eigen::Vector3d& p) { return voxelKeyOf(p, kOnSurfaceM); }

MapScore scoreMap(const Scene& scene, const std::vector<Eigen::Vector3d>& map) {
  MapScore s;
  s.points = map.size();
  if (map.empty()) return s;
  std::vector<double> d(map.size());
  tbb::parallel_for(std::size_t(0), map.size(), [&](std::size_t i) { d[i] = scene.distanceToSurface(map[i]); });
  FlatKeySet voxels;
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (d[i] > kOnSurfaceM) {
      s.off_surface.push_back(i);
      continue;
    }
    s.on_surface.push_back(map[i]);
    voxels.insert(surfaceVoxelOf(map[i]));
  }
  s.static_voxels = voxels.size();
  s.off_surface_fraction = static_cast<double>(s.off_surface.size()) / static_cast<double>(map.size());
  const auto at = [&d](double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(d.size() - 1));
    std::nth_element(d.begin(), d.begin() + k, d.end());
    return d[static_cast<std::size_t>(k)];
  };
  s.median_m = at(0.5);
  s.p90_m = at(0.9);
  return s;
}

double staticPointsKept(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& reference) {
  if (reference.empty() || points.empty()) return 0.0;
  map::CloudAdaptor adaptor{&points};
  map::KdTree3d tree(3, adaptor, map::kdTreeParams());
  tree.buildIndex();
  std::vector<std::uint8_t> kept(reference.size(), 0);
  tbb::parallel_for(std::size_t(0), reference.size(), [&](std::size_t i) {
    std::uint32_t nearest = 0;
    double d2 = 0.0;
    tree.knnSearch(reference[i].data(), 1, &nearest, &d2);
    kept[i] = d2 <= kOnSurfaceM * kOnSurfaceM;
  });
  return static_cast<double>(std::count(kept.begin(), kept.end(), 1)) / static_cast<double>(reference.size());
}

}  // namespace mmlio::sim
