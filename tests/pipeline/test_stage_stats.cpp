#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "mmlio/pipeline/stage_stats.hpp"

namespace mmlio::pipeline {

TEST(StageStats, MeanAndNearestRankP95OverSweepsWithATotalPerSweep) {
  StageStats stats;
  for (int i = 1; i <= 20; ++i) stats.add({{"features", double(i)}, {"registration", 2.0}});
  EXPECT_EQ(stats.sweeps(), 20u);
  EXPECT_DOUBLE_EQ(stats.meanMs("features"), 10.5);
  EXPECT_NEAR(stats.p95Ms("features"), 19.0, 0.19);  // 19 of 20 samples are <= 19 (to within 1 %)
  EXPECT_DOUBLE_EQ(stats.p99Ms("features"), 20.0);   // nearest rank ceil(19.8) = 20: the maximum
  EXPECT_DOUBLE_EQ(stats.maxMs("features"), 20.0);
  EXPECT_DOUBLE_EQ(stats.maxMs("unknown stage"), 0.0);
  EXPECT_DOUBLE_EQ(stats.meanMs("total"), 12.5);
  const std::vector<std::string> expected{"features", "registration", "total"};
  EXPECT_EQ(stats.stages(), expected);
  const std::string json = stats.toJson().dump(-1);
  EXPECT_NE(json.find("\"total\":{\"mean_ms\":12.5"), std::string::npos) << json;
}

TEST(StageStats, PercentilesOfAMillionSweepsAreWithinOnePercent) {
  // Times spread over five decades, as a run's stages are (microseconds to seconds).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> decades(-2.0, 3.0);
  std::vector<double> ms(1000000);
  StageStats stats;
  for (double& t : ms) {
    t = std::pow(10.0, decades(rng));
    stats.add({{"registration", t}});
  }
  std::sort(ms.begin(), ms.end());
  const double p95 = ms[949999], p99 = ms[989999];  // nearest rank
  EXPECT_NEAR(stats.p95Ms("registration"), p95, 0.01 * p95);
  EXPECT_GE(stats.p95Ms("registration"), p95);
  EXPECT_NEAR(stats.p99Ms("registration"), p99, 0.01 * p99);
  EXPECT_DOUBLE_EQ(stats.maxMs("registration"), ms.back());
  EXPECT_EQ(stats.sweeps(), ms.size());
}

}  // namespace mmlio::pipeline
