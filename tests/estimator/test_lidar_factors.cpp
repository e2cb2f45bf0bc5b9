// PoseManifold and LiDAR point-to-plane / point-to-edge factors: known answers, analytic vs
// numeric tangent-space Jacobians, and a small registration with a known 6-DoF perturbation.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <memory>
#include <random>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/lidar_factors.hpp"
#include "mmlio/estimator/map_matching.hpp"
#include "mmlio/estimator/pose_manifold.hpp"
#include "synthetic_matches.hpp"

namespace mmlio::estimator {
namespace {

using Pose = Eigen::Matrix<double, 7, 1>;

Pose makePose(const Eigen::Vector3d& p, const Eigen::Vector3d& rotvec) {
  Pose x;
  x.head<3>() = p;
  x.tail<4>() = so3::exp(rotvec).coeffs();
  return x;
}

/// Central differences of cost w.r.t. the 6 tangent directions of PoseManifold at x.
Eigen::MatrixXd numericTangentJacobian(const ceres::CostFunction& cost, const Pose& x) {
  const int m = cost.num_residuals();
  PoseManifold manifold;
  Eigen::MatrixXd J(m, 6);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
    Pose xp, xm;
    d[k] = h;
    manifold.Plus(x.data(), d.data(), xp.data());
    d[k] = -h;
    manifold.Plus(x.data(), d.data(), xm.data());
    Eigen::VectorXd rp(m), rm(m);
    const double* pp[] = {xp.data()};
    const double* pm[] = {xm.data()};
    cost.Evaluate(pp, rp.data(), nullptr);
    cost.Evaluate(pm, rm.data(), nullptr);
    J.col(k) = (rp - rm) / (2 * h);
  }
  return J;
}

Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> analyticJacobian(const ceres::CostFunction& cost,
                                                                           const Pose& x) {
  const int m = cost.num_residuals();
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J(m, 7);
  Eigen::VectorXd r(m);
  const double* params[] = {x.data()};
  double* jac[] = {J.data()};
  EXPECT_TRUE(cost.Evaluate(params, r.data(), jac));
  return J;
}

TEST(PoseManifold, MinusOfPlusReturnsTheTangentStep) {
  PoseManifold m;
  const Pose x = makePose({1, -2, 3}, {0.3, -1.2, 2.0});
  Eigen::Matrix<double, 6, 1> d;
  d << 0.1, -0.2, 0.3, 0.4, -0.5, 0.6;
  Pose y;
  ASSERT_TRUE(m.Plus(x.data(), d.data(), y.data()));
  EXPECT_NEAR(y.tail<4>().norm(), 1.0, 1e-12);
  Eigen::Matrix<double, 6, 1> back;
  ASSERT_TRUE(m.Minus(y.data(), x.data(), back.data()));
  EXPECT_LT((back - d).norm(), 1e-12);
}

TEST(PoseManifold, PlusPerturbsTheRotationOnTheRight) {
  PoseManifold m;
  const Pose x = makePose({0, 0, 0}, {0, 0, M_PI / 2});  // yaw 90 deg
  Eigen::Matrix<double, 6, 1> d;
  d << 1, 0, 0, 0.1, 0, 0;  // body-x rotation of 0.1 rad
  Pose y;
  m.Plus(x.data(), d.data(), y.data());
  const Eigen::Quaterniond expected = so3::exp({0, 0, M_PI / 2}) * so3::exp({0.1, 0, 0});
  EXPECT_NEAR(std::abs(Eigen::Map<const Eigen::Quaterniond>(y.data() + 3).dot(expected)), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(y[0], 1.0);  // translation is added in the world frame, not rotated
}

TEST(PoseManifold, PlusJacobianIsIdentitySelectorAndMinusJacobianItsLeftInverse) {
  PoseManifold m;
  const Pose x = makePose({1, 2, 3}, {0.1, 0.2, 0.3});
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> Jp;
  Eigen::Matrix<double, 6, 7, Eigen::RowMajor> Jm;
  m.PlusJacobian(x.data(), Jp.data());
  m.MinusJacobian(x.data(), Jm.data());
  Eigen::Matrix<double, 7, 6> expected = Eigen::Matrix<double, 7, 6>::Zero();
  expected.topRows<6>().setIdentity();
  EXPECT_EQ(Jp, expected);
  EXPECT_TRUE((Jm * Jp).isIdentity(0.0));
}

TEST(PointToPlaneFactor, ResidualIsWeightedSignedDistance) {
  // Plane z = 2 (n = e_z, d = -2); body point (0,0,1) under a pose at z = 3 lies at z = 4.
  PointToPlaneFactor f({0, 0, 1}, {0, 0, 1}, -2.0, 10.0);
  const Pose x = makePose({5, -1, 3}, {0, 0, 0.7});
  double r;
  const double* params[] = {x.data()};
  f.Evaluate(params, &r, nullptr);
  EXPECT_NEAR(r, 10.0 * 2.0, 1e-12);
}

TEST(PointToPlaneFactor, AnalyticJacobianMatchesNumericInTangentSpace) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  PointToPlaneFactor f({1.5, -2.0, 0.7}, n, 0.4, 3.0);
  const Pose x = makePose({0.2, 1.0, -0.5}, {0.4, -0.9, 1.7});
  const auto Ja = analyticJacobian(f, x);
  const Eigen::MatrixXd Jn = numericTangentJacobian(f, x);
  EXPECT_LT((Ja.leftCols<6>() - Jn).norm(), 1e-6) << Ja << "\n" << Jn;
  EXPECT_EQ(Ja.col(6).norm(), 0.0);
}

TEST(PointToEdgeFactor, ResidualIsPerpendicularOffsetToTheLine) {
  // Line through (0,0,1) along x; point maps to (4, 3, 5): offset (0, 3, 4), distance 5.
  PointToEdgeFactor f({4, 3, 5}, {0, 0, 1}, {2, 0, 0}, 2.0);
  const Pose x = makePose({0, 0, 0}, {0, 0, 0});
  Eigen::Vector3d r;
  const double* params[] = {x.data()};
  f.Evaluate(params, r.data(), nullptr);
  EXPECT_LT((r - Eigen::Vector3d(0, 6, 8)).norm(), 1e-12);
  EXPECT_NEAR(r.norm(), 2.0 * 5.0, 1e-12);
}

TEST(PointToEdgeFactor, AnalyticJacobianMatchesNumericInTangentSpace) {
  PointToEdgeFactor f({-0.4, 2.2, 1.1}, {1, 2, 3}, {0.2, 0.9, -0.4}, 1.7);
  const Pose x = makePose({-1.0, 0.3, 2.0}, {-2.1, 0.5, 0.3});
  const auto Ja = analyticJacobian(f, x);
  const Eigen::MatrixXd Jn = numericTangentJacobian(f, x);
  EXPECT_LT((Ja.leftCols<6>() - Jn).norm(), 1e-6) << Ja << "\n" << Jn;
  EXPECT_EQ(Ja.col(6).norm(), 0.0);
}

/// Planes and edges 0-25 cm from where pose x puts their points: at weight 4 about half of
/// them lie beyond a Huber scale of 0.5 (whitened).
std::vector<MapMatch> mixedMatches(const Pose& x) { return testing::randomMatches(blockToPose(x.data()), {}); }

/// One match's residual, whitened and made Huber-robust as r sqrt(rho(|r|^2)) / |r| (huber <= 0: as is).
Eigen::VectorXd robustResidual(const MapMatch& m, double weight, double huber, const Pose& x) {
  const std::unique_ptr<ceres::CostFunction> one(mapMatchCost(m, weight));
  Eigen::VectorXd r(one->num_residuals());
  const double* params[] = {x.data()};
  one->Evaluate(params, r.data(), nullptr);
  if (huber <= 0.0) return r;
  const ceres::HuberLoss loss(huber);
  double rho[3];
  loss.Evaluate(r.squaredNorm(), rho);
  return r.norm() > 0.0 ? Eigen::VectorXd(r * std::sqrt(rho[0]) / r.norm()) : r;
}

/// Cost, gradient and Gauss-Newton matrix of the matches stacked one robust residual each, the
/// Jacobians by central differences in the tangent space.
struct Stacked {
  double cost = 0.0;
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> gauss_newton = Eigen::Matrix<double, 6, 6>::Zero();
};
Stacked stackedMatches(const std::vector<MapMatch>& matches, double weight, double huber, const Pose& x) {
  PoseManifold manifold;
  Stacked s;
  for (const MapMatch& m : matches) {
    const Eigen::VectorXd r = robustResidual(m, weight, huber, x);
    Eigen::MatrixXd J(r.size(), 6);
    for (int k = 0; k < 6; ++k) {
      Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
      Pose xp, xm;
      d[k] = 1e-6;
      manifold.Plus(x.data(), d.data(), xp.data());
      d[k] = -1e-6;
      manifold.Plus(x.data(), d.data(), xm.data());
      J.col(k) = (robustResidual(m, weight, huber, xp) - robustResidual(m, weight, huber, xm)) / 2e-6;
    }
    s.cost += r.squaredNorm();
    s.gradient += J.transpose() * r;
    s.gauss_newton += J.transpose() * J;
  }
  return s;
}

struct Evaluation {
  Eigen::VectorXd r;
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J;
};
Evaluation evaluateWithJacobian(const ceres::CostFunction& cost, const Pose& x) {
  Evaluation e{Eigen::VectorXd(cost.num_residuals()), {cost.num_residuals(), 7}};
  const double* params[] = {x.data()};
  double* jac[] = {e.J.data()};
  EXPECT_TRUE(cost.Evaluate(params, e.r.data(), jac));
  return e;
}

double costOnly(const ceres::CostFunction& cost, const Pose& x) {
  Eigen::VectorXd r(cost.num_residuals());
  const double* params[] = {x.data()};
  EXPECT_TRUE(cost.Evaluate(params, r.data(), nullptr));
  return r.squaredNorm();
}

// Levenberg-Marquardt sees only cost, gradient J^T r and J^T J: the reduced block must give the
// stacked matches' three, with and without the Jacobian asked for.
void expectSameAsStacked(const std::vector<MapMatch>& matches, double weight, double huber, const Pose& x) {
  const MapMatchesFactor batched(matches, weight, huber);
  const Stacked s = stackedMatches(matches, weight, huber, x);
  const Evaluation e = evaluateWithJacobian(batched, x);
  EXPECT_EQ(e.r.size(), 7);
  EXPECT_TRUE(e.r.allFinite() && e.J.allFinite());
  EXPECT_EQ(e.J.col(6).norm(), 0.0);
  EXPECT_NEAR(e.r.squaredNorm(), s.cost, 1e-9 * s.cost);
  EXPECT_NEAR(costOnly(batched, x), s.cost, 1e-9 * s.cost);
  EXPECT_LT((e.J.leftCols<6>().transpose() * e.r - s.gradient).norm(), 1e-6 * s.gradient.norm()) << s.gradient;
  EXPECT_LT((e.J.leftCols<6>().transpose() * e.J.leftCols<6>() - s.gauss_newton).norm(), 1e-6 * s.gauss_newton.norm());
}

TEST(MapMatchesFactor, CostGradientAndGaussNewtonMatrixAreThoseOfOneHuberRobustResidualPerMatch) {
  const Pose x = makePose({0.1, -0.2, 0.05}, {0.02, -0.01, 0.03});
  const std::vector<MapMatch> matches = mixedMatches(x);
  const double weight = 4.0, huber = 0.5;
  int beyond = 0;
  for (const MapMatch& m : matches) {
    const std::unique_ptr<ceres::CostFunction> one(mapMatchCost(m, weight));
    Eigen::VectorXd r(one->num_residuals());
    const double* params[] = {x.data()};
    one->Evaluate(params, r.data(), nullptr);
    beyond += r.norm() > huber;
  }
  ASSERT_GT(beyond, 5);  // the loss is exercised
  ASSERT_LT(beyond, 25);
  expectSameAsStacked(matches, weight, huber, x);
  expectSameAsStacked(matches, weight, 0.0, x);  // no loss
}

TEST(MapMatchesFactor, MatchesOnOneFloorConstrainThreeDirectionsAndLeaveTheOthersAtZero) {
  // Points on the plane z = 0 only fix z, roll and pitch: J^T J has rank 3.
  const Pose x = makePose({0.3, 0.1, 0.04}, {0.01, -0.02, 0.5});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-3.0, 3.0);
  std::vector<MapMatch> matches;
  for (int i = 0; i < 40; ++i) {
    MapMatch m;
    m.p_body = {U(rng), U(rng), -0.04};
    m.a = {0, 0, 1};
    m.b = {0.0, 0, 0};
    matches.push_back(m);
  }
  expectSameAsStacked(matches, 4.0, 0.5, x);
  const Evaluation e = evaluateWithJacobian(MapMatchesFactor(matches, 4.0, 0.5), x);
  const Eigen::Matrix<double, 6, 6> JtJ = e.J.leftCols<6>().transpose() * e.J.leftCols<6>();
  Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(JtJ);
  lu.setThreshold(1e-9);
  EXPECT_EQ(lu.rank(), 3);
}

