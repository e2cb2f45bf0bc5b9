#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "mmlio/lidar/sweep_aligner.hpp"

using namespace mmlio;
using mmlio::lidar::AlignedSweep;
using mmlio::lidar::SweepAligner;

namespace {

// A frame of n points evenly spread over [0, duration); each point's intensity is a unique tag.
LidarScan makeFrame(const std::string& sensor, double start_s, int n, double duration_s, float* next_tag) {
  LidarScan s;
  s.sensor = sensor;
  s.start_ns = fromSec(start_s);
  for (int i = 0; i < n; ++i) {
    Point p;
    p.time_s = static_cast<float>(duration_s * i / n);
    p.intensity = (*next_tag)++;
    s.points.push_back(p);
  }
  return s;
}

struct Collected {
  std::vector<AlignedSweep> sweeps;
  std::map<float, std::pair<std::string, Stamp>> seen;  // tag -> sensor, absolute time
  int duplicates = 0;
};

void collect(const AlignedSweep& sw, Collected* c) {
  c->sweeps.push_back(sw);
  for (const auto& scan : sw.scans) {
    EXPECT_EQ(scan.start_ns, sw.start_ns);
    for (const auto& p : scan.points) {
      EXPECT_GE(p.time_s, 0.f);
      EXPECT_LT(fromSec(p.time_s), sw.end_ns - sw.start_ns + 1000);
      if (!c->seen.emplace(p.intensity, std::make_pair(scan.sensor, sw.start_ns + fromSec(p.time_s))).second)
        ++c->duplicates;
    }
  }
}

// Feeds frames in bag order (by end time), popping after each.
Collected run(SweepAligner& aligner, std::vector<LidarScan> frames) {
  std::stable_sort(frames.begin(), frames.end(),
                   [](const LidarScan& a, const LidarScan& b) { return a.endNs() < b.endNs(); });
  Collected c;
  AlignedSweep sw;
  for (const auto& f : frames) {
    aligner.add(f);
    while (aligner.pop(&sw)) collect(sw, &c);
  }
  for (const auto& s : aligner.flush()) collect(s, &c);
  return c;
}

}  // namespace

TEST(SweepAligner, ClockShiftedFramesAreCutIntoReferenceWindowsWithoutLossOrDuplicates) {
  float tag = 0;
  std::vector<LidarScan> frames;
  std::map<float, Stamp> truth;  // tag -> absolute time
  for (int k = 0; k < 10; ++k) frames.push_back(makeFrame("velodyne", 1.0 + 0.1 * k, 1000, 0.1, &tag));
  for (int k = 0; k < 9; ++k) frames.push_back(makeFrame("livox", 1.037 + 0.1 * k, 500, 0.1, &tag));
  for (const auto& f : frames)
    for (const auto& p : f.points) truth[p.intensity] = f.start_ns + fromSec(p.time_s);

  SweepAligner aligner({"velodyne", 0.3, 0.5});
  const Collected c = run(aligner, frames);
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_EQ(c.seen.size(), truth.size());  // every livox point lies inside the reference's span
  EXPECT_EQ(aligner.droppedPoints(), 0u);
  ASSERT_EQ(c.sweeps.size(), 10u);
  for (std::size_t k = 0; k < c.sweeps.size(); ++k) {
    const auto& sw = c.sweeps[k];
    EXPECT_EQ(sw.start_ns, k == 0 ? fromSec(1.0) : c.sweeps[k - 1].end_ns) << "windows are contiguous";
    EXPECT_EQ(sw.scans.front().sensor, "velodyne");
    EXPECT_EQ(sw.scans.front().points.size(), 1000u);
    if (k >= 1 && k <= 8) {
      ASSERT_EQ(sw.scans.size(), 2u);
      EXPECT_EQ(sw.scans[1].sensor, "livox");
      EXPECT_NEAR(static_cast<double>(sw.scans[1].points.size()), 500.0, 2.0);  // 0.1 s of a 5 kHz stream
    }
  }
  // Livox points from 1.037 s start 37 ms into the first window.
  ASSERT_EQ(c.sweeps[0].scans.size(), 2u);
  EXPECT_NEAR(c.sweeps[0].scans[1].points.front().time_s, 0.037, 1e-6);
  for (const auto& [t, seen] : c.seen) EXPECT_NEAR(static_cast<double>(seen.second - truth.at(t)), 0.0, 1000.0);
}

TEST(SweepAligner, WindowWaitsForTheOtherLidarUntilMaxWait) {
  float tag = 0;
  SweepAligner aligner({"velodyne", 0.3, 0.5});
  AlignedSweep sw;
  aligner.add(makeFrame("livox", 0.95, 100, 0.1, &tag));
  aligner.add(makeFrame("velodyne", 1.0, 100, 0.1, &tag));
  EXPECT_FALSE(aligner.pop(&sw));  // livox has data only up to 1.05 s
  aligner.add(makeFrame("velodyne", 1.1, 100, 0.1, &tag));
  aligner.add(makeFrame("velodyne", 1.2, 100, 0.1, &tag));
  EXPECT_FALSE(aligner.pop(&sw));
  aligner.add(makeFrame("velodyne", 1.3, 100, 0.1, &tag));
  aligner.add(makeFrame("velodyne", 1.4, 100, 0.1, &tag));  // 1.5 s > 1.1 + 0.3: give up waiting
  ASSERT_TRUE(aligner.pop(&sw));
  EXPECT_EQ(sw.start_ns, fromSec(1.0));
  ASSERT_EQ(sw.scans.size(), 2u);
  EXPECT_EQ(sw.scans[1].points.size(), 50u);  // livox points of [1.0, 1.05)
}

