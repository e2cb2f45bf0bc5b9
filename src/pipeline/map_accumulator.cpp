#include "mmlio/pipeline/map_accumulator.hpp"

#include <algorithm>

#include "mmlio/core/voxel_key.hpp"

namespace mmlio::pipeline {

MapAccumulator::MapAccumulator(double leaf_m) : leaf_m_(leaf_m) {}

void MapAccumulator::add(const std::vector<Point>& points_body, const Eigen::Isometry3d& T_world_body) {
  if (leaf_m_ <= 0.0) {
    for (const Point& p : points_body) {
      Point q = p;
      q.xyz = (T_world_body * p.xyz.cast<double>()).cast<float>();
      raw_.push_back(q);
    }
    return;
  }
  // Keys are computed (and their slots prefetched) a block ahead of the inserts: the index of a
  // keyframe's submap outgrows the cache, and consecutive returns land in unrelated slots.
  constexpr std::size_t kBlock = 16;
  Eigen::Vector3d world[kBlock];
  std::uint64_t keys[kBlock];
  for (std::size_t begin = 0; begin < points_body.size(); begin += kBlock) {
    const std::size_t n = std::min(kBlock, points_body.size() - begin);
    for (std::size_t j = 0; j < n; ++j) {
      world[j] = T_world_body * points_body[begin + j].xyz.cast<double>();
      keys[j] = voxelKeyOf(world[j], leaf_m_);
      index_.prefetch(keys[j]);
    }
    for (std::size_t j = 0; j < n; ++j) {
      const auto [index, added] = index_.insert(keys[j], static_cast<std::uint32_t>(cells_.size()));
      if (added) cells_.emplace_back();
      Cell& c = cells_[index];
      c.sum += world[j];
      c.intensity += points_body[begin + j].intensity;
      ++c.count;
    }
  }
}

void MapAccumulator::clear() {
  cells_.clear();
  index_.reset();
  raw_.clear();
}

std::size_t MapAccumulator::size() const { return leaf_m_ <= 0.0 ? raw_.size() : cells_.size(); }

std::vector<Point> MapAccumulator::points() const {
  if (leaf_m_ <= 0.0) return raw_;
  std::vector<Point> out;
  out.reserve(cells_.size());
  for (const Cell& c : cells_) {
    Point p;
    p.xyz = (c.sum / c.count).cast<float>();
    p.intensity = static_cast<float>(c.intensity / c.count);
    out.push_back(p);
  }
  return out;
}

}  // namespace mmlio::pipeline
