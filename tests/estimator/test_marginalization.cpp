// Schur-complement marginalisation prior: on linear-Gaussian problems the prior must reproduce
// the full solution exactly (wherever it was linearised and after the kept blocks' storage
// moves); on a nonlinear pose chain it must reproduce the full optimum when linearised there.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <random>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/lidar_factors.hpp"
#include "mmlio/estimator/marginalization.hpp"
#include "mmlio/estimator/pose_manifold.hpp"

namespace mmlio::estimator {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// r = sum_k A_k x_k - b over Euclidean blocks.
class LinearFactor : public ceres::CostFunction {
 public:
  LinearFactor(std::vector<Eigen::MatrixXd> A, Eigen::VectorXd b) : A_(std::move(A)), b_(std::move(b)) {
    set_num_residuals(static_cast<int>(b_.size()));
    for (const auto& a : A_) mutable_parameter_block_sizes()->push_back(static_cast<int>(a.cols()));
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Eigen::Map<Eigen::VectorXd> r(residuals, b_.size());
    r = -b_;
    for (std::size_t k = 0; k < A_.size(); ++k) {
      r += A_[k] * Eigen::Map<const Eigen::VectorXd>(x[k], A_[k].cols());
      if (jacobians && jacobians[k]) Eigen::Map<RowMatrix>(jacobians[k], A_[k].rows(), A_[k].cols()) = A_[k];
    }
    return true;
  }

 private:
  std::vector<Eigen::MatrixXd> A_;
  Eigen::VectorXd b_;
};

/// A random linear-Gaussian problem over blocks of the given sizes: factor f touches blocks
/// `touches[f]` with random 6-row Jacobians (prior factors: as many rows as the block).
struct LinearProblem {
  std::vector<int> sizes;
  struct F {
    std::vector<int> blocks;
    std::vector<Eigen::MatrixXd> A;
    Eigen::VectorXd b;
  };
  std::vector<F> factors;

  LinearProblem(std::vector<int> block_sizes, const std::vector<std::vector<int>>& touches, unsigned seed)
      : sizes(std::move(block_sizes)) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> N(0.0, 1.0);
    for (const auto& t : touches) {
      F f;
      f.blocks = t;
      const int rows = t.size() == 1 ? sizes[t[0]] : 6;
      for (int k : t) f.A.push_back(Eigen::MatrixXd::NullaryExpr(rows, sizes[k], [&] { return N(rng); }));
      f.b = Eigen::VectorXd::NullaryExpr(rows, [&] { return N(rng); });
      factors.push_back(std::move(f));
    }
  }
  ceres::CostFunction* cost(int f) const { return new LinearFactor(factors[f].A, factors[f].b); }
  std::vector<double*> addresses(int f, const std::vector<double*>& x) const {
    std::vector<double*> out;
    for (int k : factors[f].blocks) out.push_back(x[k]);
    return out;
  }
};

void solve(ceres::Problem& problem) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-16;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  ASSERT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
}

std::vector<std::vector<double>> randomValues(const std::vector<int>& sizes, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0.0, scale);
  std::vector<std::vector<double>> v;
  for (int s : sizes) {
    v.emplace_back(s);
    for (double& e : v.back()) e = N(rng);
  }
  return v;
}

std::vector<double*> pointers(std::vector<std::vector<double>>& v) {
  std::vector<double*> p;
  for (auto& b : v) p.push_back(b.data());
  return p;
}

// Blocks: x0 (3), x1 (9, speed-bias sized), x2 (3), x3 (3).
const std::vector<int> kSizes = {3, 9, 3, 3};
const std::vector<std::vector<int>> kTouches = {{0}, {0, 1}, {0, 2}, {1, 2}, {1, 3}, {2, 3}, {3}, {1}};

