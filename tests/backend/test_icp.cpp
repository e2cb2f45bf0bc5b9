#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <vector>

#include "mmlio/backend/point_to_plane_icp.hpp"
#include "synthetic_scene.hpp"

namespace mmlio::backend {
namespace {

using testing::pose;
constexpr double kDeg = M_PI / 180.0;

double angleOf(const Eigen::Isometry3d& T) { return Eigen::AngleAxisd(T.rotation()).angle(); }

TEST(PointToPlaneIcp, RecoversAKnownOffsetBetweenTwoScansOfARoom) {
  const auto scene = testing::roomA();
  const Eigen::Isometry3d T_world_a = pose(-1.0, 0.5, 1.0, 0.2);
  const Eigen::Isometry3d T_a_b = pose(0.6, -0.4, 0.05, 6 * kDeg, -0.5 * kDeg, 1 * kDeg);
  const auto cloud_a = testing::scan(scene, T_world_a, 1);
  const auto cloud_b = testing::scan(scene, T_world_a * T_a_b, 2);
  const IcpTarget target(map::voxelCentroids(cloud_a, 0.1));
  const IcpResult r = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.converged);
  const Eigen::Isometry3d err = T_a_b.inverse() * r.T_target_source;
  std::printf("ICP error %.4f m %.4f deg, fitness %.4f m, overlap %.3f, min eig %.3f, %d iterations\n",
              err.translation().norm(), angleOf(err) / kDeg, r.fitness_m, r.overlap, r.min_translation_eigenvalue,
              r.iterations);
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleOf(err), 0.1 * kDeg);
  EXPECT_LT(r.fitness_m, 0.03);
  EXPECT_GT(r.overlap, 0.8);
  EXPECT_GT(r.min_translation_eigenvalue, 0.02);  // a room constrains every direction
}

TEST(PointToPlaneIcp, TwoThousandSpreadOutSourcePointsAlignAsWellAsAll) {
  const auto scene = testing::roomA();
  const Eigen::Isometry3d T_world_a = pose(-1.0, 0.5, 1.0, 0.2);
  const Eigen::Isometry3d T_a_b = pose(0.6, -0.4, 0.05, 6 * kDeg, -0.5 * kDeg, 1 * kDeg);
  const IcpTarget target(map::voxelCentroids(testing::scan(scene, T_world_a, 1), 0.1));
  const auto cloud_b = testing::scan(scene, T_world_a * T_a_b, 2);
  IcpConfig capped;
  capped.max_source_points = 2000;
  const IcpResult all = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity());
  const IcpResult few = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity(), capped);
  ASSERT_TRUE(all.converged && few.converged);
  ASSERT_GT(all.correspondences, 4000) << "the cap must bite for the test to mean anything";
  EXPECT_LE(few.correspondences, 2000);
  std::printf("all %d correspondences, capped %d: fitness %.4f / %.4f m, overlap %.3f / %.3f\n", all.correspondences,
              few.correspondences, all.fitness_m, few.fitness_m, all.overlap, few.overlap);
  const Eigen::Isometry3d err = T_a_b.inverse() * few.T_target_source;
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleOf(err), 0.1 * kDeg);
  EXPECT_NEAR(few.fitness_m, all.fitness_m, 0.3 * all.fitness_m);
  EXPECT_NEAR(few.overlap, all.overlap, 0.05);
}

TEST(PointToPlaneIcp, ALevelObserverSeesEveryLevelButTheLastAndChangesNothingUnlessItStops) {
  const auto scene = testing::roomA();
  const Eigen::Isometry3d T_world_a = pose(-1.0, 0.5, 1.0, 0.2);
  const Eigen::Isometry3d T_a_b = pose(0.6, -0.4, 0.05, 6 * kDeg);
  const IcpTarget target(map::voxelCentroids(testing::scan(scene, T_world_a, 1), 0.1));
  const auto cloud_b = testing::scan(scene, T_world_a * T_a_b, 2);
  const IcpResult plain = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity());
  IcpConfig watched;
  std::vector<int> levels_seen;
  watched.continue_after_level = [&](int level, const Eigen::Isometry3d&) {
    levels_seen.push_back(level);
    return true;
  };
  const IcpResult same = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity(), watched);
  EXPECT_EQ(levels_seen, (std::vector<int>{0, 1}));  // 3 levels
  ASSERT_TRUE(same.converged);
  EXPECT_TRUE(same.T_target_source.isApprox(plain.T_target_source, 0.0));
  EXPECT_EQ(same.iterations, plain.iterations);
  EXPECT_EQ(same.min_translation_eigenvalue, plain.min_translation_eigenvalue);
  IcpConfig stopped;
  Eigen::Isometry3d after_coarse = Eigen::Isometry3d::Identity();
  stopped.continue_after_level = [&](int, const Eigen::Isometry3d& T) {
    after_coarse = T;
    return false;
  };
  const IcpResult cut = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity(), stopped);
  EXPECT_FALSE(cut.converged);
  EXPECT_LT(cut.iterations, plain.iterations);
  EXPECT_TRUE(cut.T_target_source.isApprox(after_coarse, 0.0));
  EXPECT_LT((after_coarse.translation() - T_a_b.translation()).norm(), 0.1);  // the coarse level got close
}

