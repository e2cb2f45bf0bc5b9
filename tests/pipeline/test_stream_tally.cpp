// Every LiDAR scan (and IMU sample) that was sent is received or counted missing: the tally learns
// each stream's period and counts the messages a longer interval lacks, without false gaps from jitter.
#include <gtest/gtest.h>

#include "mmlio/pipeline/stream_tally.hpp"

namespace mmlio::pipeline {
namespace {

constexpr Stamp kT0 = 1'700'000'000'000'000'000LL;
constexpr Stamp kPeriod = 100'000'000LL;  // 10 Hz

/// Scan k's stamp with up to +-4 ms of driver jitter, as real drivers stamp.
Stamp stampOf(int k) { return kT0 + k * kPeriod + ((k * 7919) % 9 - 4) * 1'000'000LL; }

TEST(StreamTally, AJitteredStreamHasNoGapsAndItsPeriod) {
  StreamTally t;
  for (int k = 0; k < 600; ++k) t.add("velodyne", stampOf(k));
  const auto s = t.streamsUntil(stampOf(599) + kPeriod).at("velodyne");
  EXPECT_EQ(s.received, 600u);
  EXPECT_EQ(s.missing, 0u);
  EXPECT_TRUE(s.gaps.empty());
  EXPECT_NEAR(s.period_s, 0.1, 0.005);
}

TEST(StreamTally, CountsEveryMissingScanWhereverItIsMissing) {
  StreamTally t;
  std::size_t dropped = 0, sent = 0;
  for (int k = 0; k < 300; ++k) {
    // Two of the first four (while the period is still learnt), every seventh, a 3 s outage.
    const bool lost = k == 1 || k % 7 == 3 || (k >= 100 && k < 130);
    ++sent;
    if (lost) {
      ++dropped;
      continue;
    }
    t.add("livox", stampOf(k));
  }
  const auto s = t.streamsUntil(stampOf(299) + kPeriod).at("livox");
  EXPECT_EQ(s.missing, dropped);
  EXPECT_EQ(s.expected(), sent);
  ASSERT_FALSE(s.gaps.empty());
  EXPECT_EQ(s.gaps.front().after_ns, stampOf(0));
  EXPECT_EQ(s.gaps.size(), StreamTally::kMaxListed);  // listed up to a bound, all counted
}

TEST(StreamTally, ALidarThatStopsMissesWhatItWouldHaveSentUntilTheStreamEnds) {
  StreamTally t;
  t.expect("velodyne");
  t.expect("livox");
  for (int k = 0; k < 100; ++k) t.add("livox", stampOf(k));
  for (int k = 0; k < 50; ++k) t.add("velodyne", stampOf(k));
  const Stamp end = stampOf(99) + kPeriod / 2;
  const auto streams = t.streamsUntil(end);
  EXPECT_EQ(streams.at("livox").missing, 0u);
  EXPECT_EQ(streams.at("velodyne").missing, 49u);  // scans 50..98 (99 is still being swept at the end)
  StreamTally silent;
  silent.expect("velodyne");
  EXPECT_EQ(silent.streamsUntil(end).at("velodyne").received, 0u);
}

}  // namespace
}  // namespace mmlio::pipeline
