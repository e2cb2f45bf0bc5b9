#include "mmlio/map/voxel_hash_map.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "mmlio/core/floor_to.hpp"
#include "mmlio/core/voxel_key.hpp"
#include "mmlio/map/geometry_fit.hpp"

namespace mmlio::map {

VoxelHashMap::VoxelHashMap(double voxel_m, int max_points_per_voxel, bool fit_planes)
    : voxel_m_(voxel_m > 0 ? voxel_m : 1.0),
      inv_voxel_(1.0 / voxel_m_),
      max_points_per_voxel_(std::max(1, max_points_per_voxel)),
      fit_planes_(fit_planes) {}

VoxelHashMap::Key VoxelHashMap::keyOf(const Eigen::Vector3d& p) const {
  return Key{floorTo<int>(p.x() * inv_voxel_), floorTo<int>(p.y() * inv_voxel_), floorTo<int>(p.z() * inv_voxel_)};
}

std::uint64_t VoxelHashMap::brickKey(const Key& k) {
  // Arithmetic shifts: floor division by the brick size for negative keys too.
  return packVoxelKey(k.x >> kBrickShift, k.y >> kBrickShift, k.z >> kBrickShift);
}

std::pair<std::uint32_t, bool> VoxelHashMap::findOrAdd(const Key& k) {
  const auto [b, new_brick] = brick_index_.insert(brickKey(k), static_cast<std::uint32_t>(bricks_.size()));
  if (new_brick) {
    bricks_.emplace_back();
    bricks_.back().fill(kNone);
  }
  std::uint32_t& slot = bricks_[b][slotInBrick(k)];
  if (slot != kNone) return {slot, false};
  slot = static_cast<std::uint32_t>(voxels_.size());
  Voxel voxel;
  voxel.key = k;
  voxels_.push_back(voxel);
  return {slot, true};
}

void VoxelHashMap::rebuildIndex() {
  std::vector<Voxel> kept;
  kept.reserve(voxels_.size());
  for (const Voxel& v : voxels_)
    if (v.count > 0) kept.push_back(v);
  voxels_.clear();
  bricks_.clear();
  brick_index_.clear();
  for (const Voxel& v : kept) {
    findOrAdd(v.key);
    voxels_.back() = v;
  }
}

void VoxelHashMap::compactBrickByBrick() {
  // A little room in each span: the next keyframe adds a point or two to most voxels it sees.
  constexpr std::uint32_t kSlack = 4;
  const auto max_points = static_cast<std::uint32_t>(max_points_per_voxel_);
  // The previous arena's buffer is reused: a fresh one of this size page-faults for milliseconds.
  Arena arena = std::move(spare_);
  arena.clear();
  // Room for the spans that move to the end before the next rewrite, without reallocating; a
  // growing map gets twice that, so that fresh memory (page faults) is taken now and then.
  const std::size_t needed = num_points_ + kSlack * voxels_.size();
  if (arena.capacity() < needed + needed / 2) arena.reserve(2 * needed);
  std::vector<Voxel> ordered;
  ordered.reserve(voxels_.size());
  for (Brick& brick : bricks_) {
    for (std::uint32_t& slot : brick) {
      if (slot == kNone) continue;
      Voxel v = voxels_[slot];
      const Eigen::Vector3d* from = pointsOf(v);
      v.begin = static_cast<std::uint32_t>(arena.size());
      v.capacity = std::min(max_points, v.count + kSlack);
      arena.insert(arena.end(), from, from + v.count);
      arena.resize(arena.size() + (v.capacity - v.count));
      slot = static_cast<std::uint32_t>(ordered.size());
      ordered.push_back(v);
    }
  }
  voxels_ = std::move(ordered);
  spare_ = std::move(points_);
  points_ = std::move(arena);
}

void VoxelHashMap::add(const std::vector<Eigen::Vector3d>& world_points) {
  const auto max_points = static_cast<std::uint32_t>(max_points_per_voxel_);
  for (const auto& p : world_points) {
    if (!p.allFinite()) continue;
    Voxel& v = voxels_[findOrAdd(keyOf(p)).first];
    if (v.count >= max_points) continue;
    if (v.count == v.capacity) {
      // Full span: the voxel moves to the arena's end with twice the room (its old span is
      // reclaimed when the arena is rewritten below).
      const std::uint32_t capacity = std::min(max_points, std::max<std::uint32_t>(4, 2 * v.capacity));
      const auto begin = static_cast<std::uint32_t>(points_.size());
      points_.resize(points_.size() + capacity);
      std::copy(points_.begin() + v.begin, points_.begin() + v.begin + v.count, points_.begin() + begin);
      v.begin = begin;
      v.capacity = capacity;
    }
    points_[v.begin + v.count++] = p;
    v.plane = Voxel::Plane::kStale;
    ++num_points_;
  }
  // Rewritten once a third of it holds no point (spans moved away, removed points, room to grow):
  // the spans of voxels that grew sit at the end until then.
  if (3 * (points_.size() - num_points_) > points_.size()) compactBrickByBrick();
}

void VoxelHashMap::removeFarFrom(const Eigen::Vector3d& center, double radius_m) {
  const double r2 = radius_m * radius_m;
  bool removed = false;
  for (Voxel& v : voxels_) {
    if (v.count > 0 && (*pointsOf(v) - center).squaredNorm() <= r2) continue;
    num_points_ -= v.count;
    v.count = 0;
    removed = true;
  }
  if (removed) rebuildIndex();
}

std::size_t VoxelHashMap::removeIf(const Eigen::Vector3d& center, double radius_m,
                                   const std::function<bool(const Eigen::Vector3d&)>& remove,
                                   std::vector<Eigen::Vector3d>* removed_points) {
  const double reach = radius_m + std::sqrt(3.0) * voxel_m_;
  std::vector<Voxel*> near;
  for (Voxel& v : voxels_)
    if (v.count > 0 && (*pointsOf(v) - center).squaredNorm() <= reach * reach) near.push_back(&v);
  std::vector<std::vector<Eigen::Vector3d>> removed(near.size());
  const double r2 = radius_m * radius_m;
  tbb::parallel_for(std::size_t(0), near.size(), [&](std::size_t i) {
    Voxel& v = *near[i];
    Eigen::Vector3d* points = pointsOf(v);
    std::uint32_t kept = 0;
    for (std::uint32_t j = 0; j < v.count; ++j) {
      const Eigen::Vector3d& p = points[j];
      if ((p - center).squaredNorm() <= r2 && remove(p))
        removed[i].push_back(p);
      else
        points[kept++] = p;
    }
    if (kept != v.count) v.plane = Voxel::Plane::kStale;
    v.count = kept;
  });
  std::size_t total = 0;
  for (const auto& r : removed) {
    total += r.size();
    if (removed_points) removed_points->insert(removed_points->end(), r.begin(), r.end());
  }
  if (total == 0) return 0;
  num_points_ -= total;
  rebuildIndex();
  return total;
}

int VoxelHashMap::knn(const Eigen::Vector3d& q, int k, double max_dist_m, std::vector<Eigen::Vector3d>* out) const {
  out->clear();
  if (k <= 0 || voxels_.empty() || max_dist_m <= 0) return 0;
  const double max_d2 = max_dist_m * max_dist_m;
  const Key c = keyOf(q);
  // The k best candidates (squared distance, point), nearest first. k is small (5 for a plane fit):
  // shifting a sorted array costs less than keeping a heap. The storage is reused per thread (a
  // query allocates nothing: queries run millions of times per run); the count and the bound live
  // in locals, so the per-point test is one comparison against a register.
  thread_local std::vector<std::pair<double, const Eigen::Vector3d*>> storage;
  if (storage.size() < static_cast<std::size_t>(k)) storage.resize(static_cast<std::size_t>(k));
  std::pair<double, const Eigen::Vector3d*>* const best = storage.data();
  int found = 0;
  // A candidate must come nearer than `bound`: within max_dist_m until k are found (the next
  // double above max_d2, so a point at exactly max_dist_m still counts), then nearer than the k-th.
  double bound = std::nextafter(max_d2, std::numeric_limits<double>::infinity());
  const auto full = [&] { return found == k; };
  const auto visit = [&](const Voxel& v) {
    const Eigen::Vector3d* points = pointsOf(v);
    for (std::uint32_t j = 0; j < v.count; ++j) {
      const Eigen::Vector3d& p = points[j];
      const double d2 = (p - q).squaredNorm();
      if (d2 >= bound) continue;
      int i = found < k ? found++ : k - 1;
      for (; i > 0 && best[i - 1].first > d2; --i) best[i] = best[i - 1];
      best[i] = {d2, &p};
      if (found == k) bound = best[k - 1].first;
    }
  };
  // After scanning Chebyshev rings 0..r, every unscanned point is at least r voxels away from q.
  const double rings = std::ceil(max_dist_m * inv_voxel_);
  const double cube = std::pow(2.0 * rings + 1.0, 3);
  if (cube > 4.0 * static_cast<double>(voxels_.size())) {
    // The search cube holds more cells than the map has voxels: scanning the map is cheaper.
    for (const Voxel& v : voxels_) visit(v);
  } else {
    const int max_ring = std::max(1, static_cast<int>(rings));
    const int side = 2 * max_ring + 1;
    // Per axis, once per query: the squared distance from q to the cells `offset` from its own
    // (index offset + max_ring), and which of the cube's bricks each lies in.
    thread_local std::vector<double> gaps;
    thread_local std::vector<int> brick_of;
    gaps.resize(3 * static_cast<std::size_t>(side));
    brick_of.resize(3 * static_cast<std::size_t>(side));
    const int cell[3] = {c.x, c.y, c.z};
    int first_brick[3];
    double to_own_faces = voxel_m_;  // q's distance to the nearest face of its own voxel
    for (int a = 0; a < 3; ++a) {
      const double lower = cell[a] * voxel_m_;
      to_own_faces = std::min({to_own_faces, q[a] - lower, lower + voxel_m_ - q[a]});
      first_brick[a] = (cell[a] - max_ring) >> kBrickShift;
      for (int offset = -max_ring; offset <= max_ring; ++offset) {
        double gap = 0.0;
        if (offset != 0) {
          const double face = (offset > 0 ? cell[a] + offset : cell[a] + offset + 1) * voxel_m_;
          const double d = offset > 0 ? face - q[a] : q[a] - face;
          gap = d * d;
        }
        const std::size_t at = static_cast<std::size_t>(a * side + offset + max_ring);
        gaps[at] = gap;
        brick_of[at] = ((cell[a] + offset) >> kBrickShift) - first_brick[a];
      }
    }
    to_own_faces = std::max(to_own_faces, 0.0);
    const double* const gx = gaps.data() + max_ring;
    const double* const gy = gx + side;
    const double* const gz = gy + side;
    const int* const bx = brick_of.data() + max_ring;
    const int* const by = bx + side;
    const int* const bz = by + side;
    // The bricks the cube reaches, each looked up in the hash at most once per query.
    const int bricks_per_axis = ((max_ring * 2) >> kBrickShift) + 2;
    thread_local std::vector<const Brick*> bricks;
    thread_local std::vector<char> looked_up;
    const auto n_bricks = static_cast<std::size_t>(bricks_per_axis * bricks_per_axis * bricks_per_axis);
    bricks.resize(n_bricks);
    looked_up.assign(n_bricks, 0);
    const auto brickAt = [&](int ix, int iy, int iz) {
      const auto at = static_cast<std::size_t>((ix * bricks_per_axis + iy) * bricks_per_axis + iz);
      if (!looked_up[at]) {
        looked_up[at] = 1;
        const std::uint32_t b =
            brick_index_.find(packVoxelKey(first_brick[0] + ix, first_brick[1] + iy, first_brick[2] + iz));
        bricks[at] = b == kNone ? nullptr : &bricks_[b];
      }
      return bricks[at];
    };
    for (int r = 0; r <= max_ring; ++r) {
      for (int dx = -r; dx <= r; ++dx) {
        // A voxel that cannot hold a point nearer than the bound is not looked up; the bound only
        // shrinks, so a slab or row already beyond it is left whole.
        if (gx[dx] >= bound) continue;
        for (int dy = -r; dy <= r; ++dy) {
          const double gxy = gx[dx] + gy[dy];
          if (gxy >= bound) continue;
          // The shell of ring r only: a column (dx, dy) off the shell's sides holds just its two
          // cells dz = -r and dz = r.
          const bool face = std::abs(dx) == r || std::abs(dy) == r;
          const int dz_step = face || r == 0 ? 1 : 2 * r;
          for (int dz = -r; dz <= r; dz += dz_step) {
            if (gxy + gz[dz] >= bound) continue;
            const Brick* brick = brickAt(bx[dx], by[dy], bz[dz]);
            if (!brick) continue;
            const std::uint32_t v = (*brick)[slotInBrick(Key{c.x + dx, c.y + dy, c.z + dz})];
            if (v != kNone) visit(voxels_[v]);
          }
        }
      }
      // Every unscanned point lies outside the cube of rings 0..r: at least r voxels plus q's
      // distance to the nearest face of its own voxel away.
      if (full()) {
        const double covered = r * voxel_m_ + to_own_faces;
        if (bound <= covered * covered) break;
      }
    }
  }
  out->reserve(static_cast<std::size_t>(found));
  for (int i = 0; i < found; ++i) out->push_back(*best[i].second);
  return static_cast<int>(out->size());
}

const VoxelHashMap::VoxelPlane* VoxelHashMap::planeAt(const Eigen::Vector3d& q) const {
  if (!fit_planes_) return nullptr;
  const Key k = keyOf(q);
  const std::uint32_t b = brick_index_.find(brickKey(k));
  if (b == kNone) return nullptr;
  const std::uint32_t v = bricks_[b][slotInBrick(k)];
  if (v == kNone || voxels_[v].plane != Voxel::Plane::kFitted) return nullptr;
  return &voxels_[v].fit;
}

void VoxelHashMap::refitPlanes() {
  if (!fit_planes_) return;
  std::vector<Eigen::Vector3d> pts;
  for (Voxel& v : voxels_) {
    if (v.plane != Voxel::Plane::kStale) continue;
    v.plane = Voxel::Plane::kNone;
    if (v.count < kPlaneMinPoints) continue;
    pts.assign(pointsOf(v), pointsOf(v) + v.count);
    const PlaneFit fit = fitPlane(pts, kPlaneMaxResidualM);
    if (!fit.ok) continue;
    v.fit = {fit.normal, fit.d};
    v.plane = Voxel::Plane::kFitted;
  }
}

void VoxelHashMap::clear() {
  voxels_.clear();
  points_.clear();
  bricks_.clear();
  brick_index_.clear();
  num_points_ = 0;
}

std::vector<Eigen::Vector3d> VoxelHashMap::points() const {
  std::vector<Eigen::Vector3d> all;
  all.reserve(num_points_);
  for (const Voxel& v : voxels_) all.insert(all.end(), pointsOf(v), pointsOf(v) + v.count);
  return all;
}

}  // namespace mmlio::map
