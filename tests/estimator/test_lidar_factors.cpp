// PoseManifold and LiDAR point-to-plane / point-to-edge factors: known answers, analytic vs
// numeric tangent-space Jacobians, and a small registration with a known 6-DoF perturbation.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/lidar_factors.hpp"
#include "mmlio/estimator/map_matching.hpp"
#include "mmlio/estimator/pose_manifold.hpp"

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
std::vector<MapMatch> mixedMatches(const Pose& x) {
  const Eigen::Isometry3d T = blockToPose(x.data());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-3.0, 3.0), offset(-0.25, 0.25);
  std::vector<MapMatch> matches;
  for (int i = 0; i < 30; ++i) {
    MapMatch m;
    m.kind = i % 3 == 2 ? MapMatch::Kind::kEdge : MapMatch::Kind::kPlane;
    m.p_body = {U(rng), U(rng), U(rng)};
    const Eigen::Vector3d q = T * m.p_body;
    if (m.kind == MapMatch::Kind::kPlane) {
      m.a = Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized();
      m.b = Eigen::Vector3d(-m.a.dot(q) + offset(rng), 0, 0);
    } else {
      m.a = q + Eigen::Vector3d(offset(rng), offset(rng), offset(rng));
      m.b = Eigen::Vector3d(U(rng), U(rng), 1.0);
    }
    matches.push_back(m);
  }
  return matches;
}

TEST(MapMatchesFactor, CostAndGradientAreThoseOfOneHuberRobustResidualPerMatch) {
  const Pose x = makePose({0.1, -0.2, 0.05}, {0.02, -0.01, 0.03});
  const std::vector<MapMatch> matches = mixedMatches(x);
  const double weight = 4.0, huber = 0.5;
  const MapMatchesFactor batched(matches, weight, huber);
  const auto Jb = analyticJacobian(batched, x);
  Eigen::VectorXd rb(batched.num_residuals());
  const double* params[] = {x.data()};
  batched.Evaluate(params, rb.data(), nullptr);

  const ceres::HuberLoss loss(huber);
  double cost = 0.0;
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero();
  int beyond = 0;
  for (const MapMatch& m : matches) {
    const std::unique_ptr<ceres::CostFunction> one(mapMatchCost(m, weight));
    const auto J = analyticJacobian(*one, x);
    Eigen::VectorXd r(one->num_residuals());
    one->Evaluate(params, r.data(), nullptr);
    double rho[3];
    loss.Evaluate(r.squaredNorm(), rho);
    cost += rho[0];
    gradient += rho[1] * J.leftCols<6>().transpose() * r;
    beyond += r.norm() > huber;
  }
  ASSERT_GT(beyond, 5);  // the loss is exercised
  ASSERT_LT(beyond, 25);
  EXPECT_NEAR(rb.squaredNorm(), cost, 1e-9 * cost);
  EXPECT_LT((Jb.leftCols<6>().transpose() * rb - gradient).norm(), 1e-9 * gradient.norm());
}

TEST(MapMatchesFactor, AnalyticJacobianMatchesNumericInTangentSpace) {
  const Pose x = makePose({0.1, -0.2, 0.05}, {0.02, -0.01, 0.03});
  const MapMatchesFactor batched(mixedMatches(x), 4.0, 0.5);
  const auto Ja = analyticJacobian(batched, x);
  const Eigen::MatrixXd Jn = numericTangentJacobian(batched, x);
  EXPECT_LT((Ja.leftCols<6>() - Jn).norm(), 1e-5 * Jn.norm());
  EXPECT_EQ(Ja.col(6).norm(), 0.0);
}

TEST(LidarFactors, RegistrationRecoversAKnownSixDofPerturbation) {
  // World: planes x = 3, y = -2, z = -1 (a room corner) and two edges (vertical line at
  // (3,-2) where the two walls meet, horizontal line along y at x=3, z=1.5).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-4.0, 4.0);
  struct PlaneObs { Eigen::Vector3d p_world, n; double d; };
  struct EdgeObs { Eigen::Vector3d p_world, a, u; };
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