TEST(MapMatchesFactor, NoMatchesCostNothing) {
  const Pose x = makePose({0, 0, 0}, {0, 0, 0});
  const Evaluation e = evaluateWithJacobian(MapMatchesFactor({}, 4.0, 0.5), x);
  EXPECT_EQ(e.r.norm(), 0.0);
  EXPECT_EQ(e.J.norm(), 0.0);
}

TEST(LidarFactors, RegistrationRecoversAKnownSixDofPerturbation) {
  // World: planes x = 3, y = -2, z = -1 (a room corner) and two edges (vertical line at
  // (3,-2) where the two walls meet, horizontal line along y at x=3, z=1.5).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-4.0, 4.0);
  struct PlaneObs {
    Eigen::Vector3d p_world, n;
    double d;
  };
  struct EdgeObs {
    Eigen::Vector3d p_world, a, u;
  };
  std::vector<PlaneObs> planes;
  std::vector<EdgeObs> edges;
  for (int i = 0; i < 60; ++i) {
    planes.push_back({{3.0, U(rng), U(rng)}, {1, 0, 0}, -3.0});
    planes.push_back({{U(rng), -2.0, U(rng)}, {0, 1, 0}, 2.0});
    planes.push_back({{U(rng), U(rng), -1.0}, {0, 0, 1}, 1.0});
  }
  for (int i = 0; i < 20; ++i) {
    edges.push_back({{3.0, -2.0, U(rng)}, {3.0, -2.0, 0.0}, {0, 0, 1}});
    edges.push_back({{3.0, U(rng), 1.5}, {3.0, 0.0, 1.5}, {0, 1, 0}});
  }
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.linear() = so3::exp({0.1, -0.2, 0.8}).toRotationMatrix();
  T_true.translation() = Eigen::Vector3d(0.5, 0.3, 0.2);
  const Eigen::Isometry3d T_body_world = T_true.inverse();

  // Initial guess: perturbed by 0.3 m and ~8 degrees.
  Eigen::Isometry3d T_init = T_true;
  T_init.linear() = T_true.linear() * so3::exp({0.05, 0.08, -0.1}).toRotationMatrix();
  T_init.translation() += Eigen::Vector3d(0.2, -0.15, 0.15);
  double pose[7];
  poseToBlock(T_init, pose);

  ceres::Problem problem;
  problem.AddParameterBlock(pose, 7, new PoseManifold);
  for (const auto& o : planes)
    problem.AddResidualBlock(new PointToPlaneFactor(T_body_world * o.p_world, o.n, o.d), nullptr, pose);
  for (const auto& o : edges)
    problem.AddResidualBlock(new PointToEdgeFactor(T_body_world * o.p_world, o.a, o.u), nullptr, pose);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  const Eigen::Isometry3d T_est = blockToPose(pose);
  const double err_m = (T_est.translation() - T_true.translation()).norm();
  const double err_deg =
      so3::log(Eigen::Quaterniond(T_true.rotation().transpose() * T_est.rotation())).norm() * 180.0 / M_PI;
  EXPECT_LT(err_m, 1e-3) << summary.BriefReport();
  EXPECT_LT(err_deg, 0.01) << summary.BriefReport();
}

}  // namespace
}  // namespace mmlio::estimator
