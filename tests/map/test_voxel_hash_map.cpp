#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "mmlio/map/voxel_hash_map.hpp"

using mmlio::map::VoxelHashMap;

namespace {

std::vector<Eigen::Vector3d> randomCloud(int n, double half_extent_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-half_extent_m, half_extent_m);
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) p = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return pts;
}

}  // namespace

TEST(VoxelHashMap, KnnEqualsBruteForceOnTheStoredPoints) {
  VoxelHashMap map(0.5, 1000);  // large cap: every point is stored
  const auto cloud = randomCloud(20000, 10.0, 1);
  map.add(cloud);
  ASSERT_EQ(map.size(), cloud.size());
  const auto queries = randomCloud(200, 11.0, 2);
  std::vector<Eigen::Vector3d> got;
  for (const auto& q : queries) {
    for (double max_dist : {0.4, 1.0, 2.5}) {
      const int k = 5;
      const int n = map.knn(q, k, max_dist, &got);
      std::vector<double> d;
      for (const auto& p : cloud)
        if ((p - q).norm() <= max_dist) d.push_back((p - q).norm());
      std::sort(d.begin(), d.end());
      ASSERT_EQ(n, std::min<int>(k, static_cast<int>(d.size())));
      for (int i = 0; i < n; ++i) EXPECT_NEAR((got[i] - q).norm(), d[i], 1e-12) << "rank " << i;
    }
  }
}

TEST(VoxelHashMap, KnnEqualsBruteForceWhenTheSearchSpansManyBricks) {
  // Sparse points and a wide gate: a query scans rings of voxels across dozens of 4x4x4 bricks,
  // more than a query keeps at hand, so bricks are looked up again after being let go.
  // (1 m bricks; a 1.5 m gate reaches 6 rings: up to 125 bricks, and the map has enough voxels
  // that the rings are scanned rather than the whole map.)
  VoxelHashMap map(0.25, 1000);
  const auto cloud = randomCloud(2000, 10.0, 3);
  map.add(cloud);
  const auto queries = randomCloud(100, 10.0, 4);
  std::vector<Eigen::Vector3d> got;
  for (const auto& q : queries) {
    const int k = 5;
    const double max_dist = 1.5;
    const int n = map.knn(q, k, max_dist, &got);
    std::vector<double> d;
    for (const auto& p : cloud)
      if ((p - q).norm() <= max_dist) d.push_back((p - q).norm());
    std::sort(d.begin(), d.end());
    ASSERT_EQ(n, std::min<int>(k, static_cast<int>(d.size())));
    for (int i = 0; i < n; ++i) EXPECT_NEAR((got[i] - q).norm(), d[i], 1e-12) << "rank " << i;
  }
}

TEST(VoxelHashMap, KnnFindsNeighboursBeyondTheFirstRingWhenTheyAreTheOnlyOnes) {
  VoxelHashMap map(0.2, 20);
  map.add({Eigen::Vector3d(1.0, 0, 0), Eigen::Vector3d(0, 1.5, 0), Eigen::Vector3d(0, 0, 3.0)});
  std::vector<Eigen::Vector3d> got;
  EXPECT_EQ(map.knn(Eigen::Vector3d::Zero(), 2, 2.0, &got), 2);
  EXPECT_TRUE(got[0].isApprox(Eigen::Vector3d(1.0, 0, 0)));
  EXPECT_TRUE(got[1].isApprox(Eigen::Vector3d(0, 1.5, 0)));
  EXPECT_EQ(map.knn(Eigen::Vector3d::Zero(), 5, 0.5, &got), 0);
  // A huge radius on a small map scans the map instead of millions of empty cells.
  EXPECT_EQ(map.knn(Eigen::Vector3d::Zero(), 5, 1e6, &got), 3);
  EXPECT_TRUE(got[2].isApprox(Eigen::Vector3d(0, 0, 3.0)));
}

TEST(VoxelHashMap, VoxelCapBoundsThePointsPerVoxel) {
  VoxelHashMap map(1.0, 3);
  std::vector<Eigen::Vector3d> same_voxel(10, Eigen::Vector3d(0.5, 0.5, 0.5));
  map.add(same_voxel);
  EXPECT_EQ(map.size(), 3u);
  EXPECT_EQ(map.numVoxels(), 1u);
}

TEST(VoxelHashMap, RemoveFarFromKeepsOnlyPointsNearTheCentre) {
  VoxelHashMap map(0.5, 5);
  map.add(randomCloud(20000, 50.0, 3));
  const std::size_t before = map.size();
  const Eigen::Vector3d c(10, 0, 0);
  map.removeFarFrom(c, 20.0);
  EXPECT_LT(map.size(), before / 4);
  EXPECT_GT(map.size(), 0u);
  // Voxels are dropped by their first point: any kept point is within radius + one voxel diagonal.
  for (const auto& p : map.points()) EXPECT_LE((p - c).norm(), 20.0 + std::sqrt(3.0) * 0.5);
  EXPECT_EQ(map.points().size(), map.size());
  map.clear();
  EXPECT_TRUE(map.empty());
}

namespace mmlio::map {

TEST(VoxelHashMap, RemoveIfDropsOnlyThePointsWithinTheRadiusThatThePredicateNames) {
  VoxelHashMap m(0.5, 20);
  std::vector<Eigen::Vector3d> pts;
  for (int i = -40; i <= 40; ++i) pts.emplace_back(0.1 * i, 0.0, 0.0);  // a line from -4 to 4 m
  m.add(pts);
  const std::size_t removed =
      m.removeIf(Eigen::Vector3d::Zero(), 2.0, [](const Eigen::Vector3d& p) { return p.x() > 0.05; });
  EXPECT_EQ(removed, 20u);  // x = 0.1 .. 2.0
  EXPECT_EQ(m.size(), pts.size() - 20);
  std::vector<Eigen::Vector3d> nn;
  ASSERT_EQ(m.knn(Eigen::Vector3d(1.0, 0, 0), 1, 5.0, &nn), 1);
  EXPECT_NEAR(nn[0].x(), 0.0, 1e-9);  // the nearest left is the origin ...
  ASSERT_EQ(m.knn(Eigen::Vector3d(2.3, 0, 0), 1, 5.0, &nn), 1);
  EXPECT_NEAR(nn[0].x(), 2.3, 1e-9);  // ... and beyond the radius nothing moved
}

}  // namespace mmlio::map
