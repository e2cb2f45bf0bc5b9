#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "mmlio/core/floor_to.hpp"

namespace mmlio {
namespace {

TEST(FloorTo, EqualsStdFloorAtIntegersAroundThemAndOnBothSidesOfZero) {
  std::vector<double> values = {0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 1e-300, -1e-300, 2147483646.5, -2147483647.5};
  for (int i = -5; i <= 5; ++i)
    for (double v : {static_cast<double>(i), std::nextafter(i, -1e9), std::nextafter(i, 1e9)}) values.push_back(v);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> any(-1e6, 1e6);
  for (int k = 0; k < 10000; ++k) values.push_back(any(rng));
  for (double v : values) {
    EXPECT_EQ(floorTo<int>(v), static_cast<int>(std::floor(v))) << v;
    EXPECT_EQ(floorTo<std::int64_t>(v), static_cast<std::int64_t>(std::floor(v))) << v;
    EXPECT_EQ(floorTo<int>(static_cast<float>(v)), static_cast<int>(std::floor(static_cast<float>(v)))) << v;
  }
  EXPECT_EQ(floorTo<std::int64_t>(-4.0e15 - 0.5), -4000000000000001);
}

}  // namespace
}  // namespace mmlio
