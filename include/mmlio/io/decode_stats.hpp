#pragma once
// Counts of LiDAR points kept and dropped while decoding (ROS-free, shared by cloud_decoders.hpp
// and bag_source.hpp).
#include <cstddef>

namespace mmlio::io {

struct DecodeStats {
  std::size_t kept = 0;
  std::size_t dropped_nan = 0;    // x, y, z or time not finite
  std::size_t dropped_zero = 0;   // x = y = z = 0 (no return)
  std::size_t dropped_range = 0;  // range outside [min_range_m, max_range_m]
  void add(const DecodeStats& other);
  std::size_t total() const { return kept + dropped_nan + dropped_zero + dropped_range; }
};

}  // namespace mmlio::io
