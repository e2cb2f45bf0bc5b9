#include "mmlio/backend/pose_graph.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <utility>

#include "mmlio/core/log.hpp"
#include "mmlio/core/so3.hpp"

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

/// A measured pose and the residual of an estimate against it: S [p_est - p; 2 vec(q^-1 q_est)]
/// (see the header for the formula).
struct MeasuredPose {
  MeasuredPose(const Eigen::Isometry3d& T, const Matrix6d& sqrt_info)
      : p(T.translation()), q(Eigen::Quaterniond(T.rotation()).normalized()), S(sqrt_info) {}

  template <typename T>
  void residual(const Eigen::Matrix<T, 3, 1>& p_est, const Eigen::Quaternion<T>& q_est, T* residual) const {
    const Eigen::Quaternion<T> dq = q.template cast<T>().conjugate() * q_est;
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = p_est - p.template cast<T>();
    r.template tail<3>() = T(2) * dq.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = S.template cast<T>() * r;
  }

  Eigen::Vector3d p;
  Eigen::Quaterniond q;
  Matrix6d S;
};

/// Relative-pose residual between poses a and b: b in a's frame against the measured T_a_b.
struct RelativePoseCost {
  RelativePoseCost(const Eigen::Isometry3d& T_a_b, const Matrix6d& sqrt_info) : ab(T_a_b, sqrt_info) {}

  template <typename T> bool operator()(const T* a, const T* b, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(a), p_b(b);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(a + 3), q_b(b + 3);
    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    ab.residual<T>(q_a_inv * (p_b - p_a), q_a_inv * q_b, residual);
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Isometry3d& T_a_b, const Matrix6d& sqrt_info) {
    return new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 7, 7>(new RelativePoseCost(T_a_b, sqrt_info));
  }

  MeasuredPose ab;
};

/// Absolute-pose residual of a pose against a measurement (same tangent as RelativePoseCost).
struct PriorCost {
  PriorCost(const Eigen::Isometry3d& T, const Matrix6d& sqrt_info) : measured(T, sqrt_info) {}

  template <typename T> bool operator()(const T* x, T* residual) const {
    measured.residual<T>(Eigen::Map<const Eigen::Matrix<T, 3, 1>>(x), Eigen::Map<const Eigen::Quaternion<T>>(x + 3),
                         residual);
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Isometry3d& T, const Matrix6d& sqrt_info) {
    return new ceres::AutoDiffCostFunction<PriorCost, 6, 7>(new PriorCost(T, sqrt_info));
  }

  MeasuredPose measured;
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
  nodes_.push_back(std::move(node));
  folded_.push_back(false);
  loop_end_.push_back(false);
  if (index == 0) {
    params_.push_back(toParams(nodes_.back().T_world_body_odom));
  } else {
    odom_edges_.push_back(edge(index - 1, index,
                               nodes_[index - 1].T_world_body_odom.inverse() * nodes_[index].T_world_body_odom,
                               isotropicInformation(cfg_.odom_sigma_translation_m, cfg_.odom_sigma_rotation_rad)));
    params_.push_back(toParams(pose(index - 1) * odom_edges_.back().T_from_to));
  }
  return index;
}

PoseGraph::Edge PoseGraph::edge(int from, int to, const Eigen::Isometry3d& T_from_to, const Matrix6d& information) {
  return Edge{from, to, T_from_to, sqrtInformation(information), information, information.inverse()};
}

std::vector<PoseGraph::LoopEdge> PoseGraph::loopEdges() const {
  std::vector<LoopEdge> out;
  out.reserve(loops_.size());
  for (const Edge& e : loops_) out.push_back({e.from, e.to, e.T_from_to, e.information});
  return out;
}

void PoseGraph::addLoop(int from, int to, const Eigen::Isometry3d& T_from_to, const Matrix6d& information) {
  const int n = static_cast<int>(nodes_.size());
  if (from < 0 || to < 0 || from >= n || to >= n || from == to)
    throw std::invalid_argument("PoseGraph::addLoop: keyframe index out of range");
  if (folded_[from] || folded_[to])
    throw std::invalid_argument("PoseGraph::addLoop: a folded keyframe cannot end a loop");
  loops_.push_back(edge(from, to, T_from_to, information));
  loop_end_[from] = loop_end_[to] = true;
}

void PoseGraph::addPrior(int k, const Eigen::Isometry3d& T_world_body, const Matrix6d& information) {
  if (k < 0 || k >= static_cast<int>(nodes_.size()))
    throw std::invalid_argument("PoseGraph::addPrior: keyframe index out of range");
  if (folded_[k]) throw std::invalid_argument("PoseGraph::addPrior: a folded keyframe cannot take a prior");
  priors_.push_back(edge(k, k, T_world_body, information));
  loop_end_[k] = true;
}

bool PoseGraph::fold(int i) {
  const int n = static_cast<int>(nodes_.size());
  if (i <= 0 || i >= n - 1 || folded_[i] || loop_end_[i]) return false;
  // Odometry edges join kept keyframes in order: the one leaving i follows the one reaching it.
  const auto out = std::lower_bound(odom_edges_.begin(), odom_edges_.end(), i,
                                    [](const Edge& e, int from) { return e.from < from; });
  const auto in = std::prev(out);
  // Composed T_ac = T_ab T_bc with independent noise (dp in the first frame, dtheta on the right,
  // as the residual): dp_ac = dp_ab - R_ab [p_bc]x dtheta_ab + R_ab dp_bc, dtheta_ac = R_bc^T dtheta_ab
  // + dtheta_bc. The rotation noise of the first leg moves the end sideways, which isotropic noise
  // per step would miss.
  const Eigen::Matrix3d R_ab = in->T_from_to.rotation(), R_bc = out->T_from_to.rotation();
  const Eigen::Vector3d p_bc = out->T_from_to.translation();
  Matrix6d A = Matrix6d::Zero(), B = Matrix6d::Zero();
  A.topLeftCorner<3, 3>().setIdentity();
  A.topRightCorner<3, 3>() = -R_ab * so3::hat(p_bc);
  A.bottomRightCorner<3, 3>() = R_bc.transpose();
  B.topLeftCorner<3, 3>() = R_ab;
  B.bottomRightCorner<3, 3>().setIdentity();
  Matrix6d covariance = A * in->covariance * A.transpose() + B * out->covariance * B.transpose();
  covariance = 0.5 * (covariance + covariance.transpose());
  *in = edge(in->from, out->to, in->T_from_to * out->T_from_to, covariance.inverse());
  odom_edges_.erase(out);
  folded_[i] = true;
  ++folded_count_;
  return true;
}

