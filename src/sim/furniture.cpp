#include "mmlio/sim/furniture.hpp"

#include <algorithm>
#include <cmath>

#include "mmlio/sim/random.hpp"

namespace mmlio::sim {
namespace {

constexpr std::uint64_t kFurnitureId = 6;
constexpr double kRouteClearanceM = 0.7;
constexpr double kStructureHeightM = 2.5;  // taller boxes are walls, pillars, storeys: they stay
constexpr std::uint64_t kDraws = 8;

bool isFurniture(const Box& b) {
  const Eigen::Vector3d size = b.hi - b.lo;
  return std::abs(b.lo.z()) < 0.01 && size.z() >= 0.3 && size.z() <= 2.1 && size.x() >= 0.3 && size.x() <= 1.6 &&
         size.y() >= 0.3 && size.y() <= 1.6;
}

/// Distance in x, y from p to the box's footprint (0 inside).
double footprintDistance(const Box& b, const Eigen::Vector2d& p) {
  const double dx = std::max({b.lo.x() - p.x(), 0.0, p.x() - b.hi.x()});
  const double dy = std::max({b.lo.y() - p.y(), 0.0, p.y() - b.hi.y()});
  return std::hypot(dx, dy);
}

bool footprintsOverlap(const Box& a, const Box& b) {
  return a.lo.x() < b.hi.x() && b.lo.x() < a.hi.x() && a.lo.y() < b.hi.y() && b.lo.y() < a.hi.y();
}

}  // namespace

std::size_t rearrangeFurniture(std::vector<Box>* boxes, const std::vector<Eigen::Vector2d>& route, std::uint64_t seed) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e9), hi = Eigen::Vector2d::Constant(-1e9);
  for (const Box& b : *boxes) {
    lo = lo.cwiseMin(b.lo.head<2>());
    hi = hi.cwiseMax(b.hi.head<2>());
  }
  std::size_t moved = 0;
  for (std::size_t i = 0; i < boxes->size(); ++i) {
    if (!isFurniture((*boxes)[i])) continue;
    for (std::uint64_t draw = 0; draw < kDraws; ++draw) {
      const double angle = 2.0 * M_PI * unitFromHash(hashKey(seed, kFurnitureId, i, 2 * draw));
      const double distance = 0.4 + 0.6 * unitFromHash(hashKey(seed, kFurnitureId, i, 2 * draw + 1));
      Box b = (*boxes)[i];
      const Eigen::Vector3d shift(distance * std::cos(angle), distance * std::sin(angle), 0.0);
      b.lo += shift;
      b.hi += shift;
      const bool inside =
          (b.lo.head<2>().array() > lo.array() + 0.1).all() && (b.hi.head<2>().array() < hi.array() - 0.1).all();
      const bool off_structure = std::none_of(boxes->begin(), boxes->end(), [&](const Box& other) {
        return other.hi.z() - other.lo.z() > kStructureHeightM && other.hi.z() > 0.05 && footprintsOverlap(b, other);
      });
      const bool clear = std::all_of(route.begin(), route.end(), [&](const Eigen::Vector2d& p) {
        return footprintDistance(b, p) >= kRouteClearanceM;
      });
      if (!inside || !off_structure || !clear) continue;
      (*boxes)[i] = b;
      ++moved;
      break;
    }
  }
  return moved;
}

}  // namespace mmlio::sim
