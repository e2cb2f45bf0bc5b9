#include "mmlio/estimator/free_space.hpp"

#include <tbb/parallel_for.h>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"

namespace mmlio::estimator {

void SweepView::place(const Eigen::Isometry3d& T_world_body) {
  for (SensorView& s : sensors) s.T_sensor_world = (T_world_body * s.T_body_sensor).inverse();
}

bool SweepView::seesThrough(const Eigen::Vector3d& p_world) const {
  for (const SensorView& s : sensors)
    if (s.image.classify(s.T_sensor_world * p_world) == map::Visibility::kFree) return true;
  return false;
}

std::size_t SweepView::memoryBytes() const {
  std::size_t n = sizeof(*this);
  for (const SensorView& s : sensors) n += sizeof(s) + s.image.memoryBytes();
  return n;
}

bool moverFound(const std::vector<Eigen::Vector3d>& world_points, const std::vector<std::uint8_t>& moved) {
  FlatKeyIndex cells;  // 1 m cell -> count
  std::vector<int> counts;
  for (std::size_t i = 0; i < moved.size() && i < world_points.size(); ++i) {
    if (!moved[i]) continue;
    const auto [c, added] = cells.insert(voxelKeyOf(world_points[i], 1.0), static_cast<std::uint32_t>(counts.size()));
    if (added) counts.push_back(0);
    if (++counts[c] >= kMoverReturns) return true;
  }
  return false;
}

bool MoverWatch::shouldJudge(Stamp now) const {
  if (cfg_.quiet_interval_s <= 0 || now <= movers_until_ns_) return true;
  return last_judged_ns_ == std::numeric_limits<Stamp>::min() || now < last_judged_ns_ ||
         toSec(now - last_judged_ns_) >= cfg_.quiet_interval_s - 0.005;  // sweep stamps jitter
}

void MoverWatch::judged(Stamp now, bool mover_found) {
  last_judged_ns_ = now;
  if (mover_found) movers_until_ns_ = now + fromSec(cfg_.hold_s);
}

void FreeSpaceMemory::remember(std::shared_ptr<const SweepView> view) {
  views_.push_back(std::move(view));
  while (views_.size() > 1 && toSec(views_.back()->stamp_ns - views_.front()->stamp_ns) > cfg_.look_back_max_s + 0.2)
    views_.pop_front();
}

std::vector<std::uint8_t> FreeSpaceMemory::movedIn(const std::vector<Eigen::Vector3d>& points, Stamp now) const {
  std::vector<std::uint8_t> flags(points.size(), 0);
  std::vector<const SweepView*> asked;
  for (const auto& v : views_) {  // oldest first
    const double age = toSec(now - v->stamp_ns);
    if (age >= cfg_.look_back_min_s && age <= cfg_.look_back_max_s) asked.push_back(v.get());
  }
  if (asked.size() > 2) asked = {asked.front(), asked.back()};
  if (asked.empty()) return flags;
  // Seen through by one of them and seen on by none: a point on a silhouette edge, which one view
  // may see past by a hair, is seen on by the other.
  // One sensor seeing a surface there settles it (most points: static ones), so the rest are not asked.
  const auto moved = [&](const Eigen::Vector3d& p) {
    bool free = false;
    for (const SweepView* v : asked)
      for (const SensorView& s : v->sensors) {
        const map::Visibility seen = s.image.classify(s.T_sensor_world * p);
        if (seen == map::Visibility::kHit) return false;
        free = free || seen == map::Visibility::kFree;
      }
    return free;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) flags[i] = moved(points[i]) ? 1 : 0;
                    });
  return flags;
}

}  // namespace mmlio::estimator