std::vector<std::vector<double>> fullSolution(const LinearProblem& lp) {
  auto x = randomValues(lp.sizes, 99, 1.0);
  auto px = pointers(x);
  ceres::Problem problem;
  for (std::size_t f = 0; f < lp.factors.size(); ++f)
    problem.AddResidualBlock(lp.cost(static_cast<int>(f)), nullptr, lp.addresses(static_cast<int>(f), px));
  solve(problem);
  return x;
}

TEST(Marginalization, LinearPriorOfX0GivesTheFullProblemsEstimateOfTheRest) {
  const LinearProblem lp(kSizes, kTouches, 1);
  const auto x_full = fullSolution(lp);

  // Linearise at an arbitrary point far from the optimum: a linear problem's prior is exact.
  auto x = randomValues(kSizes, 5, 3.0);
  auto px = pointers(x);
  auto info = std::make_shared<MarginalizationInfo>();
  for (int f : {0, 1, 2}) info->addResidualBlock({lp.cost(f), nullptr, lp.addresses(f, px), {0}});
  info->preMarginalize();
  info->marginalize();
  ASSERT_TRUE(info->valid());
  EXPECT_EQ(info->droppedTangentSize(), 3);
  EXPECT_EQ(info->keptTangentSize(), 12);  // x1 (9) + x2 (3)
  EXPECT_EQ(info->keptBlockAddresses({}), (std::vector<double*>{px[1], px[2]}));

  ceres::Problem problem;
  problem.AddResidualBlock(new MarginalizationFactor(info), nullptr, info->keptBlockAddresses({}));
  for (int f : {3, 4, 5, 6, 7}) problem.AddResidualBlock(lp.cost(f), nullptr, lp.addresses(f, px));
  solve(problem);
  for (int k : {1, 2, 3})
    for (int i = 0; i < kSizes[k]; ++i) EXPECT_NEAR(x[k][i], x_full[k][i], 1e-6) << "block " << k;
}

TEST(Marginalization, DroppedBlockWithAnUnobservableDirectionStillGivesTheFullEstimate) {
  // No factor sees x0 along v (a gauge direction): H_mm is singular and its pseudo-inverse
  // (eigenvalues below the floor zeroed) must still give the exact marginal.
  LinearProblem lp(kSizes, kTouches, 9);
  const Eigen::Vector3d v = Eigen::Vector3d(1, 2, -1).normalized();
  for (auto& f : lp.factors)
    for (std::size_t k = 0; k < f.blocks.size(); ++k)
      if (f.blocks[k] == 0) f.A[k] = f.A[k] * (Eigen::Matrix3d::Identity() - v * v.transpose());
  const auto x_full = fullSolution(lp);

  auto x = randomValues(kSizes, 13, 1.0);
  auto px = pointers(x);
  auto info = std::make_shared<MarginalizationInfo>();
  for (int f : {0, 1, 2}) info->addResidualBlock({lp.cost(f), nullptr, lp.addresses(f, px), {0}});
  info->preMarginalize();
  info->marginalize();
  ASSERT_TRUE(info->valid());
  ceres::Problem problem;
  problem.AddResidualBlock(new MarginalizationFactor(info), nullptr, info->keptBlockAddresses({}));
  for (int f : {3, 4, 5, 6, 7}) problem.AddResidualBlock(lp.cost(f), nullptr, lp.addresses(f, px));
  solve(problem);
  for (int k : {1, 2, 3})
    for (int i = 0; i < kSizes[k]; ++i) EXPECT_NEAR(x[k][i], x_full[k][i], 1e-6) << "block " << k;
}

