#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tuple>

#include "mmlio/estimator/feature_budget.hpp"

namespace mmlio::estimator {
namespace {

// Plane features on a 0.3 m grid over the floor (z = 0) and one wall (x = 0) of a hall, as a
// 0.3 m voxel filter leaves them; the wall's from LiDAR 1.
Features hallFeatures(double floor_m, double wall_m) {
  Features f;
  for (double x = 0.15; x < floor_m; x += 0.3)
    for (double y = 0.15; y < floor_m; y += 0.3) {
      f.planes.emplace_back(x, y, 0.0);
      f.plane_source.push_back(0);
    }
  for (double y = 0.15; y < wall_m; y += 0.3)
    for (double z = 0.15; z < 6.0; z += 0.3) {
      f.planes.emplace_back(0.0, y, z);
      f.plane_source.push_back(1);
    }
  for (int i = 0; i < 50; ++i) f.edges.emplace_back(0.0, 0.0, 0.1 * i);
  return f;
}

TEST(FeatureBudget, ASweepWithinTheBudgetKeepsEveryFeatureInOrder) {
  const Features f = hallFeatures(6.0, 6.0);  // 400 + 400 planes
  const Features t = thinToBudget(f, FeatureBudget{1000, 1000, 0.2, 0.3});
  EXPECT_EQ(t.planes, f.planes);
  EXPECT_EQ(t.plane_source, f.plane_source);
  EXPECT_EQ(t.edges, f.edges);
  EXPECT_EQ(thinToBudget(f, FeatureBudget{}).planes, f.planes) << "a budget of 0 is no limit";
}

TEST(FeatureBudget, ALargeSceneIsThinnedEvenlyToTheBudgetWithItsSources) {
  const Features f = hallFeatures(40.0, 40.0);  // 17689 floor + 2660 wall planes
  ASSERT_GT(f.planes.size(), 20000u);
  const Features t = thinToBudget(f, FeatureBudget{20, 3000, 0.2, 0.3});
  EXPECT_LE(t.planes.size(), 3000u);
  EXPECT_GT(t.planes.size(), 1500u) << "the grid grows by the excess, not far past the budget";
  EXPECT_LE(t.edges.size(), 20u);
  ASSERT_EQ(t.plane_source.size(), t.planes.size());
  // Kept features are features (not centroids of larger cells) with their own LiDAR.
  for (std::size_t i = 0; i < t.planes.size(); ++i) {
    const auto it = std::find(f.planes.begin(), f.planes.end(), t.planes[i]);
    ASSERT_NE(it, f.planes.end());
    EXPECT_EQ(t.plane_source[i], f.plane_source[it - f.planes.begin()]);
  }
  // Evenly over space: every 4 x 4 m tile of the floor and of the wall keeps features, so no
  // part of the scene (and no direction it constrains) is dropped.
  std::set<std::tuple<int, int, int>> tiles;
  for (const auto& p : t.planes)
    tiles.insert({p.z() == 0.0 ? 0 : 1, static_cast<int>(p.x() / 4 + p.z() / 4), static_cast<int>(p.y() / 4)});
  EXPECT_EQ(tiles.size(), 100u + 20u);
  const auto wall = std::count(t.plane_source.begin(), t.plane_source.end(), 1);
  EXPECT_GT(wall, 0.08 * t.planes.size()) << "the wall keeps about its share of the area (13 %)";
}

}  // namespace
}  // namespace mmlio::estimator
