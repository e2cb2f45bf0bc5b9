#include <gtest/gtest.h>

#include "mmlio/estimator/free_space.hpp"

namespace mmlio::estimator {
namespace {

constexpr Stamp kSweep = 100'000'000;  // 10 Hz

TEST(MoverFound, NeedsAClusterNotScatteredReturns) {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::uint8_t> moved;
  for (int i = 0; i < 40; ++i) {  // one flagged return per 2 m along a wall: the odd false detection
    points.emplace_back(2.0 * i + 0.5, 0.5, 0.5);
    moved.push_back(1);
  }
  EXPECT_FALSE(moverFound(points, moved));
  for (int i = 0; i < kMoverReturns - 1; ++i) {  // a cluster one short of a mover
    points.emplace_back(10.1 + 0.05 * i, 5.2, 1.1);
    moved.push_back(1);
  }
  EXPECT_FALSE(moverFound(points, moved));
  points.emplace_back(10.6, 5.3, 1.2);  // unflagged: does not count
  moved.push_back(0);
  EXPECT_FALSE(moverFound(points, moved));
  points.emplace_back(10.7, 5.3, 1.2);
  moved.push_back(1);
  EXPECT_TRUE(moverFound(points, moved));
}

TEST(MoverWatch, JudgesAtIntervalsWhileQuietAndEverySweepAfterAMover) {
  DynamicConfig cfg;
  cfg.quiet_interval_s = 0.4;
  cfg.hold_s = 1.0;
  MoverWatch watch(cfg);
  std::vector<int> judged;
  for (int k = 0; k < 40; ++k) {
    const Stamp now = 1'000'000'000 + k * kSweep;
    if (!watch.shouldJudge(now)) continue;
    judged.push_back(k);
    watch.judged(now, k == 12);  // a walker found in sweep 12
  }
  // Every 4th sweep, then every sweep for 1 s after sweep 12, then every 4th again.
  const std::vector<int> expected = {0, 4, 8, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 26, 30, 34, 38};
  EXPECT_EQ(judged, expected);
}

TEST(MoverWatch, ZeroIntervalJudgesEverySweep) {
  DynamicConfig cfg;
  cfg.quiet_interval_s = 0.0;
  MoverWatch watch(cfg);
  for (int k = 0; k < 10; ++k) {
    EXPECT_TRUE(watch.shouldJudge(k * kSweep));
    watch.judged(k * kSweep, false);
  }
}

}  // namespace
}  // namespace mmlio::estimator