TEST(SweepAligner, WhenTheReferenceStopsWindowsComeFromTheOtherLidarsFrames) {
  float tag = 0;
  std::vector<LidarScan> frames;
  for (int k = 0; k < 3; ++k) frames.push_back(makeFrame("velodyne", 1.0 + 0.1 * k, 1000, 0.1, &tag));
  for (int k = 0; k < 15; ++k) frames.push_back(makeFrame("livox", 1.02 + 0.1 * k, 500, 0.1, &tag));
  SweepAligner aligner({"velodyne", 0.3, 0.5});
  const Collected c = run(aligner, frames);
  EXPECT_TRUE(aligner.usingFallback());
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_EQ(c.seen.size(), 3u * 1000 + 15u * 500);  // contiguous windows: nothing lost
  ASSERT_GT(c.sweeps.size(), 10u);
  // The last windows are the livox frames themselves.
  const auto& last = c.sweeps.back();
  EXPECT_EQ(last.end_ns, frames.back().endNs() + 1);
  EXPECT_EQ(last.start_ns, c.sweeps[c.sweeps.size() - 2].end_ns);
  ASSERT_EQ(last.scans.size(), 1u);
  EXPECT_EQ(last.scans[0].sensor, "livox");
  EXPECT_EQ(last.scans[0].points.size(), 500u);
  for (std::size_t k = 1; k < c.sweeps.size(); ++k) EXPECT_EQ(c.sweeps[k].start_ns, c.sweeps[k - 1].end_ns);
}

TEST(SweepAligner, WhenTheReferenceComesBackItsSweepsDefineTheWindowsAgain) {
  float tag = 0;
  std::vector<LidarScan> frames;
  for (int k = 0; k < 3; ++k) frames.push_back(makeFrame("velodyne", 1.0 + 0.1 * k, 1000, 0.1, &tag));
  for (int k = 10; k < 15; ++k)
    frames.push_back(makeFrame("velodyne", 1.0 + 0.1 * k, 1000, 0.1, &tag));  // gap 1.3-2.0 s
  for (int k = 0; k < 15; ++k) frames.push_back(makeFrame("livox", 1.02 + 0.1 * k, 500, 0.1, &tag));
  SweepAligner aligner({"velodyne", 0.3, 0.5});
  const Collected c = run(aligner, frames);
  EXPECT_FALSE(aligner.usingFallback());
  EXPECT_EQ(c.duplicates, 0);
  // All but the last livox frame's final 20 ms, which lies after the last reference sweep.
  EXPECT_EQ(c.seen.size(), 8u * 1000 + 14u * 500 + 400u);
  for (std::size_t k = 1; k < c.sweeps.size(); ++k) EXPECT_EQ(c.sweeps[k].start_ns, c.sweeps[k - 1].end_ns);
  // The last windows are velodyne sweeps again, each with its 1000 points.
  const auto& last = c.sweeps.back();
  EXPECT_EQ(last.end_ns, fromSec(1.0 + 1.4) + fromSec(0.0999) + 1);
  EXPECT_EQ(last.scans.front().sensor, "velodyne");
  EXPECT_EQ(last.scans.front().points.size(), 1000u);
}

TEST(SweepAligner, PointsArrivingAfterTheirWindowWasCutAreCountedAsDroppedAndTheRestDeliveredInOrder) {
  float tag = 0;
  SweepAligner aligner({"velodyne", 0.3, 0.5});
  Collected c;
  AlignedSweep sw;
  const auto feed = [&](const LidarScan& f) {
    aligner.add(f);
    while (aligner.pop(&sw)) collect(sw, &c);
  };
  for (int k = 0; k < 8; ++k) {
    feed(makeFrame("livox", 1.0 + 0.1 * k, 200, 0.1, &tag));
    feed(makeFrame("velodyne", 1.0 + 0.1 * k, 100, 0.1, &tag));
  }
  ASSERT_GE(c.sweeps.size(), 3u);
  const Stamp cut_until = c.sweeps.back().end_ns;
  // A frame delivered late: its first 51 points belong to windows already cut, the other 49 to
  // the next one, among the queued points of the same LiDAR.
  const LidarScan late = makeFrame("livox", toSec(cut_until) - 0.0505, 100, 0.1, &tag);
  feed(late);
  for (int k = 8; k < 12; ++k) {
    feed(makeFrame("livox", 1.0 + 0.1 * k, 200, 0.1, &tag));
    feed(makeFrame("velodyne", 1.0 + 0.1 * k, 100, 0.1, &tag));
  }
  for (const auto& s : aligner.flush()) collect(s, &c);

  EXPECT_EQ(c.duplicates, 0);
  EXPECT_EQ(aligner.droppedPoints(), 51u);
  for (std::size_t i = 0; i < late.points.size(); ++i) {
    const bool on_time = late.start_ns + fromSec(late.points[i].time_s) >= cut_until;
    EXPECT_EQ(c.seen.count(late.points[i].intensity), on_time ? 1u : 0u) << "point " << i;
  }
  for (const auto& s : c.sweeps)
    for (const auto& scan : s.scans)
      EXPECT_TRUE(std::is_sorted(scan.points.begin(), scan.points.end(),
                                 [](const Point& a, const Point& b) { return a.time_s < b.time_s; }));
}