TEST(Marginalization, TwoWindowSlidesWithMovedStorageStillGiveTheFullEstimate) {
  const LinearProblem lp(kSizes, kTouches, 2);
  const auto x_full = fullSolution(lp);

  // Window 1 holds x0..x3 in `window`; marginalise x0.
  auto window = randomValues(kSizes, 6, 2.0);
  auto pw = pointers(window);
  auto info1 = std::make_shared<MarginalizationInfo>();
  for (int f : {0, 1, 2}) info1->addResidualBlock({lp.cost(f), nullptr, lp.addresses(f, pw), {0}});
  info1->preMarginalize();
  info1->marginalize();
  ASSERT_TRUE(info1->valid());

  // Slide: the states move to new storage (as a fixed-size window array shifts by one) and
  // take different values (the kept blocks moved since linearisation).
  auto moved = randomValues(kSizes, 7, 2.0);
  auto pm = pointers(moved);
  const auto shift = addressShift({pw[1], pw[2], pw[3]}, {pm[1], pm[2], pm[3]});
  const auto prior1_blocks = info1->keptBlockAddresses(shift);
  ASSERT_EQ(prior1_blocks, (std::vector<double*>{pm[1], pm[2]}));

  // Window 2 marginalises x1: the old prior (on x1, x2) and the factors touching x1.
  auto info2 = std::make_shared<MarginalizationInfo>();
  info2->addResidualBlock({new MarginalizationFactor(info1), nullptr, prior1_blocks, {0}});
  info2->addResidualBlock({lp.cost(3), nullptr, lp.addresses(3, pm), {0}});
  info2->addResidualBlock({lp.cost(4), nullptr, lp.addresses(4, pm), {0}});
  info2->addResidualBlock({lp.cost(7), nullptr, lp.addresses(7, pm), {0}});
  info2->preMarginalize();
  info2->marginalize();
  ASSERT_TRUE(info2->valid());
  EXPECT_EQ(info2->keptTangentSize(), 6);
  // A prior is its (J, r0): marginalising releases the factors, and with them the prior before,
  // so the priors of a long run do not chain up in memory.
  EXPECT_EQ(info2->numResidualBlocks(), 0);
  const std::weak_ptr<const MarginalizationInfo> first = info1;
  info1.reset();
  EXPECT_TRUE(first.expired());

  ceres::Problem problem;
  problem.AddResidualBlock(new MarginalizationFactor(info2), nullptr, info2->keptBlockAddresses({}));
  for (int f : {5, 6}) problem.AddResidualBlock(lp.cost(f), nullptr, lp.addresses(f, pm));
  solve(problem);
  for (int k : {2, 3})
    for (int i = 0; i < kSizes[k]; ++i) EXPECT_NEAR(moved[k][i], x_full[k][i], 1e-6) << "block " << k;
}

TEST(Marginalization, PriorCostIsTheExactMarginalCostUpToAConstant) {
  // For a linear problem min_{x0} sum_{f touching x0} |r_f|^2 is a quadratic in (x1, x2); the
  // prior must equal it up to a constant at any (x1, x2), including far from x0's linearisation.
  const LinearProblem lp(kSizes, kTouches, 3);
  auto x = randomValues(kSizes, 8, 1.0);
  auto px = pointers(x);
  auto info = std::make_shared<MarginalizationInfo>();
  for (int f : {0, 1, 2}) info->addResidualBlock({lp.cost(f), nullptr, lp.addresses(f, px), {0}});
  info->preMarginalize();
  info->marginalize();
  MarginalizationFactor prior(info);

  auto marginalCost = [&](std::vector<std::vector<double>> v) {
    auto pv = pointers(v);
    ceres::Problem problem;
    for (int f : {0, 1, 2}) problem.AddResidualBlock(lp.cost(f), nullptr, lp.addresses(f, pv));
    problem.SetParameterBlockConstant(pv[1]);
    problem.SetParameterBlockConstant(pv[2]);
    solve(problem);
    double cost = 0;
    problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
    return cost;
  };
  auto priorCost = [&](std::vector<std::vector<double>> v) {
    Eigen::VectorXd r(prior.num_residuals());
    const double* params[] = {v[1].data(), v[2].data()};
    prior.Evaluate(params, r.data(), nullptr);
    return 0.5 * r.squaredNorm();
  };
  const auto a = randomValues(kSizes, 10, 5.0), b = randomValues(kSizes, 11, 5.0);
  EXPECT_NEAR(priorCost(a) - priorCost(b), marginalCost(a) - marginalCost(b), 1e-6 * (1 + marginalCost(a)));
}

