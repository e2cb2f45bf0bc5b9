#include "mmlio/estimator/map_matching.hpp"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "mmlio/estimator/lidar_factors.hpp"
#include "mmlio/map/geometry_fit.hpp"

namespace mmlio::estimator {

std::vector<MapMatch> findMapMatches(const Features& f, const Eigen::Isometry3d& T_world_body,
                                     const map::VoxelHashMap& edge_map, const map::VoxelHashMap& plane_map,
                                     const MapMatchConfig& cfg) {
  const std::size_t n_planes = f.planes.size();
  std::vector<MapMatch> matches(n_planes + f.edges.size());
  std::vector<char> found(matches.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, matches.size(), 64), [&](const auto& range) {
    std::vector<Eigen::Vector3d> nn;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const bool plane = i < n_planes;
      const Eigen::Vector3d& p = plane ? f.planes[i] : f.edges[i - n_planes];
      const Eigen::Vector3d q = T_world_body * p;
      MapMatch& m = matches[i];
      if (plane) {
        if (plane_map.knn(q, cfg.neighbours, cfg.max_distance_m, &nn) < cfg.neighbours) continue;
        const map::PlaneFit fit = map::fitPlane(nn, 0.1);
        if (!fit.ok) continue;
        m = {MapMatch::Kind::kPlane, f.plane_source.empty() ? std::uint8_t{0} : f.plane_source[i], p, fit.normal,
             Eigen::Vector3d(fit.d, 0, 0)};
      } else {
        if (edge_map.knn(q, cfg.neighbours, cfg.max_distance_m, &nn) < cfg.neighbours) continue;
        const map::LineFit fit = map::fitLine(nn, 3.0);
        if (!fit.ok) continue;
        m = {MapMatch::Kind::kEdge, f.edge_source.empty() ? std::uint8_t{0} : f.edge_source[i - n_planes], p,
             fit.point, fit.direction};
      }
      found[i] = 1;
    }
  });
  std::vector<MapMatch> out;
  out.reserve(matches.size());
  for (std::size_t i = 0; i < matches.size(); ++i)
    if (found[i]) out.push_back(matches[i]);
  return out;
}

bool Reassociation::needed(const Eigen::Isometry3d& found_at, const Eigen::Isometry3d& now) const {
  const Eigen::Isometry3d moved = found_at.inverse() * now;
  return moved.translation().norm() >= translation_m || Eigen::AngleAxisd(moved.linear()).angle() >= rotation_rad;
}

double matchDistance(const MapMatch& m, const Eigen::Isometry3d& T_world_body) {
  const Eigen::Vector3d q = T_world_body * m.p_body;
  if (m.kind == MapMatch::Kind::kPlane) return std::abs(m.a.dot(q) + m.b.x());
  const Eigen::Vector3d u = m.b.normalized();
  const Eigen::Vector3d d = q - m.a;
  return (d - u * u.dot(d)).norm();
}

ceres::CostFunction* mapMatchCost(const MapMatch& m, double weight) {
  if (m.kind == MapMatch::Kind::kPlane) return new PointToPlaneFactor(m.p_body, m.a, m.b.x(), weight);
  return new PointToEdgeFactor(m.p_body, m.a, m.b, weight);
}

}  // namespace mmlio::estimator
