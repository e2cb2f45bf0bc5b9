#include "mmlio/estimator/marginalization.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <stdexcept>
#include <unordered_set>

#include "mmlio/core/so3.hpp"

namespace mmlio::estimator {

int tangentSize(int global_size) { return global_size == 7 ? 6 : global_size; }

std::unordered_map<long, double*> addressShift(const std::vector<double*>& from, const std::vector<double*>& to) {
  if (from.size() != to.size()) throw std::invalid_argument("addressShift: from and to differ in length");
  std::unordered_map<long, double*> shift;
  for (std::size_t i = 0; i < from.size(); ++i) shift[reinterpret_cast<long>(from[i])] = to[i];
  return shift;
}

namespace {

/// Triggs correction of a robust loss (the scheme Ceres applies internally): afterwards
/// 1/2 |r|^2 and J^T J, J^T r match the second-order model of rho(|r|^2) / 2.
void applyLoss(const ceres::LossFunction& loss, Eigen::VectorXd& r, std::vector<Eigen::MatrixXd>& jacobians) {
  const double sq_norm = r.squaredNorm();
  double rho[3];
  loss.Evaluate(sq_norm, rho);
  const double sqrt_rho1 = std::sqrt(std::max(rho[1], 0.0));
  double residual_scaling = sqrt_rho1, alpha_sq_norm = 0.0;
  if (sq_norm > 0.0 && rho[2] > 0.0 && rho[1] > 0.0) {
    const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * sq_norm * rho[2] / rho[1]);
    residual_scaling = sqrt_rho1 / (1.0 - alpha);
    alpha_sq_norm = alpha / sq_norm;
  }
  for (auto& J : jacobians) J = sqrt_rho1 * (J - alpha_sq_norm * r * (r.transpose() * J));
  r *= residual_scaling;
}

/// Pseudo-inverse / square-root helpers on a symmetric matrix via its eigen decomposition.
Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> symmetricEigen(const Eigen::MatrixXd& A) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (A + A.transpose()));
}

}  // namespace

MarginalizationInfo::MarginalizationInfo(double eigenvalue_floor) : eigenvalue_floor_(eigenvalue_floor) {}

MarginalizationInfo::~MarginalizationInfo() { releaseFactors(); }

void MarginalizationInfo::releaseFactors() {
  std::unordered_set<ceres::CostFunction*> costs;
  std::unordered_set<ceres::LossFunction*> losses;
  for (auto& f : factors_) {
    if (f.info.cost) costs.insert(f.info.cost);
    if (f.info.loss) losses.insert(f.info.loss);
  }
  for (auto* c : costs) delete c;
  for (auto* l : losses) delete l;
  factors_ = {};
}

void MarginalizationInfo::addResidualBlock(ResidualBlockInfo info) {
  if (!info.cost) throw std::invalid_argument("MarginalizationInfo: residual block without a cost function");
  const auto& sizes = info.cost->parameter_block_sizes();
  if (sizes.size() != info.blocks.size())
    throw std::invalid_argument("MarginalizationInfo: cost function and block list disagree in length");
  for (int idx : info.drop_indices)
    if (idx < 0 || idx >= static_cast<int>(info.blocks.size()))
      throw std::invalid_argument("MarginalizationInfo: drop index out of range");
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    auto [it, inserted] = block_size_.emplace(info.blocks[i], sizes[i]);
    if (!inserted && it->second != sizes[i])
      throw std::invalid_argument("MarginalizationInfo: one parameter block used with two sizes");
  }
  Factor f;
  f.info = std::move(info);
  factors_.push_back(std::move(f));
  pre_marginalized_ = false;
  valid_ = false;
}

void MarginalizationInfo::preMarginalize() {
  for (auto& f : factors_) {
    const auto& sizes = f.info.cost->parameter_block_sizes();
    const int m = f.info.cost->num_residuals();
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> ambient(sizes.size());
    std::vector<double*> jac_ptrs(sizes.size());
    for (std::size_t i = 0; i < sizes.size(); ++i) {
      ambient[i].setZero(m, sizes[i]);
      jac_ptrs[i] = ambient[i].data();
    }
    f.residual.setZero(m);
    f.info.cost->Evaluate(f.info.blocks.data(), f.residual.data(), jac_ptrs.data());
    f.jacobians.resize(sizes.size());
    for (std::size_t i = 0; i < sizes.size(); ++i) f.jacobians[i] = ambient[i].leftCols(tangentSize(sizes[i]));
    if (f.info.loss) applyLoss(*f.info.loss, f.residual, f.jacobians);
    for (std::size_t i = 0; i < sizes.size(); ++i)
      values_[f.info.blocks[i]] = Eigen::Map<const Eigen::VectorXd>(f.info.blocks[i], sizes[i]);
  }
  pre_marginalized_ = true;
}