// ---- nonlinear: a chain of three poses ----

using Pose = Eigen::Matrix<double, 7, 1>;

Pose makePose(const Eigen::Vector3d& p, const Eigen::Vector3d& rotvec) {
  Pose x;
  x.head<3>() = p;
  x.tail<4>() = so3::exp(rotvec).coeffs();
  return x;
}

/// r = weight * [R0^T (p1 - p0) - dp_m;  Log(dq_m^-1 q0^-1 q1)], estimator Jacobian convention.
class RelativePoseFactor : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  RelativePoseFactor(const Eigen::Vector3d& dp, const Eigen::Quaterniond& dq, double weight)
      : dp_(dp), dq_(dq), w_(weight) {}
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> p0(x[0]), p1(x[1]);
    const Eigen::Quaterniond q0 = Eigen::Map<const Eigen::Quaterniond>(x[0] + 3).normalized();
    const Eigen::Quaterniond q1 = Eigen::Map<const Eigen::Quaterniond>(x[1] + 3).normalized();
    const Eigen::Matrix3d R0t = q0.toRotationMatrix().transpose();
    const Eigen::Vector3d dp_est = R0t * (p1 - p0);
    const Eigen::Vector3d e = so3::log(dq_.conjugate() * q0.conjugate() * q1);
    Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
    r << w_ * (dp_est - dp_), w_ * e;
    if (jacobians) {
      if (jacobians[0]) {
        Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobians[0]);
        J.setZero();
        J.block<3, 3>(0, 0) = -w_ * R0t;
        J.block<3, 3>(0, 3) = w_ * so3::hat(dp_est);
        J.block<3, 3>(3, 3) = -w_ * so3::rightJacobianInverse(-e) * dq_.toRotationMatrix().transpose();
      }
      if (jacobians[1]) {
        Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobians[1]);
        J.setZero();
        J.block<3, 3>(0, 0) = w_ * R0t;
        J.block<3, 3>(3, 3) = w_ * so3::rightJacobianInverse(e);
      }
    }
    return true;
  }

 private:
  Eigen::Vector3d dp_;
  Eigen::Quaterniond dq_;
  double w_;
};

/// Numeric tangent-space Jacobian (central differences through PoseManifold) of block k.
Eigen::MatrixXd numericJacobian(const ceres::CostFunction& cost, std::vector<Pose> x, int k) {
  const int m = cost.num_residuals();
  PoseManifold manifold;
  Eigen::MatrixXd J(m, 6);
  for (int c = 0; c < 6; ++c) {
    Eigen::VectorXd r[2];
    for (int s = 0; s < 2; ++s) {
      Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
      d[c] = s == 0 ? 1e-6 : -1e-6;
      std::vector<Pose> xs = x;
      manifold.Plus(x[k].data(), d.data(), xs[k].data());
      std::vector<const double*> params;
      for (const auto& p : xs) params.push_back(p.data());
      r[s].resize(m);
      cost.Evaluate(params.data(), r[s].data(), nullptr);
    }
    J.col(c) = (r[0] - r[1]) / 2e-6;
  }
  return J;
}

RowMatrix analyticJacobian(const ceres::CostFunction& cost, const std::vector<Pose>& x, int k) {
  const int m = cost.num_residuals();
  std::vector<RowMatrix> J(x.size(), RowMatrix(m, 7));
  std::vector<double*> jp;
  for (auto& j : J) jp.push_back(j.data());
  std::vector<const double*> params;
  for (const auto& p : x) params.push_back(p.data());
  Eigen::VectorXd r(m);
  cost.Evaluate(params.data(), r.data(), jp.data());
  return J[k];
}

