#include <gtest/gtest.h>

#include <cmath>

#include "mmlio/estimator/map_matching.hpp"

namespace mmlio::estimator {
namespace {

// A floor (z = 0, 4 x 4 m) and a wall (x = 0.55, 1 m high), points 8 cm apart (36 per voxel, below
// the cap of 60), into a plane map of 0.5 m voxels (as the odometry's).
map::VoxelHashMap floorAndWall(bool voxel_planes) {
  map::VoxelHashMap map(0.5, 60, voxel_planes);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) pts.emplace_back(-2.0 + 0.01 + 0.08 * i, -2.0 + 0.01 + 0.08 * j, 0.0);
  for (int j = 0; j < 50; ++j)
    for (int k = 0; k < 12; ++k) pts.emplace_back(0.55, -2.0 + 0.01 + 0.08 * j, 0.02 + 0.08 * k);
  map.add(pts);
  map.refitPlanes();
  return map;
}

MapMatch only(const std::vector<MapMatch>& matches) {
  EXPECT_EQ(matches.size(), 1u);
  return matches.empty() ? MapMatch{} : matches.front();
}

TEST(MapMatching, APointInAPlanarVoxelTakesThePlaneTheNeighboursWouldGive) {
  const map::VoxelHashMap edges(0.5, 60), with_planes = floorAndWall(true), without = floorAndWall(false);
  Features f;
  f.planes = {Eigen::Vector3d(-1.23, 0.71, 0.02)};
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  ASSERT_NE(with_planes.planeAt(f.planes[0]), nullptr);
  const MapMatch voxel = only(findMapMatches(f, T, edges, with_planes));
  const MapMatch knn = only(findMapMatches(f, T, edges, without));
  EXPECT_GT(std::abs(voxel.a.dot(Eigen::Vector3d::UnitZ())), 1.0 - 1e-9);
  EXPECT_GT(std::abs(knn.a.dot(Eigen::Vector3d::UnitZ())), 1.0 - 1e-9);
  EXPECT_NEAR(matchDistance(voxel, T), 0.02, 1e-9);
  EXPECT_NEAR(matchDistance(knn, T), 0.02, 1e-9);
}

TEST(MapMatching, APointFarFromItsVoxelsPlaneTakesItsNeighboursPlane) {
  const map::VoxelHashMap edges(0.5, 60), map = floorAndWall(true);
  Features f;
  // In the floor's voxel (x < 0.5), 0.3 m above the floor, 7 cm from the wall: the wall's plane.
  f.planes = {Eigen::Vector3d(0.48, 0.25, 0.3)};
  const MapMatchConfig cfg;
  ASSERT_NE(map.planeAt(f.planes[0]), nullptr);
  ASSERT_GT(0.3, cfg.voxel_plane_gate_m);
  const MapMatch m = only(findMapMatches(f, Eigen::Isometry3d::Identity(), edges, map, cfg));
  EXPECT_GT(std::abs(m.a.dot(Eigen::Vector3d::UnitX())), 0.999);
  EXPECT_NEAR(matchDistance(m, Eigen::Isometry3d::Identity()), 0.07, 1e-6);
}

TEST(MapMatching, APointOnTheFarSideOfASlabMatchesNothingWithAResidualGate) {
  // The map holds a 0.25 m slab's underside (seen from the storey below); a point on its top face
  // finds those neighbours and their plane 0.25 m away: with a gate it is left unmatched.
  map::VoxelHashMap planes(0.5, 60, false);
  const map::VoxelHashMap edges(0.5, 60);
  std::vector<Eigen::Vector3d> underside;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) underside.emplace_back(0.05 * i, 0.05 * j, 2.75);
  planes.add(underside);
  Features f;
  f.planes = {Eigen::Vector3d(0.52, 0.48, 3.0)};
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  EXPECT_NEAR(matchDistance(only(findMapMatches(f, T, edges, planes)), T), 0.25, 1e-9);
  MapMatchConfig gated;
  gated.max_residual_m = 0.1;
  EXPECT_TRUE(findMapMatches(f, T, edges, planes, gated).empty());
  f.planes = {Eigen::Vector3d(0.52, 0.48, 2.8)};  // 5 cm below the underside: matched
  EXPECT_NEAR(matchDistance(only(findMapMatches(f, T, edges, planes, gated)), T), 0.05, 1e-9);
}

}  // namespace
}  // namespace mmlio::estimator
