#include "mmlio/lidar/voxel_filter.hpp"

#include <cstdint>
#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"

namespace mmlio::lidar {
namespace {

struct Accumulator {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double intensity_sum = 0.0;
  int count = 0;
};

}  // namespace

std::vector<Point> voxelDownsample(const std::vector<Point>& pts, double leaf_m) {
  if (leaf_m <= 0.0) return pts;
  const double inv_leaf = 1.0 / leaf_m;
  thread_local FlatKeyIndex slot_of_key;  // every sweep's filter needs about the same size
  slot_of_key.reset();
  std::vector<Point> out;
  thread_local std::vector<Accumulator> acc;
  acc.clear();
  for (const Point& p : pts) {
    if (!p.xyz.allFinite()) continue;
    const auto [slot, inserted] =
        slot_of_key.insert(scaledVoxelKeyOf(p.xyz.cast<double>(), inv_leaf), static_cast<std::uint32_t>(out.size()));
    if (inserted) {
      out.push_back(p);
      acc.emplace_back();
    }
    Accumulator& a = acc[slot];
    a.sum += p.xyz.cast<double>();
    a.intensity_sum += p.intensity;
    ++a.count;
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i].xyz = (acc[i].sum / acc[i].count).cast<float>();
    out[i].intensity = static_cast<float>(acc[i].intensity_sum / acc[i].count);
  }
  return out;
}

}  // namespace mmlio::lidar
