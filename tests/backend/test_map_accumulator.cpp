#include <gtest/gtest.h>

#include <random>

#include "mmlio/backend/map_accumulator.hpp"

namespace mmlio::backend {

TEST(MapAccumulator, AveragesPointsPerVoxelInTheWorldFrame) {
  MapAccumulator map(0.1);
  Point a, b, c;
  a.xyz = {0.01f, 0.01f, 0.01f};
  a.intensity = 10;
  b.xyz = {0.03f, 0.05f, 0.07f};
  b.intensity = 30;
  c.xyz = {0.51f, 0.01f, 0.01f};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10, 0, 0);
  map.add({a, b, c}, T);
  ASSERT_EQ(map.size(), 2u);
  bool found = false;
  for (const Point& p : map.points()) {
    if (p.xyz.x() < 10.2f) {
      found = true;
      EXPECT_NEAR(p.xyz.x(), 10.02f, 1e-5);
      EXPECT_NEAR(p.xyz.z(), 0.04f, 1e-5);
      EXPECT_FLOAT_EQ(p.intensity, 20.f);
    }
  }
  EXPECT_TRUE(found);
}

TEST(MapAccumulator, LeafZeroKeepsEveryPoint) {
  MapAccumulator map(0.0);
  map.add(std::vector<Point>(5), Eigen::Isometry3d::Identity());
  EXPECT_EQ(map.size(), 5u);
}

// Clouds of a few submaps, overlapping in space (several clouds share voxels), around the origin
// (negative keys) and with a voxel's first point in a later cloud than others'.
std::vector<std::vector<Point>> overlappingClouds(std::mt19937& rng) {
  std::uniform_real_distribution<float> coord(-1.0f, 1.0f), intensity(0.0f, 255.0f);
  std::vector<std::vector<Point>> clouds(6);
  for (auto& cloud : clouds) {
    cloud.resize(500 + rng() % 500);
    for (Point& p : cloud) {
      p.xyz = {coord(rng), coord(rng), 0.3f * coord(rng)};
      p.intensity = intensity(rng);
    }
  }
  clouds[3].clear();  // a submap without points
  return clouds;
}

TEST(MapAccumulator, MergingBySortedKeysGivesTheAccumulatorsPointsBitForBit) {
  std::mt19937 rng(7);
  for (double leaf : {0.0, 0.05, 0.2}) {
    const auto clouds = overlappingClouds(rng);
    std::vector<PosedPoints> posed;
    MapAccumulator map(leaf);
    for (std::size_t c = 0; c < clouds.size(); ++c) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = Eigen::AngleAxisd(0.3 * static_cast<double>(c), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      T.translation() = Eigen::Vector3d(0.1 * static_cast<double>(c), -0.05, 0.02);
      posed.push_back({&clouds[c], T});
      map.add(clouds[c], T);
    }
    const std::vector<Point> expected = map.points();
    const std::vector<Point> merged = mergeIntoVoxels(posed, leaf);
    ASSERT_EQ(merged.size(), expected.size()) << "leaf " << leaf;
    if (leaf > 0) {
      ASSERT_LT(merged.size(), 4000u) << "the clouds overlap: voxels were merged";
    }
    for (std::size_t i = 0; i < merged.size(); ++i) {
      ASSERT_EQ(merged[i].xyz, expected[i].xyz) << "leaf " << leaf << ", voxel " << i;
      ASSERT_EQ(merged[i].intensity, expected[i].intensity) << "leaf " << leaf << ", voxel " << i;
    }
  }
  EXPECT_TRUE(mergeIntoVoxels({}, 0.05).empty());
}

}  // namespace mmlio::backend