void MarginalizationInfo::marginalize() {
  if (!pre_marginalized_) throw std::logic_error("MarginalizationInfo::marginalize() before preMarginalize()");
  // Order: dropped blocks first, then kept blocks, each by first appearance (deterministic).
  std::unordered_set<const double*> dropped;
  for (const auto& f : factors_)
    for (int idx : f.info.drop_indices) dropped.insert(f.info.blocks[idx]);
  std::vector<double*> dropped_order;
  kept_blocks_.clear();
  std::unordered_set<const double*> seen;
  for (const auto& f : factors_)
    for (double* b : f.info.blocks)
      if (seen.insert(b).second) (dropped.count(b) ? dropped_order : kept_blocks_).push_back(b);

  std::unordered_map<const double*, int> offset;
  int dim = 0;
  for (double* b : dropped_order) {
    offset[b] = dim;
    dim += tangentSize(block_size_.at(b));
  }
  dropped_dim_ = dim;
  kept_sizes_.clear();
  kept_offsets_.clear();
  kept_values_.clear();
  for (double* b : kept_blocks_) {
    offset[b] = dim;
    kept_sizes_.push_back(block_size_.at(b));
    kept_offsets_.push_back(dim - dropped_dim_);
    kept_values_.push_back(values_.at(b));
    dim += tangentSize(block_size_.at(b));
  }
  kept_dim_ = dim - dropped_dim_;

  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
  for (const auto& f : factors_) {
    for (std::size_t i = 0; i < f.info.blocks.size(); ++i) {
      const int oi = offset.at(f.info.blocks[i]);
      const Eigen::MatrixXd& Ji = f.jacobians[i];
      g.segment(oi, Ji.cols()) += Ji.transpose() * f.residual;
      for (std::size_t j = i; j < f.info.blocks.size(); ++j) {
        const int oj = offset.at(f.info.blocks[j]);
        const Eigen::MatrixXd JiJj = Ji.transpose() * f.jacobians[j];
        H.block(oi, oj, JiJj.rows(), JiJj.cols()) += JiJj;
        if (j != i) H.block(oj, oi, JiJj.cols(), JiJj.rows()) += JiJj.transpose();
      }
    }
  }

  const int m = dropped_dim_, n = kept_dim_;
  Eigen::MatrixXd H_prior = H.bottomRightCorner(n, n);
  Eigen::VectorXd g_prior = g.tail(n);
  if (m > 0) {
    const auto eig = symmetricEigen(H.topLeftCorner(m, m));
    const Eigen::VectorXd inv =
        (eig.eigenvalues().array() > eigenvalue_floor_).select(eig.eigenvalues().array().inverse(), 0.0);
    const Eigen::MatrixXd H_mm_inv = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
    const Eigen::MatrixXd H_rm = H.bottomLeftCorner(n, m);
    H_prior -= H_rm * H_mm_inv * H_rm.transpose();
    g_prior -= H_rm * H_mm_inv * g.head(m);
  }
  const auto eig = symmetricEigen(H_prior);
  const Eigen::ArrayXd lambda = eig.eigenvalues().array();
  const Eigen::VectorXd s_sqrt = (lambda > eigenvalue_floor_).select(lambda.sqrt(), 0.0);
  const Eigen::VectorXd s_inv_sqrt = (lambda > eigenvalue_floor_).select(lambda.sqrt().inverse(), 0.0);
  J_ = s_sqrt.asDiagonal() * eig.eigenvectors().transpose();
  r0_ = s_inv_sqrt.asDiagonal() * eig.eigenvectors().transpose() * g_prior;
  valid_ = n > 0 && J_.allFinite() && r0_.allFinite();
  // The prior is (J, r0) from here on. Kept, the factors would hold every match of the dropped
  // keyframe, and the previous prior's factor the previous prior: a chain as long as the run.
  releaseFactors();
  pre_marginalized_ = false;
}

std::vector<double*> MarginalizationInfo::keptBlockAddresses(const std::unordered_map<long, double*>& shift) const {
  std::vector<double*> out;
  out.reserve(kept_blocks_.size());
  for (double* b : kept_blocks_) {
    const auto it = shift.find(reinterpret_cast<long>(b));
    out.push_back(it == shift.end() ? b : it->second);
  }
  return out;
}

bool MarginalizationInfo::valid() const { return valid_; }

MarginalizationFactor::MarginalizationFactor(std::shared_ptr<const MarginalizationInfo> info) : info_(std::move(info)) {
  if (!info_ || !info_->valid()) throw std::invalid_argument("MarginalizationFactor: invalid marginalization info");
  set_num_residuals(info_->keptTangentSize());
  for (int s : info_->keptBlockSizes()) mutable_parameter_block_sizes()->push_back(s);
}

bool MarginalizationFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const auto& sizes = info_->keptBlockSizes();
  const auto& offsets = info_->keptBlockTangentOffsets();
  const auto& x0 = info_->keptBlockValues();
  const int n = info_->keptTangentSize();
  const Eigen::MatrixXd& J = info_->linearizedJacobian();

  Eigen::VectorXd dx(n);
  std::vector<Eigen::Vector3d> dtheta(sizes.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    const int o = offsets[i];
    if (sizes[i] == 7) {
      const Eigen::Map<const Eigen::Vector3d> p(parameters[i]);
      const Eigen::Map<const Eigen::Quaterniond> q(parameters[i] + 3);
      const Eigen::Quaterniond q0(x0[i][6], x0[i][3], x0[i][4], x0[i][5]);
      dx.segment<3>(o) = p - x0[i].head<3>();
      dtheta[i] = so3::log(q0.conjugate() * q.normalized());
      dx.segment<3>(o + 3) = dtheta[i];
    } else {
      dx.segment(o, sizes[i]) = Eigen::Map<const Eigen::VectorXd>(parameters[i], sizes[i]) - x0[i];
    }
  }
  Eigen::Map<Eigen::VectorXd>(residuals, n) = info_->linearizedResidual() + J * dx;

  if (jacobians) {
    for (std::size_t i = 0; i < sizes.size(); ++i) {
      if (!jacobians[i]) continue;
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Ji(jacobians[i], n, sizes[i]);
      Ji.setZero();
      const int o = offsets[i];
      if (sizes[i] == 7) {
        Ji.leftCols<3>() = J.middleCols<3>(o);
        Ji.middleCols<3>(3) = J.middleCols<3>(o + 3) * so3::rightJacobianInverse(dtheta[i]);
      } else {
        Ji = J.middleCols(o, sizes[i]);
      }
    }
  }
  return true;
}

}  // namespace mmlio::estimator
