#include "mmlio/backend/point_to_plane_icp.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "mmlio/core/so3.hpp"
#include "mmlio/map/kd_tree.hpp"

namespace mmlio::backend {
namespace {

using map::CloudAdaptor;
using KdTree = map::KdTree3d;

double geometric(double a, double b, int level, int levels) {
  if (levels <= 1) return b;
  return a * std::pow(b / a, static_cast<double>(level) / (levels - 1));
}

}  // namespace

struct IcpTarget::Impl {
  enum Normal : std::uint8_t { kUnknown, kPlane, kNone };
  std::vector<Eigen::Vector3d> points;
  std::size_t normal_neighbours = 10;
  double min_patch_width_m = 0.04;
  // Normals are fitted on first use: an alignment touches only the target points nearest to its
  // source, and a loop check that stops early touches few of them.
  std::vector<Eigen::Vector3d> normals;
  std::vector<Normal> normal_state;
  CloudAdaptor adaptor{nullptr};
  std::unique_ptr<KdTree> tree;

  void fitNormal(std::size_t i) {
    normal_state[i] = kNone;
    const std::size_t k = normal_neighbours;
    if (points.size() < k) return;
    thread_local std::vector<std::uint32_t> idx;
    thread_local std::vector<double> d2;
    idx.resize(k);
    d2.resize(k);
    const std::size_t n = tree->knnSearch(points[i].data(), k, idx.data(), d2.data());
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < n; ++j) mean += points[idx[j]];
    mean /= static_cast<double>(n);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t j = 0; j < n; ++j) {
      const Eigen::Vector3d d = points[idx[j]] - mean;
      cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const Eigen::Vector3d& ev = es.eigenvalues();  // ascending
    // A plane: thin (smallest << middle) and wide in its second direction too. The absolute
    // width test matters: neighbours from one scan line (or one column of rings hitting a wall
    // at grazing incidence) form a line whose range noise alone would pass a ratio test and give
    // an arbitrary "normal".
    const double width_sq = min_patch_width_m * min_patch_width_m * static_cast<double>(n);
    if (ev(0) < 0.1 * ev(1) && ev(1) > width_sq) {
      normals[i] = es.eigenvectors().col(0);
      normal_state[i] = kPlane;
    }
  }
  bool hasNormal(std::size_t i) {
    if (normal_state[i] == kUnknown) fitNormal(i);
    return normal_state[i] == kPlane;
  }
};

IcpTarget::IcpTarget(std::vector<Eigen::Vector3d> points, int normal_neighbours, double min_patch_width_m)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.points = std::move(points);
  m.normal_neighbours = static_cast<std::size_t>(std::max(3, normal_neighbours));
  m.min_patch_width_m = min_patch_width_m;
  m.adaptor.pts = &m.points;
  m.tree = std::make_unique<KdTree>(3, m.adaptor, map::kdTreeParams());
  m.normals.assign(m.points.size(), Eigen::Vector3d::UnitZ());
  m.normal_state.assign(m.points.size(), Impl::kUnknown);
}

IcpTarget::~IcpTarget() = default;
IcpTarget::IcpTarget(IcpTarget&&) noexcept = default;
IcpTarget& IcpTarget::operator=(IcpTarget&&) noexcept = default;

std::size_t IcpTarget::size() const { return impl_->points.size(); }
const std::vector<Eigen::Vector3d>& IcpTarget::points() const { return impl_->points; }
const Eigen::Vector3d& IcpTarget::normal(std::size_t i) const {
  impl_->hasNormal(i);
  return impl_->normals[i];
}
bool IcpTarget::hasNormal(std::size_t i) const { return impl_->hasNormal(i); }

int IcpTarget::nearestWithin(const Eigen::Vector3d& q, double max_dist_sq, int hint) const {
  if (hint >= 0 && static_cast<std::size_t>(hint) < impl_->points.size()) {
    // Only points strictly nearer than the bound are taken: just above the hint's distance, the
    // hint itself still counts, and the nearest point is found as by the full search.
    const double hint_sq = (impl_->points[static_cast<std::size_t>(hint)] - q).squaredNorm();
    if (hint_sq < max_dist_sq) max_dist_sq = std::nextafter(hint_sq, std::numeric_limits<double>::infinity());
  }
  return nearestWithin(q, max_dist_sq);
}

int IcpTarget::nearestWithin(const Eigen::Vector3d& q, double max_dist_sq) const {
  if (impl_->points.empty()) return -1;
  std::uint32_t idx = 0;
  double d2 = 0;
  nanoflann::KNNResultSet<double, std::uint32_t> result(1);
  result.init(&idx, &d2);
  d2 = max_dist_sq;  // the search bound from the start: branches beyond the gate are not visited
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams());
  return result.size() == 0 ? -1 : static_cast<int>(idx);
}

