#include "mmlio/backend/map_accumulator.hpp"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <limits>

#include "mmlio/core/voxel_key.hpp"

namespace mmlio::backend {
namespace {

// A voxel's output point, by MapAccumulator and mergeIntoVoxels alike (their results must agree
// bit for bit).
Point centroid(const Eigen::Vector3d& sum, double intensity_sum, std::uint32_t count) {
  Point p;
  p.xyz = (sum / count).cast<float>();
  p.intensity = static_cast<float>(intensity_sum / count);
  return p;
}

}  // namespace

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
  for (const Cell& c : cells_) out.push_back(centroid(c.sum, c.intensity, c.count));
  return out;
}

std::vector<Point> mergeIntoVoxels(const std::vector<PosedPoints>& clouds, double leaf_m) {
  std::vector<std::size_t> offset{0};  // of each cloud's first point in the concatenation
  for (const PosedPoints& c : clouds) offset.push_back(offset.back() + c.points->size());
  const std::size_t n = offset.back();
  // Runs are numbered and ordered in 32 bits each below: a larger map (100 GB of points) takes the hash.
  if (leaf_m <= 0.0 || n >= std::numeric_limits<std::uint32_t>::max()) {
    MapAccumulator map(leaf_m);
    for (const PosedPoints& c : clouds) map.add(*c.points, c.T_world_body);
    return map.points();
  }
  const auto worldPoint = [&](std::size_t cloud, std::size_t j) {
    return clouds[cloud].T_world_body * (*clouds[cloud].points)[j].xyz.cast<double>();
  };
  // Every point's voxel key, sorted by (key, input order): a voxel's points form a run, in the
  // order the accumulator would have summed them.
  struct Keyed {
    std::uint64_t key;
    std::uint32_t cloud, index;  // index within the cloud
    bool operator<(const Keyed& o) const {
      return key != o.key ? key < o.key : cloud != o.cloud ? cloud < o.cloud : index < o.index;
    }
  };
  std::vector<Keyed> keyed(n);
  for (std::size_t c = 0; c < clouds.size(); ++c)
    for (std::size_t j = 0; j < clouds[c].points->size(); ++j)
      keyed[offset[c] + j] = {voxelKeyOf(worldPoint(c, j), leaf_m), static_cast<std::uint32_t>(c),
                              static_cast<std::uint32_t>(j)};
  tbb::parallel_sort(keyed.begin(), keyed.end());  // (key, cloud, index) are unique: one order
  std::size_t runs = n > 0 ? 1 : 0;
  for (std::size_t i = 1; i < n; ++i) runs += keyed[i].key != keyed[i - 1].key;
  std::vector<Point> voxels;
  std::vector<std::uint64_t> first_hit;  // (input position of a voxel's first point) << 32 | voxel
  voxels.reserve(runs);
  first_hit.reserve(runs);
  for (std::size_t begin = 0; begin < n;) {
    std::size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double intensity = 0.0;
    for (; end < n && keyed[end].key == keyed[begin].key; ++end) {
      sum += worldPoint(keyed[end].cloud, keyed[end].index);
      intensity += (*clouds[keyed[end].cloud].points)[keyed[end].index].intensity;
    }
    first_hit.push_back(static_cast<std::uint64_t>(offset[keyed[begin].cloud] + keyed[begin].index) << 32 |
                        voxels.size());
    voxels.push_back(centroid(sum, intensity, static_cast<std::uint32_t>(end - begin)));
    begin = end;
  }
  keyed = {};
  tbb::parallel_sort(first_hit.begin(), first_hit.end());
  // voxels[i] <- voxels[first_hit[i]'s voxel], permuted in place cycle by cycle.
  constexpr std::uint64_t kPlaced = std::numeric_limits<std::uint64_t>::max();
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    if (first_hit[i] == kPlaced) continue;
    const Point start = voxels[i];
    std::size_t j = i;
    for (;;) {
      const std::size_t from = first_hit[j] & 0xFFFFFFFFu;
      first_hit[j] = kPlaced;
      if (from == i) {
        voxels[j] = start;
        break;
      }
      voxels[j] = voxels[from];
      j = from;
    }
  }
  return voxels;
}

}  // namespace mmlio::backend
