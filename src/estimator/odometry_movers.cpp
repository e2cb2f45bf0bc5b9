// Odometry stage: moving objects. Returns in space earlier sweeps saw through leave the sweep
// (and its points go to the dynamic map); a keyframe's view carves what moved out of the local map.
#include <algorithm>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"
#include "odometry_impl.hpp"

namespace mmlio::estimator {

// Returns on things that moved in (space an earlier sweep saw through) leave the sweep's features.
// Returns whether they include a mover (moverFound), not only the odd false return.
bool Odometry::Impl::rejectMovedIn(Features* f, const Eigen::Isometry3d& T_world_body, Stamp now,
                                   SweepResult* out) const {
  std::vector<Eigen::Vector3d> world;
  world.reserve(f->edges.size() + f->planes.size());
  for (const auto& p : f->edges) world.push_back(T_world_body * p);
  for (const auto& p : f->planes) world.push_back(T_world_body * p);
  std::vector<std::uint8_t> moved = free_space.movedIn(world, now);
  const bool mover = moverFound(world, moved);
  // Raw points follow their feature's voxel (features are voxel centroids of the raw points).
  const double inv = 1.0 / cfg.plane_voxel_m;
  const auto key = [inv](const Eigen::Vector3d& p, int dx = 0, int dy = 0, int dz = 0) {
    return scaledVoxelKeyOf(p, inv, dx, dy, dz);
  };
  // A mover is found where part of it entered free space (its leading side); its other returns
  // lie next to those: every feature in a voxel touching a flagged one goes with them.
  // The flagged voxels are few: their neighbourhoods go in one set, looked up once per feature.
  FlatKeySet near_flagged;
  const auto bodyPoint = [&](std::size_t i) {
    return i < f->edges.size() ? f->edges[i] : f->planes[i - f->edges.size()];
  };
  // Not from a frame still under judgement: rejected, it must leave the other LiDARs' features as they were.
  const auto judged = [&](std::size_t i) {
    const std::vector<std::uint8_t>& src = i < f->edges.size() ? f->edge_source : f->plane_source;
    const std::size_t k = i < f->edges.size() ? i : i - f->edges.size();
    return k < src.size() && edge_poor[src[k]] != 0;
  };
  for (std::size_t i = 0; i < moved.size(); ++i)
    if (moved[i] && !judged(i))
      for (int n = 0; n < 27; ++n) near_flagged.insert(key(bodyPoint(i), n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1));
  if (!near_flagged.empty())
    for (std::size_t i = 0; i < moved.size(); ++i)
      if (!moved[i]) moved[i] = near_flagged.contains(key(bodyPoint(i))) ? 1 : 0;
  FlatKeySet moved_voxels;
  std::size_t index = 0;
  const auto keep = [&](std::vector<Eigen::Vector3d>* pts, std::vector<std::uint8_t>* src) {
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts->size(); ++i, ++index) {
      if (moved[index]) {
        moved_voxels.insert(key((*pts)[i]));
        continue;
      }
      (*pts)[k] = (*pts)[i];
      if (src->size() == pts->size()) (*src)[k] = (*src)[i];
      ++k;
    }
    if (src->size() == pts->size()) src->resize(k);
    pts->resize(k);
  };
  for (std::size_t i = 0; i < moved.size(); ++i)
    if (moved[i]) out->moved_world.push_back(world[i]);
  keep(&f->edges, &f->edge_source);
  keep(&f->planes, &f->plane_source);
  out->dynamic_points = static_cast<std::size_t>(std::count(moved.begin(), moved.end(), 1));
  if (moved_voxels.empty() || out->points_body.empty()) return mover;
  std::size_t k = 0;
  for (const Point& p : out->points_body) {
    if (moved_voxels.contains(key(p.xyz.cast<double>())))
      out->points_dynamic_body.push_back(p);
    else
      out->points_body[k++] = p;
  }
  out->points_body.resize(k);
  return mover;
}

/// Local map points the keyframe's sweep saw through were left by something that has gone.
std::size_t Odometry::Impl::carveMap(const Eigen::Vector3d& center, std::vector<Eigen::Vector3d>* carved) {
  if (!view) return 0;
  const auto seen_through = [this](const Eigen::Vector3d& p) { return view->seesThrough(p); };
  return plane_map.removeIf(center, cfg.dynamic.carve_radius_m, seen_through, carved) +
         edge_map.removeIf(center, cfg.dynamic.carve_radius_m, seen_through, carved);
}

}  // namespace mmlio::estimator
