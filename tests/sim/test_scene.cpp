#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mmlio/sim/scenarios.hpp"
#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {
namespace {

TEST(RayBox, RayAlongXHitsTheNearFaceAtTheKnownDistance) {
  const Box b{{2, -1, -1}, {3, 1, 1}, 100};
  EXPECT_DOUBLE_EQ(rayBox({0, 0, 0}, {1, 0, 0}, b), 2.0);
  const Eigen::Vector3d d = Eigen::Vector3d(1, 0.2, 0).normalized();
  EXPECT_NEAR(rayBox({0, 0, 0}, d, b), 2.0 / d.x(), 1e-12);
}

TEST(RayBox, MissesBehindBesideAndFromInside) {
  const Box b{{2, -1, -1}, {3, 1, 1}, 100};
  EXPECT_TRUE(std::isinf(rayBox({0, 0, 0}, {-1, 0, 0}, b)));   // box behind
  EXPECT_TRUE(std::isinf(rayBox({0, 1.5, 0}, {1, 0, 0}, b)));  // parallel, beside
  EXPECT_TRUE(std::isinf(rayBox({2.5, 0, 0}, {1, 0, 0}, b)));  // starts inside
  EXPECT_TRUE(std::isinf(rayBox({0, 0, 0}, Eigen::Vector3d(1, 1, 0).normalized(), b)));
}

TEST(Scene, GridCastEqualsBruteForceOnRandomRaysInTheHall) {
  const Scenario s = makeScenario("hall");
  const Scene scene(s.boxes);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-10, 120), uy(1, 34), uz(0.5, 3), ud(-1, 1);
  int hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d o(ux(rng), uy(rng), uz(rng));
    Eigen::Vector3d d(ud(rng), ud(rng), 0.3 * ud(rng));
    if (i % 100 == 0) d = Eigen::Vector3d(0, 0, 1);  // vertical rays too
    d.normalize();
    const RayHit a = scene.cast(o, d, 100.0), b = scene.castBruteForce(o, d, 100.0);
    ASSERT_EQ(a.box < 0, b.box < 0) << i;
    if (a.box >= 0) {
      ++hits;
      EXPECT_NEAR(a.range_m, b.range_m, 1e-9) << i;
    }
  }
  EXPECT_GT(hits, 2000);
}

TEST(Scene, DistanceToSurfaceOfAPointOnAFaceIsZeroAndOutsideIsEuclidean) {
  const Scene scene({Box{{0, 0, 0}, {1, 1, 1}, 10}});
  EXPECT_NEAR(scene.distanceToSurface({1.0, 0.5, 0.5}), 0.0, 1e-12);
  EXPECT_NEAR(scene.distanceToSurface({2.0, 2.0, 0.5}), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(scene.distanceToSurface({0.9, 0.5, 0.5}), 0.1, 1e-12);
}

TEST(Scenarios, UnknownNameListsTheValidOnes) {
  try {
    makeScenario("garage");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("office, corridor, corridor_blind, hall"), std::string::npos);
  }
}

TEST(Scenarios, HaveTheAdvertisedSize) {
  for (const auto& [name, x, y, z] : {std::tuple<std::string, double, double, double>{"office", 12, 3.7, 2.8},
                                      {"corridor", 60, 2.4, 2.8},
                                      {"hall", 127, 35, 8}}) {
    const Scenario s = makeScenario(name);
    const Scene scene(s.boxes);
    const Eigen::Vector3d size = scene.hi() - scene.lo();
    EXPECT_GE(size.x(), x) << name;
    EXPECT_GE(size.y(), y) << name;
    EXPECT_GE(size.z(), z) << name;
    EXPECT_LT(size.z(), z + 1.0) << name;
  }
}

}  // namespace
}  // namespace mmlio::sim
