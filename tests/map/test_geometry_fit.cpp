#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "mmlio/map/geometry_fit.hpp"

using namespace mmlio::map;

TEST(GeometryFit, PlaneThroughNoisySamplesRecoversNormalAndOffset) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
  const double d = -2.0;  // n.x = 2
  const Eigen::Vector3d a = n.unitOrthogonal(), b = n.cross(a);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 50; ++i) pts.push_back(-d * n + u(rng) * a + u(rng) * b + noise(rng) * n);
  const PlaneFit fit = fitPlane(pts, 0.05);
  ASSERT_TRUE(fit.ok);
  const double sign = fit.normal.dot(n) > 0 ? 1.0 : -1.0;
  EXPECT_NEAR((sign * fit.normal - n).norm(), 0.0, 0.01);
  EXPECT_NEAR(sign * fit.d, d, 0.01);
  EXPECT_LT(fit.max_residual_m, 0.03);
}

TEST(GeometryFit, PlaneIsRejectedWhenAPointIsOffItOrThePointsAreCollinear) {
  std::vector<Eigen::Vector3d> pts{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.5, 0.5}};
  EXPECT_FALSE(fitPlane(pts, 0.1).ok);
  EXPECT_FALSE(fitPlane({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, 0.1).ok);
  EXPECT_FALSE(fitPlane({{0, 0, 0}, {1, 0, 0}}, 0.1).ok);
}

TEST(GeometryFit, LineThroughNoisySamplesRecoversDirection) {
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::Vector3d dir = Eigen::Vector3d(0, 1, 1).normalized(), p0(1, 2, 3);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 20; ++i)
    pts.push_back(p0 + (i * 0.1 - 1.0) * dir + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  const LineFit fit = fitLine(pts);
  ASSERT_TRUE(fit.ok);
  EXPECT_GT(std::abs(fit.direction.dot(dir)), 0.999);
  // The fitted point lies on the true line.
  const Eigen::Vector3d off = fit.point - p0;
  EXPECT_LT((off - off.dot(dir) * dir).norm(), 0.01);
}

TEST(GeometryFit, LineIsRejectedForARoundBlob) {
  std::vector<Eigen::Vector3d> pts{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  EXPECT_FALSE(fitLine(pts).ok);
}

TEST(GeometryFit, LineIsRejectedForNeighboursOnTwoParallelStairNosings) {
  // Five nearest edge points on two nosings of a staircase (0.28 m treads, 0.167 m risers): the
  // cloud is elongated along the nosings, but its axis runs between them, on neither.
  const std::vector<Eigen::Vector3d> pts{{0, 0, 0}, {0, 0.5, 0}, {0, 1.0, 0}, {0.28, 0.25, 0.167}, {0.28, 0.75, 0.167}};
  const LineFit loose = fitLine(pts);
  EXPECT_TRUE(loose.ok);
  EXPECT_NEAR(loose.max_residual_m, 0.6 * std::hypot(0.28, 0.167), 0.02);  // the axis splits them 3:2
  EXPECT_FALSE(fitLine(pts, 3.0, 0.1).ok);
  // One nosing alone, with 1 cm noise, passes the same tolerance.
  const std::vector<Eigen::Vector3d> one{{0, 0, 0.01}, {0, 0.3, -0.01}, {0.01, 0.6, 0}, {0, 0.9, 0.005}, {0, 1.2, 0}};
  EXPECT_TRUE(fitLine(one, 3.0, 0.1).ok);
}

TEST(GeometryFit, PlaneIsRejectedForOneNoisyRingLine) {
  // Five neighbours from one LiDAR ring on a floor: a 1 m line with 1.5 cm range noise. Any plane
  // containing the line fits them, so the fitted normal says nothing about tilt.
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.015);
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 5; ++i) line.push_back({0.25 * i, noise(rng), noise(rng)});
  EXPECT_FALSE(fitPlane(line, 0.1).ok);
  // The same points with two rows 0.3 m apart form a patch and are accepted.
  std::vector<Eigen::Vector3d> patch = line;
  for (int i = 0; i < 4; ++i) patch.push_back({0.25 * i + 0.1, 0.3 + noise(rng), noise(rng)});
  EXPECT_TRUE(fitPlane(patch, 0.1).ok);
  EXPECT_TRUE(fitPlane(line, 0.1, 0.0).ok);  // without the spread test the line passes
}
