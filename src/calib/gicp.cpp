#include "mmlio/calib/gicp.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_map>

#include "mmlio/core/so3.hpp"
#include "mmlio/map/kd_tree.hpp"

namespace mmlio::calib {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

using map::CloudAdaptor;
using KdTree = map::KdTree3d;

double geometric(double a, double b, int level, int levels) {
  if (levels <= 1) return b;
  return a * std::pow(b / a, static_cast<double>(level) / (levels - 1));
}

std::vector<Eigen::Matrix3d> covariancesWithTree(const std::vector<Eigen::Vector3d>& points, const KdTree& tree,
                                                 int k_in, double eps) {
  std::vector<Eigen::Matrix3d> covs(points.size(), Eigen::Matrix3d::Identity() * eps);
  const std::size_t k = static_cast<std::size_t>(std::max(3, k_in));
  if (points.size() < k) return covs;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<std::uint32_t> idx(k);
                      std::vector<double> d2(k);
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const std::size_t n = tree.knnSearch(points[i].data(), k, idx.data(), d2.data());
                        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
                        for (std::size_t j = 0; j < n; ++j) mean += points[idx[j]];
                        mean /= static_cast<double>(n);
                        Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
                        for (std::size_t j = 0; j < n; ++j) {
                          const Eigen::Vector3d d = points[idx[j]] - mean;
                          c += d * d.transpose();
                        }
                        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(c);
                        // Segal et al.: keep the directions, replace the spread by a unit disc of thickness eps.
                        const Eigen::Vector3d values(eps, 1.0, 1.0);
                        covs[i] = es.eigenvectors() * values.asDiagonal() * es.eigenvectors().transpose();
                      }
                    });
  return covs;
}

}  // namespace

std::vector<Eigen::Matrix3d> planeCovariances(const std::vector<Eigen::Vector3d>& points, int k, double plane_epsilon) {
  CloudAdaptor adaptor{&points};
  KdTree tree(3, adaptor, map::kdTreeParams());
  tree.buildIndex();
  return covariancesWithTree(points, tree, k, plane_epsilon);
}

GicpTarget::GicpTarget(std::vector<Eigen::Vector3d> points, const GicpConfig& cfg)
    : points_(std::move(points)), adaptor_{&points_}, tree_(3, adaptor_, map::kdTreeParams()) {
  tree_.buildIndex();
  covariances_ = covariancesWithTree(points_, tree_, cfg.covariance_neighbours, cfg.plane_epsilon);
}

GicpResult gicp(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                const Eigen::Isometry3d& T_target_source_guess, const GicpConfig& cfg) {
  if (source.empty() || target.size() < 3) {
    GicpResult result;
    result.T_target_source = T_target_source_guess;
    return result;
  }
  return gicp(source, GicpTarget(target, cfg), T_target_source_guess, cfg);
}

GicpResult gicp(const std::vector<Eigen::Vector3d>& source, const GicpTarget& target_cloud,
                const Eigen::Isometry3d& T_target_source_guess, const GicpConfig& cfg) {
  GicpResult result;
  result.T_target_source = T_target_source_guess;
  const std::vector<Eigen::Vector3d>& target = target_cloud.points();
  if (source.empty() || target.size() < 3) return result;

  const KdTree& target_tree = target_cloud.tree();
  const std::vector<Eigen::Matrix3d>& target_covs = target_cloud.covariances();
  std::vector<Eigen::Matrix3d> source_covs;
  if (cfg.source_covariances) {
    source_covs = planeCovariances(source, cfg.covariance_neighbours, cfg.plane_epsilon);
  } else {
    source_covs.assign(source.size(), Eigen::Matrix3d::Identity() * cfg.plane_epsilon);
  }

  // Per-point linearisation in parallel, summed serially in index order: deterministic.
  std::vector<int> match(source.size(), -1);
  std::vector<Matrix6d> Hs(source.size());
  std::vector<Vector6d> gs(source.size());
  std::vector<double> dist(source.size(), 0.0);
  Eigen::Isometry3d T = T_target_source_guess;

  auto linearise = [&](double gate_m, Matrix6d* H, Vector6d* g, int* n_inliers, double* dist_sum) {
    const double gate_sq = gate_m * gate_m;
    const Eigen::Matrix3d R = T.linear();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, source.size(), 256),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          const Eigen::Vector3d x = T * source[i];
                          std::uint32_t j = 0;
                          double d2 = 0;
                          target_tree.knnSearch(x.data(), 1, &j, &d2);
                          if (d2 > gate_sq) {
                            match[i] = -1;
                            continue;
                          }
                          match[i] = static_cast<int>(j);
                          dist[i] = std::sqrt(d2);
                          const Eigen::Matrix3d C = target_covs[j] + R * source_covs[i] * R.transpose();
                          const Eigen::Matrix3d W = C.inverse();
                          const Eigen::Vector3d res = target[j] - x;
                          Eigen::Matrix<double, 3, 6> J;
                          J.leftCols<3>() = -Eigen::Matrix3d::Identity();
                          J.rightCols<3>() = so3::hat(x);
                          Hs[i].noalias() = J.transpose() * W * J;
                          gs[i].noalias() = J.transpose() * W * res;
                        }
                      });
    H->setZero();
    g->setZero();
    *n_inliers = 0;
    *dist_sum = 0;
    for (std::size_t i = 0; i < source.size(); ++i) {
      if (match[i] < 0) continue;
      *H += Hs[i];
      *g += gs[i];
      *dist_sum += dist[i];
      ++*n_inliers;
    }
  };

  const int levels = std::max(1, cfg.levels);
  Matrix6d H;
  Vector6d g;
  int n = 0;
  double dist_sum = 0;
  bool last_level_converged = false;
  for (int level = 0; level < levels; ++level) {
    const double gate = geometric(cfg.max_corr_dist_coarse_m, cfg.max_corr_dist_fine_m, level, levels);
    last_level_converged = false;
    for (int it = 0; it < cfg.max_iterations_per_level; ++it) {
      linearise(gate, &H, &g, &n, &dist_sum);
      ++result.iterations;
      if (n < cfg.min_correspondences) return result;
      // Levenberg-style damping keeps a near-degenerate system (few planes) from jumping.
      const Vector6d delta =
          (H + 1e-6 * H.diagonal().asDiagonal().toDenseMatrix() + 1e-9 * Matrix6d::Identity()).ldlt().solve(-g);
      Eigen::Isometry3d dT = Eigen::Isometry3d::Identity();
      dT.linear() = so3::exp(delta.tail<3>()).toRotationMatrix();
      dT.translation() = delta.head<3>();
      T = dT * T;
      if (delta.head<3>().norm() < cfg.converged_translation_m && delta.tail<3>().norm() < cfg.converged_rotation_rad) {
        last_level_converged = true;
        break;
      }
      // Correspondences flickering at the gate keep a settled solution moving by a hair: still settled.
      last_level_converged = delta.head<3>().norm() < cfg.settled_factor * cfg.converged_translation_m &&
                             delta.tail<3>().norm() < cfg.settled_factor * cfg.converged_rotation_rad;
    }
  }
  linearise(cfg.max_corr_dist_fine_m, &H, &g, &n, &dist_sum);
  result.T_target_source = T;
  result.inliers = n;
  result.overlap = static_cast<double>(n) / static_cast<double>(source.size());
  result.fitness_m = n > 0 ? dist_sum / n : 0.0;
  result.hessian = H;
  result.converged = n >= cfg.min_correspondences && last_level_converged;
  return result;
}

}  // namespace mmlio::calib