TEST(PointToPlaneIcp, FlagsAFeaturelessCorridorAsDegenerateAlongItsAxis) {
  const auto scene = testing::corridor(200.0, 4.0, /*doors=*/false);
  const auto cloud_a = testing::scan(scene, pose(0, 0, 1.0, 0), 3, 0.01, 20.0);
  const auto cloud_b = testing::scan(scene, pose(0.5, 0.1, 1.0, 2 * kDeg), 4, 0.01, 20.0);
  const IcpTarget target(map::voxelCentroids(cloud_a, 0.1));
  const IcpResult r = alignPointToPlane(cloud_b, target, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.converged);
  std::printf("corridor: min eig %.4f along (%.2f %.2f %.2f)\n", r.min_translation_eigenvalue,
              r.weakest_translation_direction.x(), r.weakest_translation_direction.y(),
              r.weakest_translation_direction.z());
  EXPECT_LT(r.min_translation_eigenvalue, 0.03);  // the room above: ~0.1
  EXPECT_GT(std::abs(r.weakest_translation_direction.x()), 0.99);
}

TEST(PointToPlaneIcp, TargetNormalsArePlaneNormalsAndLinesHaveNone) {
  // A 4 x 4 m floor patch on a 10 cm grid (a target's resolution), and a line of points above it.
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) pts.emplace_back(0.1 * i, 0.1 * j, 0.0);
  const std::size_t floor_points = pts.size();
  for (int i = 0; i < 40; ++i) pts.emplace_back(0.05 * i, 1.0, 3.0);
  const IcpTarget target(pts);
  for (std::size_t i : {std::size_t{205}, std::size_t{820}, std::size_t{1234}}) {  // inside the patch
    ASSERT_TRUE(target.hasNormal(i)) << i;
    EXPECT_NEAR(std::abs(target.normal(i).z()), 1.0, 1e-9) << i;
  }
  for (std::size_t i = floor_points; i < pts.size(); i += 13) EXPECT_FALSE(target.hasNormal(i)) << i;
}

// A hint only bounds the search: whatever target point it names, near, far or beyond the gate, the
// answer is the full search's. Points on a 5 cm grid make exact ties, which must resolve alike.
TEST(PointToPlaneIcp, NearestWithAnyHintIsTheFullSearchsAnswer) {
  std::vector<Eigen::Vector3d> grid;
  for (int x = 0; x < 40; ++x)
    for (int y = 0; y < 40; ++y) grid.emplace_back(0.05 * x, 0.05 * y, 0.01 * ((x * 7 + y * 3) % 5));
  const IcpTarget target(grid);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.2, 2.2);
  std::uniform_int_distribution<int> any(-1, static_cast<int>(grid.size()) - 1);
  int found = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d q(u(rng), u(rng), 0.025 * (i % 3));
    const double gate_sq = i % 2 ? 0.01 : 0.25;
    const int full = target.nearestWithin(q, gate_sq);
    found += full >= 0;
    ASSERT_EQ(target.nearestWithin(q, gate_sq, any(rng)), full) << i;
    if (full >= 0) {
      ASSERT_EQ(target.nearestWithin(q, gate_sq, full), full) << i;
    }
  }
  EXPECT_GT(found, 2000);
}

TEST(PointToPlaneIcp, VoxelCentroidsKeepsOnePointPerVoxel) {
  const std::vector<Eigen::Vector3d> pts{{0.1, 0.1, 0.1}, {0.3, 0.3, 0.3}, {1.5, 0.2, 0.2}};
  const auto out = map::voxelCentroids(pts, 1.0);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out[0].isApprox(Eigen::Vector3d(0.2, 0.2, 0.2)));
  EXPECT_TRUE(out[1].isApprox(pts[2]));
}

}  // namespace
}  // namespace mmlio::backend