bool PoseGraph::optimize() {
  if (nodes_.size() < 2) return true;
  std::vector<Params> x = params_;
  ceres::Problem problem;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!folded_[i]) problem.AddParameterBlock(x[i].data(), 7, new ceres::AutoDiffManifold<RightPosePlus, 7, 6>());
  for (const Edge& e : odom_edges_)
    problem.AddResidualBlock(RelativePoseCost::Create(e.T_from_to, e.sqrt_information), nullptr, x[e.from].data(),
                             x[e.to].data());
  for (const Edge& e : loops_)
    problem.AddResidualBlock(RelativePoseCost::Create(e.T_from_to, e.sqrt_information),
                             cfg_.loop_huber > 0 ? new ceres::HuberLoss(cfg_.loop_huber) : nullptr, x[e.from].data(),
                             x[e.to].data());
  for (const Edge& e : priors_)
    problem.AddResidualBlock(PriorCost::Create(e.T_from_to, e.sqrt_information),
                             cfg_.loop_huber > 0 ? new ceres::HuberLoss(cfg_.loop_huber) : nullptr, x[e.from].data());
  if (cfg_.tilt_sigma_rad > 0.0)
    for (std::size_t i = 1; i < nodes_.size(); ++i)
      if (!folded_[i])
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
  log::debug("pose graph: ", optimised(), " of ", nodes_.size(), " keyframes, ", loops_.size(), " loops, cost ",
             summary.initial_cost, " -> ", summary.final_cost, " in ", summary.iterations.size(), " iterations");
  if (!summary.IsSolutionUsable()) {
    log::warn("pose graph optimisation failed: ", summary.message);
    return false;
  }
  for (auto& p : x) {
    Eigen::Map<Eigen::Quaterniond> q(p.data() + 3);
    q.normalize();
  }
  params_ = std::move(x);
  placeFolded();
  return true;
}

void PoseGraph::placeFolded() {
  if (folded_count_ == 0) return;
  const auto correctionAt = [&](int k) { return pose(k) * nodes_[k].T_world_body_odom.inverse(); };
  const int n = static_cast<int>(nodes_.size());
  for (int a = 0, b = 1; b < n; ++b) {
    if (folded_[b]) continue;
    if (b > a + 1) {  // a and b kept, a + 1 .. b - 1 folded
      const Eigen::Isometry3d C_a = correctionAt(a), C_b = correctionAt(b);
      const Eigen::Quaterniond q_a(C_a.rotation()), q_b(C_b.rotation());
      double total = 0.0;
      for (int i = a; i < b; ++i) total += odometryStep(i);
      double along = 0.0;
      for (int i = a + 1; i < b; ++i) {
        along += odometryStep(i - 1);
        const double w = total > 0.0 ? along / total : static_cast<double>(i - a) / (b - a);
        Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
        C.linear() = q_a.slerp(w, q_b).toRotationMatrix();
        C.translation() = (1.0 - w) * C_a.translation() + w * C_b.translation();
        params_[i] = toParams(C * nodes_[i].T_world_body_odom);
      }
    }
    a = b;
  }
}

void PoseGraph::dropCloud(int i) {
  auto& cloud = nodes_.at(static_cast<std::size_t>(i)).cloud_body;
  cloud.clear();
  cloud.shrink_to_fit();
}

double PoseGraph::odometryStep(int i) const {
  return (nodes_[i + 1].T_world_body_odom.translation() - nodes_[i].T_world_body_odom.translation()).norm();
}

double PoseGraph::routeLength(int a, int b) const {
  const int n = static_cast<int>(nodes_.size());
  if (a < 0 || b < 0 || a >= n || b >= n)
    throw std::invalid_argument("PoseGraph::routeLength: keyframe index out of range");
  // Dijkstra over the chain of odometry edges plus the loops' shortcuts.
  std::vector<std::vector<int>> shortcuts(nodes_.size());
  for (const Edge& e : loops_) {
    shortcuts[e.from].push_back(e.to);
    shortcuts[e.to].push_back(e.from);
  }
  std::vector<double> dist(nodes_.size(), std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  dist[a] = 0.0;
  open.push({0.0, a});
  while (!open.empty()) {
    const double d = open.top().first;  // not a structured binding: the lambda below captures it
    const int i = open.top().second;
    open.pop();
    if (i == b) return d;
    if (d > dist[i]) continue;
    const auto relax = [&](int j, double length) {
      if (d + length < dist[j]) {
        dist[j] = d + length;
        open.push({dist[j], j});
      }
    };
    if (i + 1 < n) relax(i + 1, odometryStep(i));
    if (i > 0) relax(i - 1, odometryStep(i - 1));
    for (const int j : shortcuts[i]) relax(j, 0.0);
  }
  return dist[b];  // the chain connects every keyframe: not reached
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
