#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "mmlio/sim/lidar_patterns.hpp"

namespace mmlio::sim {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

TEST(VelodynePattern, SixteenRingsFromMinus15To15DegIn2DegStepsWithSortedTimesInOneTenthSecond) {
  const std::vector<Beam> beams = velodyneBeams(VelodyneConfig());
  EXPECT_EQ(beams.size(), 1800u * 16u);
  std::set<int> rings;
  for (size_t i = 0; i < beams.size(); ++i) {
    const Beam& b = beams[i];
    const double elevation = std::asin(b.dir.z()) * kRadToDeg;
    EXPECT_NEAR(elevation, -15.0 + 2.0 * b.ring, 1e-3);
    EXPECT_GE(b.time_s, 0.f);
    EXPECT_LT(b.time_s, 0.1f);
    if (i > 0) {
      EXPECT_GE(b.time_s, beams[i - 1].time_s);
    }
    rings.insert(b.ring);
  }
  EXPECT_EQ(rings.size(), 16u);
  EXPECT_EQ(*rings.begin(), 0);
  EXPECT_EQ(*rings.rbegin(), 15);
}

TEST(VelodynePattern, HeadTurnsOnceClockwisePerSweep) {
  const std::vector<Beam> beams = velodyneBeams(VelodyneConfig());
  // Ring 0 beams, first column at azimuth 180 deg, a quarter turn later at 90 deg (clockwise).
  const Beam& first = beams[0];
  const Beam& quarter = beams[450 * 16];
  EXPECT_NEAR(std::atan2(first.dir.y(), first.dir.x()) * kRadToDeg, 180.0, 1e-3);
  EXPECT_NEAR(std::atan2(quarter.dir.y(), quarter.dir.x()) * kRadToDeg, 90.0, 1e-2);
}

// Fraction of 0.5 x 0.5 deg cells of the field of view hit by beams of frames [0, n).
double coverage(const LivoxConfig& c, int frames) {
  const double cell = 0.5;
  const int nx = static_cast<int>(c.fov_horizontal_deg / cell) + 1,
            ny = static_cast<int>(c.fov_vertical_deg / cell) + 1;
  std::vector<char> hit(nx * ny, 0);
  for (int k = 0; k < frames; ++k)
    for (const Beam& b : livoxBeams(c, k)) {
      const double az = std::atan2(b.dir.y(), b.dir.x()) * kRadToDeg + c.fov_horizontal_deg / 2;
      const double el = std::asin(b.dir.z()) * kRadToDeg + c.fov_vertical_deg / 2;
      hit[static_cast<int>(el / cell) * nx + static_cast<int>(az / cell)] = 1;
    }
  int n = 0;
  for (char h : hit) n += h;
  return static_cast<double>(n) / hit.size();
}

TEST(LivoxPattern, FrameHas24000BeamsOnSixLinesInsideTheFieldOfViewWithinOneTenthSecond) {
  const LivoxConfig c;
  for (int k : {0, 7, 123}) {
    const std::vector<Beam> beams = livoxBeams(c, k);
    EXPECT_EQ(beams.size(), 24000u);
    std::set<int> lines;
    for (size_t i = 0; i < beams.size(); ++i) {
      const Beam& b = beams[i];
      EXPECT_LE(std::abs(std::atan2(b.dir.y(), b.dir.x())) * kRadToDeg, c.fov_horizontal_deg / 2 + 1e-3);
      EXPECT_LE(std::abs(std::asin(b.dir.z())) * kRadToDeg, c.fov_vertical_deg / 2 + 1e-3);
      EXPECT_GT(b.dir.x(), 0.f);
      EXPECT_GE(b.time_s, 0.f);
      EXPECT_LT(b.time_s, 0.1f);
      if (i > 0) {
        EXPECT_GE(b.time_s, beams[i - 1].time_s);
      }
      lines.insert(b.ring);
    }
    EXPECT_EQ(lines.size(), 6u);
    EXPECT_EQ(*lines.rbegin(), 5);
  }
}

TEST(LivoxPattern, CoverageGrowsFromOneTenthToOneSecondOfIntegration) {
  const LivoxConfig c;
  const double c1 = coverage(c, 1), c10 = coverage(c, 10);
  EXPECT_GT(c1, 0.2);
  EXPECT_GT(c10, c1 + 0.15);
  EXPECT_GT(c10, 0.8);
}

TEST(LivoxPattern, ConsecutiveFramesDiffer) {
  const LivoxConfig c;
  const auto a = livoxBeams(c, 0), b = livoxBeams(c, 1);
  EXPECT_GT((a[100].dir - b[100].dir).norm(), 1e-3);
}

TEST(LivoxPattern, RosetteStaysInTheViewAndCoversItWithOtherBeamsThanTheLissajous) {
  LivoxConfig rosette;
  rosette.pattern = SolidStatePattern::kRosette;
  for (const Beam& b : livoxBeams(rosette, 3)) {
    EXPECT_LE(std::abs(std::atan2(b.dir.y(), b.dir.x())) * kRadToDeg, rosette.fov_horizontal_deg / 2 + 1e-3);
    EXPECT_LE(std::abs(std::asin(b.dir.z())) * kRadToDeg, rosette.fov_vertical_deg / 2 + 1e-3);
  }
  EXPECT_GT(coverage(rosette, 10), 0.6);
  EXPECT_GT(coverage(rosette, 10), coverage(rosette, 1) + 0.1);
  // Not the Lissajous pattern: the same beams point elsewhere.
  const auto a = livoxBeams(rosette, 3), b = livoxBeams(LivoxConfig(), 3);
  int different = 0;
  for (std::size_t i = 0; i < a.size(); i += 100) different += (a[i].dir - b[i].dir).norm() > 0.05f ? 1 : 0;
  EXPECT_GT(different, 200);
}

}  // namespace
}  // namespace mmlio::sim
