#include "mmlio/pipeline/map_accumulator.hpp"

#include <cmath>

namespace mmlio::pipeline {
namespace {

// 21 bits per axis: +-1e6 voxels, i.e. +-20 km at 2 cm.
std::uint64_t voxelKey(const Eigen::Vector3d& p, double leaf) {
  auto axis = [leaf](double v) {
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / leaf)) + (1 << 20)) &
           0x1FFFFFu;
  };
  return (axis(p.x()) << 42) | (axis(p.y()) << 21) | axis(p.z());
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
    Cell& c = cells_[voxelKey(w, leaf_m_)];
    c.sum += w;
    c.intensity += p.intensity;
    ++c.count;
  }
}

std::size_t MapAccumulator::size() const { return leaf_m_ <= 0.0 ? raw_.size() : cells_.size(); }

std::vector<Point> MapAccumulator::points() const {
  if (leaf_m_ <= 0.0) return raw_;
  std::vector<Point> out;
  out.reserve(cells_.size());
  for (const auto& [key, c] : cells_) {
    Point p;
    p.xyz = (c.sum / c.count).cast<float>();
    p.intensity = static_cast<float>(c.intensity / c.count);
    out.push_back(p);
  }
  return out;
}

}  // namespace mmlio::pipeline