IcpResult alignPointToPlane(const std::vector<Eigen::Vector3d>& source, const IcpTarget& target,
                            const Eigen::Isometry3d& T_target_source_guess, const IcpConfig& cfg) {
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  IcpResult result;
  result.T_target_source = T_target_source_guess;
  if (target.size() == 0 || source.empty()) return result;

  Eigen::Isometry3d T = T_target_source_guess;
  const int levels = std::max(1, cfg.levels);
  std::vector<Eigen::Vector3d> src;
  std::vector<int> previous;  // per source point, its match in the last iteration (-1: none)
  Matrix6d H;
  Vector6d g;
  int n_valid = 0;
  double abs_sum = 0;
  for (int level = 0; level < levels; ++level) {
    const double gate = geometric(cfg.max_corr_coarse_m, cfg.max_corr_fine_m, level, levels);
    src = map::voxelCentroids(source, geometric(cfg.voxel_coarse_m, cfg.voxel_fine_m, level, levels));
    if (cfg.max_source_points > 0 && src.size() > cfg.max_source_points) {
      const std::size_t stride = (src.size() + cfg.max_source_points - 1) / cfg.max_source_points;
      std::size_t kept = 0;
      for (std::size_t i = 0; i < src.size(); i += stride) src[kept++] = src[i];
      src.resize(kept);
    }
    const double gate_sq = gate * gate;
    previous.assign(src.size(), -1);
    for (int it = 0; it < cfg.max_iterations_per_level; ++it) {
      H.setZero();
      g.setZero();
      n_valid = 0;
      abs_sum = 0;
      for (std::size_t i = 0; i < src.size(); ++i) {
        const Eigen::Vector3d x = T * src[i];
        const int j = target.nearestWithin(x, gate_sq, previous[i]);
        previous[i] = j;
        if (j < 0 || !target.hasNormal(static_cast<std::size_t>(j))) continue;
        const Eigen::Vector3d& n = target.normal(static_cast<std::size_t>(j));
        const double r = n.dot(x - target.points()[static_cast<std::size_t>(j)]);
        Vector6d J;
        J.head<3>() = n;
        J.tail<3>() = x.cross(n);  // n^T (-hat(x)) = (x × n)^T
        H.noalias() += J * J.transpose();
        g.noalias() += J * r;
        abs_sum += std::abs(r);
        ++n_valid;
      }
      ++result.iterations;
      if (n_valid < cfg.min_correspondences) {  // not converged; say how few there were
        result.correspondences = n_valid;
        return result;
      }
      const Vector6d delta = (H + 1e-9 * Matrix6d::Identity()).ldlt().solve(-g);
      Eigen::Isometry3d dT = Eigen::Isometry3d::Identity();
      dT.linear() = so3::exp(delta.tail<3>()).toRotationMatrix();
      dT.translation() = delta.head<3>();
      T = dT * T;
      if (delta.head<3>().norm() < cfg.converged_translation_m && delta.tail<3>().norm() < cfg.converged_rotation_rad)
        break;
    }
    if (level + 1 < levels && cfg.continue_after_level && !cfg.continue_after_level(level, T)) {
      result.T_target_source = T;
      return result;
    }
  }
  // Final statistics at the finest gate, at the final pose.
  const double gate_sq = cfg.max_corr_fine_m * cfg.max_corr_fine_m;
  H.setZero();
  n_valid = 0;
  abs_sum = 0;
  int overlapping = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    const Eigen::Vector3d x = T * src[i];
    const int j = target.nearestWithin(x, gate_sq, previous[i]);
    if (j < 0) continue;
    ++overlapping;
    if (!target.hasNormal(static_cast<std::size_t>(j))) continue;
    const Eigen::Vector3d& n = target.normal(static_cast<std::size_t>(j));
    Vector6d J;
    J.head<3>() = n;
    J.tail<3>() = x.cross(n);
    H.noalias() += J * J.transpose();
    abs_sum += std::abs(n.dot(x - target.points()[static_cast<std::size_t>(j)]));
    ++n_valid;
  }
  result.T_target_source = T;
  result.correspondences = n_valid;
  result.overlap = src.empty() ? 0.0 : static_cast<double>(overlapping) / static_cast<double>(src.size());
  if (n_valid < cfg.min_correspondences) return result;
  result.converged = true;
  result.fitness_m = abs_sum / n_valid;
  result.hessian_normalised = H / n_valid;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(result.hessian_normalised.topLeftCorner<3, 3>());
  result.min_translation_eigenvalue = es.eigenvalues()(0);
  result.weakest_translation_direction = es.eigenvectors().col(0);
  return result;
}

}  // namespace mmlio::backend
