#include <gtest/gtest.h>

#include <cstdio>

#include "calib_scene.hpp"
#include "mmlio/calib/gicp.hpp"

namespace mmlio::calib {
namespace {

using namespace testing;

TEST(Gicp, RecoversAKnownTransformBetweenTwoNoiselessScansOfARoom) {
  const Scene scene = office();
  const Eigen::Isometry3d T_world_a = pose(0, 0, 1.2, 0.0);
  const Eigen::Isometry3d T_a_b = pose(0.15, -0.1, 0.05, 4 * kDeg, 1 * kDeg, -2 * kDeg);
  // Dense target, sparser source, distinct sample positions.
  const auto target = map::voxelCentroids(xyz(solidFrame(scene, T_world_a, 1, 0.0, 40000)), 0.05);
  const auto source = map::voxelCentroids(xyz(solidFrame(scene, T_world_a * T_a_b, 2, 0.0, 20000)), 0.05);
  const GicpResult r = gicp(source, target, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.converged);
  const Eigen::Isometry3d err = T_a_b.inverse() * r.T_target_source;
  std::printf("GICP noiseless: %.5f m %.5f deg, fitness %.4f m, overlap %.3f, %d iterations\n",
              err.translation().norm(), angleDeg(err), r.fitness_m, r.overlap, r.iterations);
  EXPECT_LT(err.translation().norm(), 1e-3);
  EXPECT_LT(angleDeg(err), 0.01);
  EXPECT_GT(r.overlap, 0.8);
  EXPECT_GT(r.hessian.determinant(), 0.0);
}

TEST(Gicp, StaysWithinACentimetreWithOneCentimetreRangeNoise) {
  const Scene scene = office();
  const Eigen::Isometry3d T_world_a = pose(0, 0, 1.2, 0.3);
  const Eigen::Isometry3d T_a_b = pose(-0.2, 0.1, -0.05, -5 * kDeg, -1 * kDeg, 1 * kDeg);
  const auto target = map::voxelCentroids(xyz(solidFrame(scene, T_world_a, 3, 0.01, 40000)), 0.05);
  const auto source = map::voxelCentroids(xyz(solidFrame(scene, T_world_a * T_a_b, 4, 0.01, 20000)), 0.05);
  const GicpResult r = gicp(source, target, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.converged);
  const Eigen::Isometry3d err = T_a_b.inverse() * r.T_target_source;
  std::printf("GICP 1 cm noise: %.5f m %.5f deg, fitness %.4f m, overlap %.3f\n", err.translation().norm(),
              angleDeg(err), r.fitness_m, r.overlap);
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleDeg(err), 0.1);
  EXPECT_LT(r.fitness_m, 0.05);
}

TEST(Gicp, ReportsNoConvergenceWhenTheCloudsDoNotOverlap) {
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      a.emplace_back(0.1 * i, 0.1 * j, 0.0);
      b.emplace_back(50 + 0.1 * i, 0.0, 0.1 * j);
    }
  const GicpResult r = gicp(b, a, Eigen::Isometry3d::Identity());
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.overlap, 0.0);
}

TEST(Gicp, PlaneCovariancesAreThinAlongTheNormal) {
  std::vector<Eigen::Vector3d> plane;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) plane.emplace_back(0.05 * i, 0.05 * j, 2.0);
  const auto covs = planeCovariances(plane, 20, 1e-3);
  const Eigen::Matrix3d& C = covs[210];
  EXPECT_NEAR(C(2, 2), 1e-3, 1e-9);
  EXPECT_NEAR(C(0, 0), 1.0, 1e-9);
  EXPECT_NEAR(C(1, 1), 1.0, 1e-9);
}

}  // namespace
}  // namespace mmlio::calib
