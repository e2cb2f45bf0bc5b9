#include "mmlio/estimator/map_matching.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/lidar_factors.hpp"
#include "mmlio/map/geometry_fit.hpp"

namespace mmlio::estimator {
namespace {

// Every map neighbour of a plane or line fit lies within this of the fitted plane or line.
constexpr double kFitToleranceM = 0.1;

}  // namespace

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
        const map::PlaneFit fit = map::fitPlane(nn, kFitToleranceM);
        if (!fit.ok) continue;
        m = {MapMatch::Kind::kPlane, f.plane_source.empty() ? std::uint8_t{0} : f.plane_source[i], p, fit.normal,
             Eigen::Vector3d(fit.d, 0, 0)};
      } else {
        if (edge_map.knn(q, cfg.neighbours, cfg.max_distance_m, &nn) < cfg.neighbours) continue;
        const map::LineFit fit = map::fitLine(nn, 3.0, kFitToleranceM);
        if (!fit.ok) continue;
        m = {MapMatch::Kind::kEdge, f.edge_source.empty() ? std::uint8_t{0} : f.edge_source[i - n_planes], p, fit.point,
             fit.direction};
      }
      found[i] = matchDistance(m, T_world_body) <= cfg.max_residual_m ? 1 : 0;
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

MapMatchesFactor::MapMatchesFactor(const std::vector<MapMatch>& matches, double weight, double huber) : huber_(huber) {
  for (const MapMatch& m : matches) {
    if (m.kind == MapMatch::Kind::kPlane) {
      planes_.push_back({m.p_body, weight * m.a, weight * m.b.x()});
    } else {
      const Eigen::Vector3d u = m.b.normalized();
      edges_.push_back({m.p_body, m.a, weight * (Eigen::Matrix3d::Identity() - u * u.transpose())});
    }
  }
  set_num_residuals(kReducedRows + 1);
  mutable_parameter_block_sizes()->push_back(7);
}

MapMatchesFactor::NormalEquations MapMatchesFactor::normalEquations(const double* pose, bool with_jacobian) const {
  const Eigen::Map<const Eigen::Vector3d> t(pose);
  const Eigen::Matrix3d R = Eigen::Map<const Eigen::Quaterniond>(pose + 3).normalized().toRotationMatrix();
  const double h = huber_;
  NormalEquations ne;
  for (const Plane& m : planes_) {
    const Eigen::Vector3d Rp = R * m.p_body;
    double r = m.normal.dot(Rp + t) + m.d;
    // Beyond the Huber scale: r' = sign(r) sqrt(2 h |r| - h^2), dr'/dr = h / |r'|.
    double scale = 1.0;
    if (h > 0.0 && std::abs(r) > h) {
      const double f = std::sqrt(2.0 * h * std::abs(r) - h * h);
      scale = h / f;
      r = std::copysign(f, r);
    }
    ne.cost += r * r;
    if (!with_jacobian) continue;
    // Right perturbation q <- q Exp(dtheta): d(R p) = -R [p]x dtheta, so d(n . R p) = (p x R^T n) . dtheta.
    Eigen::Matrix<double, 6, 1> j;
    j.head<3>() = scale * m.normal;
    j.tail<3>() = scale * (m.p_body.cross(R.transpose() * m.normal));
    ne.JtJ.noalias() += j * j.transpose();
    ne.Jtr += r * j;
  }
  for (const Edge& m : edges_) {
    Eigen::Vector3d r = m.perp * (R * m.p_body + t - m.line_point);
    Eigen::Matrix<double, 3, 6> Jr;
    if (with_jacobian) {
      Jr.leftCols<3>() = m.perp;
      Jr.rightCols<3>() = -m.perp * R * so3::hat(m.p_body);
    }
    const double n = r.norm();
    if (h > 0.0 && n > h) {
      // r' = g r with g = f / n, f = sqrt(2 h n - h^2): dr' = g dr + r (g' / n) r^T dr.
      const double f = std::sqrt(2.0 * h * n - h * h);
      const double g = f / n, c = (h / f) / (n * n) - f / (n * n * n);
      if (with_jacobian) Jr = g * Jr + c * r * (r.transpose() * Jr);
      r *= g;
    }
    ne.cost += r.squaredNorm();
    if (!with_jacobian) continue;
    ne.JtJ.noalias() += Jr.transpose() * Jr;
    ne.Jtr.noalias() += Jr.transpose() * r;
  }
  return ne;
}

bool MapMatchesFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  double* J = jacobians ? jacobians[0] : nullptr;
  const NormalEquations ne = normalEquations(parameters[0], J != nullptr);
  Eigen::Map<Eigen::Matrix<double, kReducedRows + 1, 1>> r(residuals);
  r.setZero();
  if (!J) {
    r(kReducedRows) = std::sqrt(ne.cost);  // only the cost is asked for
    return true;
  }
  Eigen::Map<Eigen::Matrix<double, kReducedRows + 1, 7, Eigen::RowMajor>> rows(J);
  rows.setZero();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(ne.JtJ);
  const double largest = std::max(es.eigenvalues().maxCoeff(), 0.0);
  double reduced_cost = 0.0;
  for (int k = 0; k < kReducedRows; ++k) {
    // Directions no match constrains (zero eigenvalues) have no gradient either: their rows stay 0.
    const double d = es.eigenvalues()(k);
    if (!(d > kRankTolerance * largest)) continue;
    const double s = std::sqrt(d);
    const Eigen::Matrix<double, 6, 1> v = es.eigenvectors().col(k);
    rows.block<1, 6>(k, 0) = s * v.transpose();
    r(k) = v.dot(ne.Jtr) / s;
    reduced_cost += r(k) * r(k);
  }
  r(kReducedRows) = std::sqrt(std::max(ne.cost - reduced_cost, 0.0));
  return true;
}

}  // namespace mmlio::estimator