TEST(Marginalization, TestRelativePoseFactorHasCorrectJacobians) {
  const RelativePoseFactor f({0.3, -0.2, 1.0}, so3::exp({0.2, 0.1, -0.3}), 2.0);
  const std::vector<Pose> x = {makePose({1, 2, 3}, {0.5, -0.4, 1.0}), makePose({0.5, 2.5, 2.0}, {0.1, 0.7, -0.6})};
  for (int k : {0, 1}) {
    const RowMatrix Ja = analyticJacobian(f, x, k);
    EXPECT_LT((Ja.leftCols(6) - numericJacobian(f, x, k)).norm(), 1e-6) << "block " << k;
  }
}

struct PoseChain {
  // Truth: three poses; x0 and x2 see a room corner (3 planes), relative measurements are noisy.
  std::vector<Pose> truth = {makePose({0, 0, 0}, {0, 0, 0}), makePose({1.0, 0.2, 0.0}, {0.02, -0.01, 0.3}),
                             makePose({2.0, 0.5, 0.1}, {0.03, 0.02, 0.6})};
  struct Plane {
    int pose;
    Eigen::Vector3d p_body, n;
    double d;
  };
  std::vector<Plane> planes;
  struct Rel {
    int a, b;
    Eigen::Vector3d dp;
    Eigen::Quaterniond dq;
  };
  std::vector<Rel> rels;

  PoseChain() {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-3.0, 3.0);
    std::normal_distribution<double> N(0.0, 0.02);
    for (int k : {0, 2}) {
      const Eigen::Isometry3d T_body_world = blockToPose(truth[k].data()).inverse();
      for (int i = 0; i < 10; ++i) {
        const Eigen::Vector3d pts[3] = {{5.0, U(rng), U(rng)}, {U(rng), -4.0, U(rng)}, {U(rng), U(rng), -1.5}};
        const Eigen::Vector3d ns[3] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
        const double ds[3] = {-5.0, 4.0, 1.5};
        for (int j = 0; j < 3; ++j)
          planes.push_back({k, T_body_world * pts[j] + Eigen::Vector3d(N(rng), N(rng), N(rng)), ns[j], ds[j]});
      }
    }
    for (auto [a, b] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{0, 2}}) {
      const Eigen::Isometry3d T_ab = blockToPose(truth[a].data()).inverse() * blockToPose(truth[b].data());
      rels.push_back({a, b, T_ab.translation() + Eigen::Vector3d(N(rng), N(rng), N(rng)),
                      Eigen::Quaterniond(T_ab.rotation()) * so3::exp({N(rng), N(rng), N(rng)})});
    }
  }
  ceres::CostFunction* plane(int i) const {
    return new PointToPlaneFactor(planes[i].p_body, planes[i].n, planes[i].d, 1.0 / 0.02);
  }
  ceres::CostFunction* rel(int i) const { return new RelativePoseFactor(rels[i].dp, rels[i].dq, 1.0 / 0.02); }
};

void addPoses(ceres::Problem& problem, std::vector<Pose>& x, std::initializer_list<int> ks) {
  for (int k : ks) problem.AddParameterBlock(x[k].data(), 7, new PoseManifold);
}

double poseError(const Pose& a, const Pose& b) {
  PoseManifold m;
  Eigen::Matrix<double, 6, 1> d;
  m.Minus(a.data(), b.data(), d.data());
  return d.norm();
}

