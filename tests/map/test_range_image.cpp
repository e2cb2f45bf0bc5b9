#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mmlio/map/range_image.hpp"

namespace mmlio::map {
namespace {

constexpr double kDeg = M_PI / 180.0;

Point at(double range, double azimuth_deg, double elevation_deg) {
  Point p;
  const double a = azimuth_deg * kDeg, e = elevation_deg * kDeg;
  p.xyz = (range * Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e))).cast<float>();
  return p;
}

Eigen::Vector3d dir(double range, double azimuth_deg, double elevation_deg) {
  return at(range, azimuth_deg, elevation_deg).xyz.cast<double>();
}

// A wall 10 m ahead seen over azimuth +-30 deg and elevation +-10 deg, dense.
std::vector<Point> wallAhead() {
  std::vector<Point> pts;
  for (double a = -30; a <= 30; a += 0.2)
    for (double e = -10; e <= 10; e += 0.2) pts.push_back(at(10.0 / (std::cos(a * kDeg) * std::cos(e * kDeg)), a, e));
  return pts;
}

}  // namespace

TEST(RangeImage, InFrontOfAWallIsFreeOnItIsHitBehindItIsOccludedElsewhereUnknown) {
  const RangeImage image(wallAhead(), RangeImageConfig{});
  EXPECT_EQ(image.classify(dir(5.0, 0, 0)), Visibility::kFree);
  EXPECT_EQ(image.classify(dir(10.0, 0.1, 0.1)), Visibility::kHit);
  EXPECT_EQ(image.classify(dir(13.0, 0, 0)), Visibility::kOccluded);
  EXPECT_EQ(image.classify(dir(5.0, 90, 0)), Visibility::kUnknown);  // nobody looked there
  EXPECT_EQ(image.classify(dir(0.3, 0, 0)), Visibility::kUnknown);   // inside the blind zone
  EXPECT_EQ(image.classify(dir(9.9, 0, 0)), Visibility::kHit);       // within the range noise: on the wall
  EXPECT_EQ(image.classify(dir(9.8, 0, 0)), Visibility::kUnknown);   // too close to be free, too far to be on it
}

TEST(RangeImage, PointsAtTheEdgeOfTheFieldOfViewAreNeverFree) {
  const RangeImage image(wallAhead(), RangeImageConfig{});
  // Inside the window of measured pixels but not surrounded by them: a ray beside it, none beyond.
  EXPECT_NE(image.classify(dir(5.0, 30.6, 0)), Visibility::kFree);
  EXPECT_NE(image.classify(dir(5.0, 0, 11.5)), Visibility::kFree);
}

TEST(RangeImage, BesideADepthEdgeOnlyWhatIsInFrontOfBothSidesIsFree) {
  std::vector<Point> pts;
  for (double a = -20; a <= 20; a += 0.2)
    for (double e = -5; e <= 5; e += 0.2) pts.push_back(at(a < 0 ? 10.0 : 3.0, a, e));
  const RangeImage image(pts, RangeImageConfig{});
  EXPECT_EQ(image.classify(dir(6.0, -10, 0)), Visibility::kFree);   // far from the edge
  EXPECT_NE(image.classify(dir(6.0, -0.3, 0)), Visibility::kFree);  // behind the near side's rays
  EXPECT_EQ(image.classify(dir(2.0, -0.3, 0)), Visibility::kFree);  // in front of both
}

TEST(RangeImage, AFloorBetweenTheRingsOfASpinningLidarIsNotFree) {
  // VLP-16: rings every 2 deg from -15 to +15; the floor 1.2 m below at grazing incidence.
  std::vector<Point> pts;
  for (int ring = 0; ring < 16; ++ring) {
    const double e = -15.0 + 2.0 * ring;
    for (double a = -180; a < 180; a += 0.2) {
      const double range = e < -0.5 ? 1.2 / std::sin(-e * kDeg) : 20.0;
      pts.push_back(at(std::min(range, 20.0), a, e));
    }
  }
  const RangeImage image(pts, RangeImageConfig{});
  for (double e = -14.5; e < -1.0; e += 0.25) {
    const Eigen::Vector3d floor_point = dir(1.2 / std::sin(-e * kDeg), 40.0, e);
    EXPECT_NE(image.classify(floor_point), Visibility::kFree) << "elevation " << e;
  }
  // A person-sized gap: 2 m ahead at chest height, in front of the 20 m returns above the horizon.
  EXPECT_EQ(image.classify(dir(2.0, 40.0, 5.0)), Visibility::kFree);
}

