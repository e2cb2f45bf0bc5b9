#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "mmlio/core/huge_page_allocator.hpp"

using mmlio::HugePageAllocator;

TEST(HugePageAllocator, LargeArraysStartOnAHugePageAndKeepTheirValuesAcrossGrowth) {
  std::vector<double, HugePageAllocator<double>> v;
  v.reserve(HugePageAllocator<double>::kHugePage / sizeof(double) + 1);  // just over 2 MiB
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % HugePageAllocator<double>::kHugePage, 0u);
  for (int i = 0; i < 1'000'000; ++i) v.push_back(0.5 * i);  // grows past the reservation
  for (int i = 0; i < 1'000'000; i += 9973) ASSERT_EQ(v[static_cast<std::size_t>(i)], 0.5 * i);
}

TEST(HugePageAllocator, SmallArraysAreOrdinaryAllocations) {
  std::vector<std::uint8_t, HugePageAllocator<std::uint8_t>> v(100, 7);
  EXPECT_EQ(v[99], 7);
  v.shrink_to_fit();
  v.clear();
  v.shrink_to_fit();  // small deallocations go back where they came from (ASan / valgrind clean)
  EXPECT_TRUE(v.empty());
}
