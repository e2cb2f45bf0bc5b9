#include <gtest/gtest.h>

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

}  // namespace mmlio::pipeline
