#include "mmlio/pipeline/map_accumulator.hpp"

#include <cmath>

#include "mmlio/core/voxel_key.hpp"

namespace mmlio::pipeline {
namespace {

std::uint64_t voxelKey(const Eigen::Vector3d& p, double leaf) {
  const auto idx = [leaf](double v) { return static_cast<std::int64_t>(std::floor(v / leaf)); };
  return packVoxelKey(idx(p.x()), idx(p.y()), idx(p.z()));
}

}  // namespace

MapAccumulator::MapAccumulator(double leaf_m) : leaf_m_(leaf_m) {}

void MapAccumulator::add(const std::vector<Point>& points_body, const Eigen::Isometry3d& T_world_body) {
  for (const Point& p : points_body) {
    const Eigen::Vector3d w = T_world_body * p.xyz.cast<double>();
    if (leaf_m_ <= 0.0) {
      Point q = p;
      q.xyz = w.cast<float>();
      raw_.push_back(q);
      continue;
    }
    const auto [index, added] = index_.insert(voxelKey(w, leaf_m_), static_cast<std::uint32_t>(cells_.size()));
    if (added) cells_.emplace_back();
    Cell& c = cells_[index];
    c.sum += w;
    c.intensity += p.intensity;
    ++c.count;
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