TEST(RangeImage, NoReturnPointsAndNonFiniteOnesAreIgnored) {
  std::vector<Point> pts = wallAhead();
  Point zero;
  pts.push_back(zero);
  Point nan;
  nan.xyz = Eigen::Vector3f(std::nanf(""), 0.f, 0.f);
  pts.push_back(nan);
  const RangeImage image(pts, RangeImageConfig{});
  EXPECT_EQ(image.classify(dir(5.0, 0, 0)), Visibility::kFree);
  EXPECT_TRUE(RangeImage({zero}, RangeImageConfig{}).empty());
}

}  // namespace mmlio::map

namespace mmlio::map {

TEST(RangeImage, ASolidStateViewKeepsOnlyItsArcAndJudgesAsTheFullCircleWould) {
  // The same 60 deg wall ahead and behind (its arc then straddles +-180 deg azimuth): the image
  // holds about a sixth of a full turn's pixels, and every query, near the arc's edges and across
  // the seam, gets the same answer rotated.
  const std::vector<Point> ahead = wallAhead();
  std::vector<Point> behind = ahead;
  const Eigen::Matrix3f turn = Eigen::AngleAxisf(static_cast<float>(M_PI), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  for (Point& p : behind) p.xyz = turn * p.xyz;
  const RangeImage front(ahead, RangeImageConfig{}), back(behind, RangeImageConfig{});
  const RangeImageConfig cfg;
  const double res = cfg.resolution_deg;
  // Over a full turn, the 20 deg of rows (plus the windows' reach beyond them) twice: the returns
  // and the window summaries.
  const double rows = 20.0 / res + 1;
  const auto full_turn_bytes =
      static_cast<std::size_t>(360.0 / res * (2 * rows + 2 * cfg.window_rows) * sizeof(std::uint16_t));
  EXPECT_LT(front.memoryBytes(), full_turn_bytes / 4);  // the wall's 60 of 360 deg, and a pixel or so
  EXPECT_EQ(front.memoryBytes(), back.memoryBytes());
  int free = 0;
  for (double a = -40; a <= 40; a += 0.25)
    for (double e : {-12.0, -9.9, 0.0, 5.0, 10.1})
      for (double r : {3.0, 9.9, 10.0, 13.0}) {
        const Visibility v = front.classify(dir(r, a, e));
        ASSERT_EQ(v, back.classify(turn.cast<double>() * dir(r, a, e))) << "azimuth " << a << " elevation " << e;
        free += v == Visibility::kFree;
      }
  EXPECT_GT(free, 100);
}

TEST(RangeImage, ANarrowViewAnswersAsTheSameViewWithAReturnBehindWould) {
  // One return straight behind makes the stored arc wider than a half turn, which turns off the
  // narrow view's shortcut for points beyond its arc; no query near the wall can see that return,
  // so every answer must be the same.
  const std::vector<Point> narrow = wallAhead();
  std::vector<Point> wide = narrow;
  wide.push_back(at(50.0, 180.0, 0.0));
  const RangeImage a(narrow, RangeImageConfig{}), b(wide, RangeImageConfig{});
  int unknown = 0, judged = 0;
  for (double az = -170; az <= 170; az += 0.1)
    for (double e : {-10.2, -5.0, 0.0, 9.9})
      for (double r : {3.0, 10.0, 12.0}) {
        const Visibility v = a.classify(dir(r, az, e));
        ASSERT_EQ(v, b.classify(dir(r, az, e))) << "azimuth " << az << " elevation " << e << " range " << r;
        (v == Visibility::kUnknown ? unknown : judged) += 1;
      }
  EXPECT_GT(judged, 1000);   // the wall's arc and its edges
  EXPECT_GT(unknown, 5000);  // the rest of the turn
}

TEST(RangeImage, WindowsReachAPixelBeyondEitherEndOfTheArcAcrossTheSeam) {
  // Returns at 10 m all round but for a 20 deg gap behind (pixel columns 20 .. 700 of 720, each
  // return at its pixel's centre): a query one pixel beyond either end still has a return in its
  // window (the one before column 20 lies across the -180 / +180 deg seam), two pixels beyond none.
  const double res = RangeImageConfig{}.resolution_deg;
  const auto azimuthOfColumn = [res](int col) { return (col + 0.5) * res - 180.0; };
  std::vector<Point> pts;
  for (int col = 20; col <= 700; ++col)
    for (int row = -20; row < 20; ++row) pts.push_back(at(10.0, azimuthOfColumn(col), (row + 0.5) * res));
  const RangeImage image(pts, RangeImageConfig{});
  EXPECT_EQ(image.classify(dir(13.0, azimuthOfColumn(701), 0.25)), Visibility::kOccluded);
  EXPECT_EQ(image.classify(dir(13.0, azimuthOfColumn(19), 0.25)), Visibility::kOccluded);
  EXPECT_EQ(image.classify(dir(10.0, azimuthOfColumn(700), 0.25)), Visibility::kHit);
  EXPECT_EQ(image.classify(dir(13.0, azimuthOfColumn(702), 0.25)), Visibility::kUnknown);
  EXPECT_EQ(image.classify(dir(13.0, azimuthOfColumn(18), 0.25)), Visibility::kUnknown);
  // Free needs returns on both sides: not one pixel beyond the end, but one pixel inside it.
  EXPECT_EQ(image.classify(dir(5.0, azimuthOfColumn(701), 0.25)), Visibility::kUnknown);
  EXPECT_EQ(image.classify(dir(5.0, azimuthOfColumn(699), 0.25)), Visibility::kFree);
  EXPECT_EQ(image.classify(dir(5.0, azimuthOfColumn(21), 0.25)), Visibility::kFree);
  // Rows likewise: a query up to window_rows pixels above the top row is judged, not free.
  const int above = RangeImageConfig{}.window_rows;
  EXPECT_EQ(image.classify(dir(13.0, 0.0, (19 + above + 0.5) * res)), Visibility::kOccluded);
  EXPECT_EQ(image.classify(dir(13.0, 0.0, (19 + above + 1.5) * res)), Visibility::kUnknown);
  EXPECT_EQ(image.classify(dir(5.0, 0.0, (19 + 1.5) * res)), Visibility::kUnknown);
}

TEST(RangeImage, WithoutWindowsItAnswersAlikeFromLessMemory) {
  // A spinning LiDAR's 16 rings in a cluttered room (ranges jumping, a third of the returns
  // missing) and a solid-state arc: every answer the same with and without the window summaries.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Point> rings, arc;
  for (int ring = 0; ring < 16; ++ring)
    for (double a = -180.0; a < 180.0; a += 0.2)
      if (unit(rng) > 0.3) rings.push_back(at(2.0 + 8.0 * unit(rng) * unit(rng), a, -15.0 + 2.0 * ring));
  for (int i = 0; i < 20000; ++i)
    arc.push_back(at(1.0 + 12.0 * unit(rng), -40.0 + 80.0 * unit(rng), -12.0 + 24.0 * unit(rng)));
  for (const auto* cloud : {&rings, &arc}) {
    const RangeImage full(*cloud, RangeImageConfig{});
    const RangeImage lean = full.withoutWindows();
    EXPECT_LT(2 * lean.memoryBytes(), full.memoryBytes());
    int differ = 0, judged = 0;
    for (int i = 0; i < 200000; ++i) {
      const Eigen::Vector3d q = dir(0.3 + 14.0 * unit(rng), -180.0 + 360.0 * unit(rng), -25.0 + 50.0 * unit(rng));
      const Visibility v = full.classify(q);
      differ += lean.classify(q) != v;
      judged += v == Visibility::kFree || v == Visibility::kHit;
    }
    EXPECT_EQ(differ, 0);
    EXPECT_GT(judged, 1000);
  }
}

}  // namespace mmlio::map
