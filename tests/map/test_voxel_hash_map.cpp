#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
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

// The map's k nearest within max_dist of q are, distance by distance, the brute-force ones of `stored`.
void expectKnnIsBruteForce(const VoxelHashMap& map, const std::vector<Eigen::Vector3d>& stored,
                           const Eigen::Vector3d& q, int k, double max_dist) {
  std::vector<Eigen::Vector3d> got;
  const int n = map.knn(q, k, max_dist, &got);
  std::vector<double> d;
  for (const auto& p : stored)
    if ((p - q).norm() <= max_dist) d.push_back((p - q).norm());
  std::sort(d.begin(), d.end());
  ASSERT_EQ(n, std::min<int>(k, static_cast<int>(d.size())));
  for (int i = 0; i < n; ++i) EXPECT_NEAR((got[i] - q).norm(), d[i], 1e-12) << "rank " << i;
}

}  // namespace

TEST(VoxelHashMap, KnnEqualsBruteForceOnTheStoredPoints) {
  VoxelHashMap map(0.5, 1000);  // large cap: every point is stored
  const auto cloud = randomCloud(20000, 10.0, 1);
  map.add(cloud);
  ASSERT_EQ(map.size(), cloud.size());
  for (const auto& q : randomCloud(200, 11.0, 2))
    for (double max_dist : {0.4, 1.0, 2.5}) expectKnnIsBruteForce(map, cloud, q, 5, max_dist);
}

TEST(VoxelHashMap, KnnEqualsBruteForceWhenTheSearchSpansManyBricks) {
  // Sparse points and a wide gate: a query scans rings of voxels across dozens of 4x4x4 bricks,
  // more than a query keeps at hand, so bricks are looked up again after being let go.
  // (1 m bricks; a 1.5 m gate reaches 6 rings: up to 125 bricks, and the map has enough voxels
  // that the rings are scanned rather than the whole map.)
  VoxelHashMap map(0.25, 1000);
  const auto cloud = randomCloud(2000, 10.0, 3);
  map.add(cloud);
  for (const auto& q : randomCloud(100, 10.0, 4)) expectKnnIsBruteForce(map, cloud, q, 5, 1.5);
}

TEST(VoxelHashMap, HoldsExactlyTheAddedPointsAcrossManyAddsAndRemovals) {
  // Keyframe after keyframe: voxels fill up and their spans move, removals leave holes, and the
  // arena is rewritten now and then. The map must hold exactly the points a plain list would
  // (each voxel's first max_points in arrival order, minus those removed), and kNN must agree.
  const double voxel = 0.5;
  const int cap = 12;
  VoxelHashMap map(voxel, cap);
  std::vector<std::vector<Eigen::Vector3d>> expected_by_voxel;  // arrival order per voxel
  std::map<std::tuple<int, int, int>, std::size_t> voxel_of;
  const auto cell = [&](const Eigen::Vector3d& p) {
    return std::make_tuple(static_cast<int>(std::floor(p.x() / voxel)), static_cast<int>(std::floor(p.y() / voxel)),
                           static_cast<int>(std::floor(p.z() / voxel)));
  };
  for (unsigned batch = 0; batch < 40; ++batch) {
    const auto pts = randomCloud(400, 3.0, 100 + batch);
    map.add(pts);
    for (const auto& p : pts) {
      const auto [it, added] = voxel_of.emplace(cell(p), expected_by_voxel.size());
      if (added) expected_by_voxel.emplace_back();
      auto& list = expected_by_voxel[it->second];
      if (static_cast<int>(list.size()) < cap) list.push_back(p);
    }
    if (batch % 7 == 3) {
      const Eigen::Vector3d c(0.5 * (batch % 3), 0.0, -0.5);
      const auto drop = [](const Eigen::Vector3d& p) { return p.x() + p.y() > 0.0; };
      map.removeIf(c, 1.5, drop);
      for (auto& list : expected_by_voxel)
        list.erase(std::remove_if(list.begin(), list.end(),
                                  [&](const Eigen::Vector3d& p) { return (p - c).norm() <= 1.5 && drop(p); }),
                   list.end());
    }
  }
  std::vector<Eigen::Vector3d> expected;
  for (const auto& list : expected_by_voxel) expected.insert(expected.end(), list.begin(), list.end());
  ASSERT_EQ(map.size(), expected.size());
  const auto key = [](const Eigen::Vector3d& p) { return std::make_tuple(p.x(), p.y(), p.z()); };
  auto got = map.points();
  ASSERT_EQ(got.size(), expected.size());
  std::sort(got.begin(), got.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  std::sort(expected.begin(), expected.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], expected[i]);
  for (const auto& q : randomCloud(100, 3.5, 7)) expectKnnIsBruteForce(map, expected, q, 5, 1.0);
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

namespace {

// n points of the plane z = 0.2 + 0.1 x (noise +-noise_m) inside the voxel [0, 0.5)^3.
std::vector<Eigen::Vector3d> tiltedPatch(int n, double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.02, 0.48), e(-noise_m, noise_m);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng);
    pts.emplace_back(x, y, 0.2 + 0.1 * x + e(rng));
  }
  return pts;
}

}  // namespace

