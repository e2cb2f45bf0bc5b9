#pragma once
// Test helper: PointCloud2 messages with chosen fields and known bytes (decoder and bag tests).
#include <gtest/gtest.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstring>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::io {

using PF = sensor_msgs::PointField;

struct FieldSpec {
  std::string name;
  std::uint8_t type;
};

inline std::size_t sizeOf(std::uint8_t t) {
  switch (t) {
    case PF::INT8:
    case PF::UINT8:
      return 1;
    case PF::INT16:
    case PF::UINT16:
      return 2;
    case PF::FLOAT64:
      return 8;
    default:
      return 4;
  }
}

/// An unorganised little-endian cloud of n points with packed fields (plus 3 padding bytes per point).
inline sensor_msgs::PointCloud2 makeCloud(const std::vector<FieldSpec>& specs, Stamp stamp_ns, std::size_t n) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp.fromNSec(static_cast<std::uint64_t>(stamp_ns));
  std::uint32_t off = 0;
  for (const FieldSpec& s : specs) {
    PF f;
    f.name = s.name;
    f.offset = off;
    f.datatype = s.type;
    f.count = 1;
    c.fields.push_back(f);
    off += static_cast<std::uint32_t>(sizeOf(s.type));
  }
  c.point_step = off + 3;
  c.height = 1;
  c.width = static_cast<std::uint32_t>(n);
  c.row_step = c.point_step * c.width;
  c.data.assign(c.row_step, 0);
  return c;
}

template <typename T> void put(sensor_msgs::PointCloud2& c, std::size_t i, const std::string& name, T v) {
  for (const PF& f : c.fields) {
    if (f.name == name) {
      ASSERT_EQ(sizeof(T), sizeOf(f.datatype)) << name;
      std::memcpy(c.data.data() + i * c.point_step + f.offset, &v, sizeof(T));
      return;
    }
  }
  FAIL() << "no field " << name;
}

inline void putXyz(sensor_msgs::PointCloud2& c, std::size_t i, float x, float y, float z) {
  put(c, i, "x", x);
  put(c, i, "y", y);
  put(c, i, "z", z);
}

}  // namespace mmlio::io
