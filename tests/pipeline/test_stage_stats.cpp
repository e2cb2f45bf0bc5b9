#include <gtest/gtest.h>

#include "mmlio/pipeline/map_accumulator.hpp"
#include "mmlio/pipeline/stage_stats.hpp"

namespace mmlio::pipeline {

TEST(StageStats, MeanAndNearestRankP95OverSweepsWithATotalPerSweep) {
  StageStats stats;
  for (int i = 1; i <= 20; ++i) stats.add({{"features", double(i)}, {"registration", 2.0}});
  EXPECT_EQ(stats.sweeps(), 20u);
  EXPECT_DOUBLE_EQ(stats.meanMs("features"), 10.5);
  EXPECT_DOUBLE_EQ(stats.p95Ms("features"), 19.0);  // 19 of 20 samples are <= 19
  EXPECT_DOUBLE_EQ(stats.p99Ms("features"), 20.0);  // nearest rank ceil(19.8) = 20
  EXPECT_DOUBLE_EQ(stats.maxMs("features"), 20.0);
  EXPECT_DOUBLE_EQ(stats.maxMs("unknown stage"), 0.0);
  EXPECT_DOUBLE_EQ(stats.meanMs("total"), 12.5);
  const std::vector<std::string> expected{"features", "registration", "total"};
  EXPECT_EQ(stats.stages(), expected);
  const std::string json = stats.toJson().dump(-1);
  EXPECT_NE(json.find("\"total\":{\"mean_ms\":12.5"), std::string::npos) << json;
}

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

}  // namespace mmlio::pipeline
