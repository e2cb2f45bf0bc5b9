#pragma once
// Sessions of the synthetic scenes for the relocalization tests: keyframes along a walk with their
// clouds as a mapping run keeps them (0.1 m voxel centroids) and the map they make.
#include <cmath>
#include <vector>

#include "mmlio/core/session.hpp"
#include "mmlio/map/kd_tree.hpp"
#include "synthetic_scene.hpp"

namespace mmlio::backend::testing {

/// A sweep from T_map_body as the keyframes keep it.
inline std::vector<Eigen::Vector3d> keyframeCloud(const Scene& scene, const Eigen::Isometry3d& T_map_body,
                                                  unsigned seed) {
  return map::voxelCentroids(scan(scene, T_map_body, seed), 0.1);
}

/// A walk around room A, a keyframe every 1.5 m or so, facing along the walk.
inline std::vector<Eigen::Isometry3d> roomARoute() {
  std::vector<Eigen::Isometry3d> out;
  const std::vector<Eigen::Vector2d> corners = {{-5, -3}, {3.5, -3.5}, {4.5, 3}, {-4.5, 2.5}, {-5, -3}};
  for (std::size_t c = 0; c + 1 < corners.size(); ++c) {
    const Eigen::Vector2d d = corners[c + 1] - corners[c];
    const int steps = static_cast<int>(std::ceil(d.norm() / 1.5));
    for (int i = 0; i < steps; ++i) {
      const Eigen::Vector2d p = corners[c] + d * i / steps;
      out.push_back(pose(p.x(), p.y(), 1, std::atan2(d.y(), d.x())));
    }
  }
  return out;
}

/// A session of keyframes at `poses` in `scene`, a second apart, and the map their clouds make.
inline Session sessionOf(const Scene& scene, const std::vector<Eigen::Isometry3d>& poses) {
  Session s;
  s.cloud_voxel_m = 0.1;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    SessionKeyframe kf;
    kf.stamp_ns = fromSec(static_cast<double>(k));
    kf.T_map_body = kf.T_odom_body = poses[k];
    kf.cloud_body = keyframeCloud(scene, poses[k], 10 + static_cast<unsigned>(k));
    s.keyframes.push_back(std::move(kf));
    for (const Eigen::Vector3d& p : s.keyframes.back().cloud_body) {
      Point q;
      q.xyz = (poses[k] * p).cast<float>();
      s.map.push_back(q);
    }
  }
  return s;
}

}  // namespace mmlio::backend::testing