TEST(VoxelHashMap, APlanarVoxelKeepsItsPlaneOnceRefitted) {
  VoxelHashMap map(0.5, 60, true);
  map.add(tiltedPatch(30, 0.005, 1));
  const Eigen::Vector3d q(0.25, 0.25, 0.225);
  EXPECT_EQ(map.planeAt(q), nullptr) << "a changed voxel has no plane until refitted";
  map.refitPlanes();
  const VoxelHashMap::VoxelPlane* plane = map.planeAt(q);
  ASSERT_NE(plane, nullptr);
  const Eigen::Vector3d truth = Eigen::Vector3d(-0.1, 0.0, 1.0).normalized();
  EXPECT_GT(std::abs(plane->normal.dot(truth)), 0.999);
  EXPECT_NEAR(plane->normal.norm(), 1.0, 1e-12);
  EXPECT_LT(std::abs(plane->normal.dot(q) + plane->d), 0.01) << "q lies on the patch";
  EXPECT_EQ(map.planeAt(Eigen::Vector3d(0.75, 0.25, 0.25)), nullptr) << "an empty voxel";

  VoxelHashMap plain(0.5, 60);
  plain.add(tiltedPatch(30, 0.005, 1));
  plain.refitPlanes();
  EXPECT_EQ(plain.planeAt(q), nullptr) << "only maps built with fit_planes keep planes";
}

TEST(VoxelHashMap, ACornerASparseOrARoughVoxelHasNoPlane) {
  VoxelHashMap map(0.5, 60, true);
  // Corner: the floor patch of voxel [0, 0.5)^3 and a wall at x = 0.45 in the same voxel.
  std::vector<Eigen::Vector3d> corner = tiltedPatch(20, 0.0, 2);
  for (int i = 0; i < 20; ++i) corner.emplace_back(0.45, 0.02 + 0.02 * i, 0.05 + 0.02 * i);
  map.add(corner);
  // Too few points: 9 in voxel [1, 1.5) x [0, 0.5)^2.
  std::vector<Eigen::Vector3d> sparse = tiltedPatch(VoxelHashMap::kPlaneMinPoints - 1, 0.0, 3);
  for (auto& p : sparse) p.x() += 1.0;
  map.add(sparse);
  // Rough: +-8 cm about the plane, beyond kPlaneMaxResidualM, in voxel [2, 2.5) x [0, 0.5)^2.
  std::vector<Eigen::Vector3d> rough = tiltedPatch(40, 0.08, 4);
  for (auto& p : rough) p.x() += 2.0;
  map.add(rough);
  map.refitPlanes();
  EXPECT_EQ(map.planeAt(Eigen::Vector3d(0.25, 0.25, 0.25)), nullptr);
  EXPECT_EQ(map.planeAt(Eigen::Vector3d(1.25, 0.25, 0.25)), nullptr);
  EXPECT_EQ(map.planeAt(Eigen::Vector3d(2.25, 0.25, 0.25)), nullptr);
}

TEST(VoxelHashMap, RemovingTheWallFromACornerVoxelLeavesTheFloorsPlane) {
  VoxelHashMap map(0.5, 60, true);
  std::vector<Eigen::Vector3d> corner = tiltedPatch(20, 0.0, 5);
  for (int i = 0; i < 20; ++i) corner.emplace_back(0.45, 0.02 + 0.02 * i, 0.3 + 0.005 * i);
  map.add(corner);
  map.refitPlanes();
  const Eigen::Vector3d q(0.25, 0.25, 0.225);
  ASSERT_EQ(map.planeAt(q), nullptr);
  const auto on_wall = [](const Eigen::Vector3d& p) { return p.x() == 0.45; };
  EXPECT_EQ(map.removeIf(Eigen::Vector3d::Zero(), 5.0, on_wall), 20u);
  EXPECT_EQ(map.planeAt(q), nullptr) << "changed: stale until refitted";
  map.refitPlanes();
  const VoxelHashMap::VoxelPlane* plane = map.planeAt(q);
  ASSERT_NE(plane, nullptr);
  EXPECT_GT(std::abs(plane->normal.dot(Eigen::Vector3d(-0.1, 0.0, 1.0).normalized())), 0.9999);
}
