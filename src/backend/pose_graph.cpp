#include "mmlio/backend/pose_graph.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <stdexcept>

#include "mmlio/core/log.hpp"

namespace mmlio::backend {
namespace {

using Params = std::array<double, 7>;

Params toParams(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.rotation());
  return {T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w()};
}

Eigen::Isometry3d fromParams(const Params& x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(x[6], x[3], x[4], x[5]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(x[0], x[1], x[2]);
  return T;
}

/// Right-perturbed pose manifold on {p, q(x,y,z,w)}: p <- p + dp, q <- q * Exp(dtheta)
/// (the project's estimator convention), differentiated by Ceres.
struct RightPosePlus {
  template <typename T> bool Plus(const T* x, const T* delta, T* x_plus_delta) const {
    for (int i = 0; i < 3; ++i) x_plus_delta[i] = x[i] + delta[i];
    const T theta_sq = delta[3] * delta[3] + delta[4] * delta[4] + delta[5] * delta[5];
    Eigen::Quaternion<T> dq;
    if (theta_sq > T(1e-16)) {
      using std::cos;
      using std::sin;
      using std::sqrt;
      const T theta = sqrt(theta_sq);
      const T k = sin(theta / T(2)) / theta;
      dq = Eigen::Quaternion<T>(cos(theta / T(2)), k * delta[3], k * delta[4], k * delta[5]);
    } else {  // first order; exact derivative at delta = 0
      dq = Eigen::Quaternion<T>(T(1), delta[3] / T(2), delta[4] / T(2), delta[5] / T(2));
    }
    const Eigen::Map<const Eigen::Quaternion<T>> q(x + 3);
    Eigen::Map<Eigen::Quaternion<T>> out(x_plus_delta + 3);
    out = (q * dq).normalized();
    return true;
  }
  template <typename T> bool Minus(const T* y, const T* x, T* y_minus_x) const {
    for (int i = 0; i < 3; ++i) y_minus_x[i] = y[i] - x[i];
    const Eigen::Map<const Eigen::Quaternion<T>> qx(x + 3), qy(y + 3);
    Eigen::Quaternion<T> d = qx.conjugate() * qy;
    if (d.w() < T(0)) d.coeffs() = -d.coeffs();
    const T n_sq = d.vec().squaredNorm();
    if (n_sq > T(1e-16)) {
      using std::atan2;
      using std::sqrt;
      const T n = sqrt(n_sq);
      const T k = T(2) * atan2(n, d.w()) / n;
      for (int i = 0; i < 3; ++i) y_minus_x[3 + i] = k * d.vec()[i];
    } else {
      for (int i = 0; i < 3; ++i) y_minus_x[3 + i] = T(2) * d.vec()[i];
    }
    return true;
  }
};

/// Relative-pose residual between poses a and b (see the header for the formula).
struct RelativePoseCost {
  RelativePoseCost(const Eigen::Isometry3d& T_a_b, const Matrix6d& sqrt_info)
      : p_ab(T_a_b.translation()), q_ab(Eigen::Quaterniond(T_a_b.rotation()).normalized()), S(sqrt_info) {}

  template <typename T> bool operator()(const T* a, const T* b, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(a), p_b(b);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(a + 3), q_b(b + 3);
    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    const Eigen::Matrix<T, 3, 1> p_ab_est = q_a_inv * (p_b - p_a);
    const Eigen::Quaternion<T> dq = q_ab.template cast<T>().conjugate() * (q_a_inv * q_b);
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = p_ab_est - p_ab.template cast<T>();
    r.template tail<3>() = T(2) * dq.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = S.template cast<T>() * r;
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Isometry3d& T_a_b, const Matrix6d& sqrt_info) {
    return new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 7, 7>(new RelativePoseCost(T_a_b, sqrt_info));
  }

  Eigen::Vector3d p_ab;
  Eigen::Quaterniond q_ab;
  Matrix6d S;
};

/// Keeps a keyframe's gravity direction (roll, pitch) at its odometry value.
struct TiltCost {
  TiltCost(const Eigen::Quaterniond& q_world_body_odom, double sigma_rad)
      : up_body(q_world_body_odom.conjugate() * Eigen::Vector3d::UnitZ()), inv_sigma(1.0 / sigma_rad) {}

  template <typename T> bool operator()(const T* x, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(x + 3);
    const Eigen::Matrix<T, 3, 1> up = q.conjugate() * Eigen::Matrix<T, 3, 1>::UnitZ();
    for (int i = 0; i < 3; ++i) residual[i] = T(inv_sigma) * (up[i] - T(up_body[i]));
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Quaterniond& q_world_body_odom, double sigma_rad) {
    return new ceres::AutoDiffCostFunction<TiltCost, 3, 7>(new TiltCost(q_world_body_odom, sigma_rad));
  }

  Eigen::Vector3d up_body;
  double inv_sigma;
};

Matrix6d sqrtInformation(const Matrix6d& information) {
  const Eigen::LLT<Matrix6d> llt(information);
  if (llt.info() != Eigen::Success)
    throw std::invalid_argument("PoseGraph: information matrix is not positive definite");
  return llt.matrixL().transpose();
}

}  // namespace

Matrix6d isotropicInformation(double sigma_translation_m, double sigma_rotation_rad) {
  Matrix6d info = Matrix6d::Zero();
  info.diagonal().head<3>().setConstant(1.0 / (sigma_translation_m * sigma_translation_m));
  info.diagonal().tail<3>().setConstant(1.0 / (sigma_rotation_rad * sigma_rotation_rad));
  return info;
}

PoseGraph::PoseGraph() : PoseGraph(Config{}) {}
PoseGraph::PoseGraph(Config cfg) : cfg_(cfg) {}

int PoseGraph::addKeyframe(KeyframeNode node) {
  if (!nodes_.empty() && node.stamp_ns < nodes_.back().stamp_ns)
    throw std::invalid_argument("PoseGraph::addKeyframe: keyframe stamps must not decrease");
  const int index = static_cast<int>(nodes_.size());
  if (nodes_.empty()) {
    params_.push_back(toParams(node.T_world_body_odom));
  } else {
    const Eigen::Isometry3d T_prev_cur = nodes_.back().T_world_body_odom.inverse() * node.T_world_body_odom;
    params_.push_back(toParams(pose(index - 1) * T_prev_cur));
    odom_edges_.push_back(
        Edge{index - 1, index, T_prev_cur,
             sqrtInformation(isotropicInformation(cfg_.odom_sigma_translation_m, cfg_.odom_sigma_rotation_rad))});
  }
  nodes_.push_back(std::move(node));
  return index;
}

void PoseGraph::addLoop(int from, int to, const Eigen::Isometry3d& T_from_to, const Matrix6d& information) {
  const int n = static_cast<int>(nodes_.size());
  if (from < 0 || to < 0 || from >= n || to >= n || from == to)
    throw std::invalid_argument("PoseGraph::addLoop: keyframe index out of range");
  loops_.push_back(Edge{from, to, T_from_to, sqrtInformation(information)});
}

bool PoseGraph::optimize() {
  if (nodes_.size() < 2) return true;
  std::vector<Params> x = params_;
  ceres::Problem problem;
  for (auto& p : x) problem.AddParameterBlock(p.data(), 7, new ceres::AutoDiffManifold<RightPosePlus, 7, 6>());
  for (const Edge& e : odom_edges_)
    problem.AddResidualBlock(RelativePoseCost::Create(e.T_from_to, e.sqrt_information), nullptr, x[e.from].data(),
                             x[e.to].data());
  for (const Edge& e : loops_)
    problem.AddResidualBlock(RelativePoseCost::Create(e.T_from_to, e.sqrt_information),
                             cfg_.loop_huber > 0 ? new ceres::HuberLoss(cfg_.loop_huber) : nullptr, x[e.from].data(),
                             x[e.to].data());
  if (cfg_.tilt_sigma_rad > 0.0)
    for (std::size_t i = 1; i < nodes_.size(); ++i)
      problem.AddResidualBlock(
          TiltCost::Create(Eigen::Quaterniond(nodes_[i].T_world_body_odom.rotation()), cfg_.tilt_sigma_rad), nullptr,
          x[i].data());
  problem.SetParameterBlockConstant(x[0].data());

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE)
                                   ? ceres::SPARSE_NORMAL_CHOLESKY
                                   : ceres::DENSE_QR;
  options.max_num_iterations = cfg_.max_iterations;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  log::debug("pose graph: ", nodes_.size(), " keyframes, ", loops_.size(), " loops, cost ", summary.initial_cost,
             " -> ", summary.final_cost, " in ", summary.iterations.size(), " iterations");
  if (!summary.IsSolutionUsable()) {
    log::warn("pose graph optimisation failed: ", summary.message);
    return false;
  }
  for (auto& p : x) {
    Eigen::Map<Eigen::Quaterniond> q(p.data() + 3);
    q.normalize();
  }
  params_ = std::move(x);
  return true;
}

void PoseGraph::dropCloud(int i) {
  auto& cloud = nodes_.at(static_cast<std::size_t>(i)).cloud_body;
  cloud.clear();
  cloud.shrink_to_fit();
}

Eigen::Isometry3d PoseGraph::pose(int i) const { return fromParams(params_.at(static_cast<std::size_t>(i))); }

Eigen::Isometry3d PoseGraph::correct(Stamp t, const Eigen::Isometry3d& T_world_body_odom) const {
  // Last keyframe with stamp <= t.
  const auto it =
      std::upper_bound(nodes_.begin(), nodes_.end(), t, [](Stamp s, const KeyframeNode& n) { return s < n.stamp_ns; });
  if (it == nodes_.begin()) return T_world_body_odom;
  const int k = static_cast<int>(std::distance(nodes_.begin(), it)) - 1;
  return pose(k) * nodes_[k].T_world_body_odom.inverse() * T_world_body_odom;
}

}  // namespace mmlio::backend