TEST(Marginalization, PoseChainPriorLinearisedAtTheOptimumKeepsTheOptimum) {
  const PoseChain chain;
  std::vector<Pose> x_full = chain.truth;
  {
    ceres::Problem problem;
    addPoses(problem, x_full, {0, 1, 2});
    for (std::size_t i = 0; i < chain.planes.size(); ++i)
      problem.AddResidualBlock(chain.plane(i), nullptr, x_full[chain.planes[i].pose].data());
    for (std::size_t i = 0; i < chain.rels.size(); ++i)
      problem.AddResidualBlock(chain.rel(i), nullptr, x_full[chain.rels[i].a].data(), x_full[chain.rels[i].b].data());
    solve(problem);
  }

  std::vector<Pose> x = x_full;
  auto info = std::make_shared<MarginalizationInfo>();
  for (std::size_t i = 0; i < chain.planes.size(); ++i)
    if (chain.planes[i].pose == 0) info->addResidualBlock({chain.plane(i), nullptr, {x[0].data()}, {0}});
  info->addResidualBlock({chain.rel(0), nullptr, {x[0].data(), x[1].data()}, {0}});
  info->addResidualBlock({chain.rel(2), nullptr, {x[0].data(), x[2].data()}, {0}});
  info->preMarginalize();
  info->marginalize();
  ASSERT_TRUE(info->valid());
  EXPECT_EQ(info->keptTangentSize(), 12);

  // The prior factor's Jacobians are exact also away from x0 (Jr^-1 of the rotation offset).
  {
    MarginalizationFactor prior(info);
    const std::vector<Pose> away = {makePose({1.1, 0.1, 0.2}, {0.3, -0.2, 0.5}),
                                    makePose({2.2, 0.3, 0.0}, {-0.2, 0.4, 0.9})};
    for (int k : {0, 1}) {
      const RowMatrix Ja = analyticJacobian(prior, away, k);
      EXPECT_LT((Ja.leftCols(6) - numericJacobian(prior, away, k)).norm(), 1e-5 * (1 + Ja.norm()));
      EXPECT_EQ(Ja.col(6).norm(), 0.0);
    }
  }

  // Reduced problem from a perturbed start returns to the full optimum.
  x[1] = makePose(x_full[1].head<3>() + Eigen::Vector3d(0.1, -0.1, 0.05), Eigen::Vector3d(0.05, 0.0, 0.35));
  x[2] = makePose(x_full[2].head<3>() + Eigen::Vector3d(-0.1, 0.1, 0.1), Eigen::Vector3d(0.0, 0.05, 0.55));
  ceres::Problem problem;
  addPoses(problem, x, {1, 2});
  problem.AddResidualBlock(new MarginalizationFactor(info), nullptr, info->keptBlockAddresses({}));
  for (std::size_t i = 0; i < chain.planes.size(); ++i)
    if (chain.planes[i].pose == 2) problem.AddResidualBlock(chain.plane(i), nullptr, x[2].data());
  problem.AddResidualBlock(chain.rel(1), nullptr, x[1].data(), x[2].data());
  solve(problem);
  EXPECT_LT(poseError(x[1], x_full[1]), 1e-6);
  EXPECT_LT(poseError(x[2], x_full[2]), 1e-6);
}

