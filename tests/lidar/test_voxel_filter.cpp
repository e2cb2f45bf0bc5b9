#include <gtest/gtest.h>

#include "mmlio/lidar/voxel_filter.hpp"

using mmlio::Point;

namespace {
Point P(float x, float y, float z, float intensity = 0.f) {
  Point p;
  p.xyz = Eigen::Vector3f(x, y, z);
  p.intensity = intensity;
  return p;
}
}  // namespace

TEST(VoxelFilter, OnePointPerOccupiedVoxelAtTheCentroidWithMeanIntensity) {
  // 10 x 10 x 10 grid at 0.1 m spacing, leaf 0.5 m -> 2 x 2 x 2 voxels of 125 points each.
  std::vector<Point> pts;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k)
        pts.push_back(P(0.05f + 0.1f * i, 0.05f + 0.1f * j, 0.05f + 0.1f * k, i < 5 ? 10.f : 30.f));
  const auto out = mmlio::lidar::voxelDownsample(pts, 0.5);
  ASSERT_EQ(out.size(), 8u);
  for (const auto& p : out) {
    for (int a = 0; a < 3; ++a) {
      const float c = p.xyz[a];
      EXPECT_TRUE(std::abs(c - 0.25f) < 1e-4f || std::abs(c - 0.75f) < 1e-4f) << c;
    }
    EXPECT_FLOAT_EQ(p.intensity, p.xyz.x() < 0.5f ? 10.f : 30.f);
  }
}

TEST(VoxelFilter, NegativeCoordinatesLandInTheirOwnVoxelsAndZeroLeafKeepsAll) {
  std::vector<Point> pts{P(-0.1f, 0, 0), P(0.1f, 0, 0), P(-0.2f, 0, 0), P(0.2f, 0, 0)};
  EXPECT_EQ(mmlio::lidar::voxelDownsample(pts, 1.0).size(), 2u);
  EXPECT_EQ(mmlio::lidar::voxelDownsample(pts, 0.0).size(), 4u);
  EXPECT_EQ(mmlio::lidar::voxelDownsample({}, 0.5).size(), 0u);
}
