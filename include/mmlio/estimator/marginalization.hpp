#pragma once
// Schur-complement marginalisation prior for the sliding window (paper: D_prior, after VINS-Mono).
//
// Usage per window slide (window arrays pose[i][7], sb[i][9]; drop the oldest, i = 0):
//   auto info = std::make_shared<MarginalizationInfo>();
//   if (prior)   // the previous prior, on the blocks it was added to the problem with
//     info->addResidualBlock({new MarginalizationFactor(prior), nullptr, prior_blocks,
//                             /* indices of pose[0], sb[0] within prior_blocks */ {...}});
//   info->addResidualBlock({new PointToPlaneFactor(...), new ceres::HuberLoss(s), {pose[0]}, {0}});
//   info->addResidualBlock({imu_factor_0_1, nullptr, {pose[0], sb[0], pose[1], sb[1]}, {0, 1}});
//   info->preMarginalize();   // evaluates at the current values
//   info->marginalize();
//   // slide: copy pose[i+1] -> pose[i], sb[i+1] -> sb[i]
//   prior_blocks = info->keptBlockAddresses(addressShift({pose[1], sb[1], ...}, {pose[0], sb[0], ...}));
//   prior = info;   // next problem: AddResidualBlock(new MarginalizationFactor(prior), nullptr, prior_blocks)
//
// Linearisation: every residual block is evaluated once (robust losses applied with the Triggs
// correction, as Ceres does), H = sum J^T J and g = sum J^T r are assembled in the tangent space,
// the dropped blocks are Schur-complemented out (H_mm inverted through its eigen decomposition,
// eigenvalues < eigenvalue_floor treated as zero), and the result is stored as a linear residual
//   r(x) = r0 + J (x (-) x0),   J^T J = H*,  J^T r0 = g*   (J = sqrt(S) V^T, r0 = sqrt(S)^-1 V^T g*)
// over the kept blocks, with x0 their values at preMarginalize() time.
//
// Block sizes: a block of global size 7 is a pose (PoseManifold, tangent 6, cost Jacobians carry
// d r / d tangent in their first 6 columns — the estimator convention); any other size is
// Euclidean (e.g. speed-bias 9) with tangent size == global size.

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <memory>
#include <unordered_map>
#include <vector>

namespace mmlio::estimator {

/// Tangent size of a parameter block of the given global size (7 -> 6, otherwise unchanged).
int tangentSize(int global_size);

/// The `shift` map for keptBlockAddresses() after a window slide: from[i] -> to[i]
/// (e.g. from = {&pose[1][0], ..., &pose[N][0]}, to = {&pose[0][0], ..., &pose[N-1][0]}).
std::unordered_map<long, double*> addressShift(const std::vector<double*>& from, const std::vector<double*>& to);

struct ResidualBlockInfo {
  ceres::CostFunction* cost = nullptr;  // owned by MarginalizationInfo once added
  ceres::LossFunction* loss = nullptr;  // may be nullptr; owned once added (shared pointers ok)
  std::vector<double*> blocks;          // parameter blocks, in the cost's order
  std::vector<int> drop_indices;        // indices into blocks of the blocks to marginalise
};

class MarginalizationInfo {
 public:
  /// eigenvalue_floor: eigenvalues of H_mm and of the prior information below it are zeroed.
  explicit MarginalizationInfo(double eigenvalue_floor = 1e-8);
  ~MarginalizationInfo();
  MarginalizationInfo(const MarginalizationInfo&) = delete;
  MarginalizationInfo& operator=(const MarginalizationInfo&) = delete;

  /// Takes ownership of info.cost and info.loss (each distinct pointer is deleted once).
  /// Add only residual blocks that touch at least one dropped block (a block dropped in one
  /// residual is dropped everywhere); the others stay in the problem and must not be counted twice.
  void addResidualBlock(ResidualBlockInfo info);
  /// Evaluates all residual blocks and their Jacobians and copies every block's current values.
  void preMarginalize();
  /// Builds H, g, Schur-complements the dropped blocks out and stores (J, r0). Requires preMarginalize().
  void marginalize();

  /// Addresses of the kept blocks, in the prior's parameter order, mapped through `shift`
  /// (old address -> new address, keyed by reinterpret_cast<long>(old)); an address missing
  /// from `shift` is returned unchanged (a block whose storage did not move).
  std::vector<double*> keptBlockAddresses(const std::unordered_map<long, double*>& shift) const;
  /// True after marginalize() produced a finite prior over at least one kept block.
  bool valid() const;

  // The stored prior (in kept-block order).
  const std::vector<int>& keptBlockSizes() const { return kept_sizes_; }  // global sizes
  const std::vector<int>& keptBlockTangentOffsets() const { return kept_offsets_; }
  const std::vector<Eigen::VectorXd>& keptBlockValues() const { return kept_values_; }  // x0
  int keptTangentSize() const { return kept_dim_; }
  int droppedTangentSize() const { return dropped_dim_; }
  const Eigen::MatrixXd& linearizedJacobian() const { return J_; }   // kept_dim x kept_dim
  const Eigen::VectorXd& linearizedResidual() const { return r0_; }  // kept_dim
  /// Residual blocks added and not yet marginalized (marginalize() releases them).
  int numResidualBlocks() const { return static_cast<int>(factors_.size()); }

 private:
  void releaseFactors();  // deletes each distinct cost and loss once

  struct Factor {
    ResidualBlockInfo info;
    Eigen::VectorXd residual;                // after loss correction
    std::vector<Eigen::MatrixXd> jacobians;  // tangent columns, after loss correction
  };
  std::vector<Factor> factors_;
  double eigenvalue_floor_;
  bool pre_marginalized_ = false;
  bool valid_ = false;

  std::unordered_map<const double*, int> block_size_;          // global size per block
  std::unordered_map<const double*, Eigen::VectorXd> values_;  // copied at preMarginalize()

  std::vector<double*> kept_blocks_;
  std::vector<int> kept_sizes_, kept_offsets_;
  std::vector<Eigen::VectorXd> kept_values_;
  int kept_dim_ = 0, dropped_dim_ = 0;
  Eigen::MatrixXd J_;
  Eigen::VectorXd r0_;
};

/// The prior as a Ceres cost: r = r0 + J * (x (-) x0), (-) = PoseManifold::Minus for 7-blocks and
/// plain subtraction otherwise. Jacobians follow the estimator convention (7 columns for poses,
/// the last zero) and include the exact d Log / d dtheta term (Jr^-1), exact at x0.
class MarginalizationFactor : public ceres::CostFunction {
 public:
  explicit MarginalizationFactor(std::shared_ptr<const MarginalizationInfo> info);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  const MarginalizationInfo& info() const { return *info_; }

 private:
  std::shared_ptr<const MarginalizationInfo> info_;
};

}  // namespace mmlio::estimator