TEST(Marginalization, PoseChainPriorLinearisedAwayFromTheOptimumIsAccurateToSecondOrder) {
  // The sliding-window case: x0 is marginalised at its current estimate (off the full optimum,
  // and so are the kept poses), then the kept poses move during the next solve. The prior is a
  // first-order model, so the reduced optimum differs from the full one by O(offset^2):
  // halving the linearisation offset must quarter the error.
  const PoseChain chain;
  std::vector<Pose> x_full = chain.truth;
  {
    ceres::Problem problem;
    addPoses(problem, x_full, {0, 1, 2});
    for (std::size_t i = 0; i < chain.planes.size(); ++i)
      problem.AddResidualBlock(chain.plane(i), nullptr, x_full[chain.planes[i].pose].data());
    for (std::size_t i = 0; i < chain.rels.size(); ++i)
      problem.AddResidualBlock(chain.rel(i), nullptr, x_full[chain.rels[i].a].data(), x_full[chain.rels[i].b].data());
    solve(problem);
  }
  const Eigen::Matrix<double, 6, 1> off[3] = {
      (Eigen::Matrix<double, 6, 1>() << 0.02, -0.01, 0.01, 0.017, -0.01, 0.012).finished(),
      (Eigen::Matrix<double, 6, 1>() << -0.015, 0.02, 0.01, -0.01, 0.017, 0.01).finished(),
      (Eigen::Matrix<double, 6, 1>() << 0.01, 0.015, -0.02, 0.01, 0.01, -0.017).finished()};

  auto reducedError = [&](double scale) {
    PoseManifold manifold;
    std::vector<Pose> x = x_full;
    for (int k : {0, 1, 2}) {
      const Eigen::Matrix<double, 6, 1> d = scale * off[k];
      manifold.Plus(x_full[k].data(), d.data(), x[k].data());
    }
    auto info = std::make_shared<MarginalizationInfo>();
    for (std::size_t i = 0; i < chain.planes.size(); ++i)
      if (chain.planes[i].pose == 0) info->addResidualBlock({chain.plane(i), nullptr, {x[0].data()}, {0}});
    info->addResidualBlock({chain.rel(0), nullptr, {x[0].data(), x[1].data()}, {0}});
    info->addResidualBlock({chain.rel(2), nullptr, {x[0].data(), x[2].data()}, {0}});
    info->preMarginalize();
    info->marginalize();
    EXPECT_TRUE(info->valid());

    ceres::Problem problem;
    addPoses(problem, x, {1, 2});
    problem.AddResidualBlock(new MarginalizationFactor(info), nullptr, info->keptBlockAddresses({}));
    for (std::size_t i = 0; i < chain.planes.size(); ++i)
      if (chain.planes[i].pose == 2) problem.AddResidualBlock(chain.plane(i), nullptr, x[2].data());
    problem.AddResidualBlock(chain.rel(1), nullptr, x[1].data(), x[2].data());
    solve(problem);
    return poseError(x[1], x_full[1]) + poseError(x[2], x_full[2]);
  };
  const double e1 = reducedError(1.0), e_half = reducedError(0.5);
  EXPECT_LT(e1, 2e-3);
  EXPECT_GT(e1, 1e-9);  // not exact: the prior is linearised
  EXPECT_LT(e_half / e1, 0.3) << e1 << " " << e_half;
  EXPECT_GT(e_half / e1, 0.2) << e1 << " " << e_half;
}

TEST(Marginalization, RobustLossInItsQuadraticRegionChangesNothing) {
  // A Huber loss whose scale exceeds every residual is the identity: same prior as without.
  const LinearProblem lp(kSizes, kTouches, 4);
  auto x = randomValues(kSizes, 12, 1.0);  // residuals are O(10), far below the Huber scale
  auto px = pointers(x);
  MarginalizationInfo plain, robust;
  for (int f : {0, 1, 2}) {
    plain.addResidualBlock({lp.cost(f), nullptr, lp.addresses(f, px), {0}});
    robust.addResidualBlock({lp.cost(f), new ceres::HuberLoss(1e3), lp.addresses(f, px), {0}});
  }
  for (auto* m : {&plain, &robust}) {
    m->preMarginalize();
    m->marginalize();
  }
  const Eigen::MatrixXd H1 = plain.linearizedJacobian().transpose() * plain.linearizedJacobian();
  const Eigen::MatrixXd H2 = robust.linearizedJacobian().transpose() * robust.linearizedJacobian();
  EXPECT_LT((H1 - H2).norm(), 1e-9 * H1.norm());

  // A Cauchy loss with a tiny scale down-weights the information of large residuals.
  MarginalizationInfo cauchy;
  for (int f : {0, 1, 2}) cauchy.addResidualBlock({lp.cost(f), new ceres::CauchyLoss(1e-2), lp.addresses(f, px), {0}});
  cauchy.preMarginalize();
  cauchy.marginalize();
  const Eigen::MatrixXd H3 = cauchy.linearizedJacobian().transpose() * cauchy.linearizedJacobian();
  EXPECT_LT(H3.trace(), 0.1 * H1.trace());
}

}  // namespace
}  // namespace mmlio::estimator
