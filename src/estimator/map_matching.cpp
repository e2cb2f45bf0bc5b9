#include "mmlio/estimator/map_matching.hpp"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "mmlio/core/so3.hpp"
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
        // A point in a planar map voxel near its plane takes that plane: a lookup instead of a kNN
        // search and a fit, from up to 60 points instead of 5.
        const map::VoxelHashMap::VoxelPlane* vp = plane_map.planeAt(q);
        if (vp && std::abs(vp->normal.dot(q) + vp->d) <= cfg.voxel_plane_gate_m) {
          m = {MapMatch::Kind::kPlane, f.plane_source.empty() ? std::uint8_t{0} : f.plane_source[i], p, vp->normal,
               Eigen::Vector3d(vp->d, 0, 0)};
          found[i] = 1;
          continue;
        }
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

MapMatchesFactor::MapMatchesFactor(const std::vector<MapMatch>& matches, double weight, double huber)
    : huber_(huber) {
  for (const MapMatch& m : matches) {
    if (m.kind == MapMatch::Kind::kPlane) {
      planes_.push_back({m.p_body, weight * m.a, weight * m.b.x()});
    } else {
      const Eigen::Vector3d u = m.b.normalized();
      edges_.push_back({m.p_body, m.a, weight * (Eigen::Matrix3d::Identity() - u * u.transpose())});
    }
  }
  set_num_residuals(static_cast<int>(planes_.size() + 3 * edges_.size()));
  mutable_parameter_block_sizes()->push_back(7);
}

bool MapMatchesFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> t(parameters[0]);
  const Eigen::Matrix3d R = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized().toRotationMatrix();
  double* J = jacobians ? jacobians[0] : nullptr;
  const double h = huber_;
  for (std::size_t i = 0; i < planes_.size(); ++i) {
    const Plane& m = planes_[i];
    const Eigen::Vector3d Rp = R * m.p_body;
    const double r = m.normal.dot(Rp + t) + m.d;
    // Beyond the Huber scale: r' = sign(r) sqrt(2 h |r| - h^2), dr'/dr = h / |r'|.
    double scale = 1.0;
    if (h > 0.0 && std::abs(r) > h) {
      const double f = std::sqrt(2.0 * h * std::abs(r) - h * h);
      residuals[i] = std::copysign(f, r);
      scale = h / f;
    } else {
      residuals[i] = r;
    }
    if (J) {
      // Right perturbation q <- q Exp(dtheta): d(R p) = -R [p]x dtheta, so d(n . R p) = (p x R^T n) . dtheta.
      Eigen::Map<Eigen::Matrix<double, 1, 7>> row(J + 7 * i);
      row.head<3>() = scale * m.normal;
      row.segment<3>(3) = scale * (m.p_body.cross(R.transpose() * m.normal));
      row(6) = 0.0;
    }
  }
  const std::size_t base = planes_.size();
  for (std::size_t k = 0; k < edges_.size(); ++k) {
    const Edge& m = edges_[k];
    Eigen::Map<Eigen::Vector3d> r(residuals + base + 3 * k);
    r = m.perp * (R * m.p_body + t - m.line_point);
    Eigen::Matrix<double, 3, 6> Jr;
    if (J) {
      Jr.leftCols<3>() = m.perp;
      Jr.rightCols<3>() = -m.perp * R * so3::hat(m.p_body);
    }
    const double n = r.norm();
    if (h > 0.0 && n > h) {
      // r' = g r with g = f / n, f = sqrt(2 h n - h^2): dr' = g dr + r (g' / n) r^T dr.
      const double f = std::sqrt(2.0 * h * n - h * h);
      const double g = f / n, c = (h / f) / (n * n) - f / (n * n * n);
      if (J) Jr = g * Jr + c * r * (r.transpose() * Jr);
      r *= g;
    }
    if (J) {
      Eigen::Map<Eigen::Matrix<double, 3, 7, Eigen::RowMajor>> rows(J + 7 * (base + 3 * k));
      rows.leftCols<6>() = Jr;
      rows.col(6).setZero();
    }
  }
  return true;
}

}  // namespace mmlio::estimator
