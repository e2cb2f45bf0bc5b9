#include "mmlio/sim/scene.hpp"

#include <algorithm>
#include <cmath>

namespace mmlio::sim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Entry distance and entry face axis of the slab test; t = +inf on a miss.
inline double slab(const Eigen::Vector3d& o, const Eigen::Vector3d& inv_d, const Box& b, double min_t, int& axis) {
  double t0 = -kInf, t1 = kInf;
  axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (std::isinf(inv_d[a])) {  // parallel to the slab: inside it or a miss
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return kInf;
      continue;
    }
    double ta = (b.lo[a] - o[a]) * inv_d[a], tb = (b.hi[a] - o[a]) * inv_d[a];
    if (ta > tb) std::swap(ta, tb);
    if (ta > t0) {
      t0 = ta;
      axis = a;
    }
    t1 = std::min(t1, tb);
    if (t0 > t1) return kInf;
  }
  return t0 > min_t ? t0 : kInf;
}

inline Eigen::Vector3d inverse(const Eigen::Vector3d& d) {
  Eigen::Vector3d inv;
  for (int a = 0; a < 3; ++a) inv[a] = d[a] == 0.0 ? kInf : 1.0 / d[a];
  return inv;
}
}  // namespace

double rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b, double min_t) {
  int axis;
  return slab(o, inverse(d), b, min_t, axis);
}

Scene::Scene(std::vector<Box> boxes, SceneConfig config) : boxes_(std::move(boxes)), config_(config) {
  if (boxes_.empty()) return;
  lo_ = boxes_[0].lo;
  hi_ = boxes_[0].hi;
  for (const Box& b : boxes_) {
    lo_ = lo_.cwiseMin(b.lo);
    hi_ = hi_.cwiseMax(b.hi);
  }
  const double c = config_.cell_size_m;
  nx_ = std::max(1, static_cast<int>(std::ceil((hi_.x() - lo_.x()) / c)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi_.y() - lo_.y()) / c)));
  std::vector<std::vector<std::uint32_t>> cells(static_cast<size_t>(nx_) * ny_);
  auto cellIndex = [&](double v, double origin, int n) {
    return std::clamp(static_cast<int>(std::floor((v - origin) / c)), 0, n - 1);
  };
  for (std::uint32_t i = 0; i < boxes_.size(); ++i) {
    const Box& b = boxes_[i];
    const int x0 = cellIndex(b.lo.x(), lo_.x(), nx_), x1 = cellIndex(b.hi.x(), lo_.x(), nx_);
    const int y0 = cellIndex(b.lo.y(), lo_.y(), ny_), y1 = cellIndex(b.hi.y(), lo_.y(), ny_);
    if ((x1 - x0 + 1) * (y1 - y0 + 1) > config_.large_box_cells) {
      large_boxes_.push_back(i);  // floors, ceilings, long walls: tested once per ray, not per cell
      continue;
    }
    for (int ix = x0; ix <= x1; ++ix)
      for (int iy = y0; iy <= y1; ++iy) cells[static_cast<size_t>(iy) * nx_ + ix].push_back(i);
  }
  cell_start_.assign(cells.size() + 1, 0);
  for (size_t k = 0; k < cells.size(); ++k) cell_start_[k + 1] = cell_start_[k] + cells[k].size();
  cell_boxes_.reserve(cell_start_.back());
  for (const auto& cell : cells) cell_boxes_.insert(cell_boxes_.end(), cell.begin(), cell.end());
}

RayHit Scene::castBruteForce(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m) const {
  RayHit hit;
  const Eigen::Vector3d inv_d = inverse(d);
  for (size_t i = 0; i < boxes_.size(); ++i) {
    int axis;
    const double t = slab(o, inv_d, boxes_[i], 1e-9, axis);
    if (t < hit.range_m) hit = {t, static_cast<int>(i), axis};
  }
  if (hit.range_m > max_range_m) hit = RayHit();
  return hit;
}

RayHit Scene::cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m) const {
  RayHit hit;
  if (boxes_.empty()) return hit;
  const Eigen::Vector3d inv_d = inverse(d);
  const double c = config_.cell_size_m;
  // Clip the ray to the grid's (x, y) extent.
  double t_enter = 0.0, t_leave = max_range_m;
  for (int a = 0; a < 2; ++a) {
    if (std::isinf(inv_d[a])) {
      if (o[a] < lo_[a] || o[a] > hi_[a]) return hit;
      continue;
    }
    double ta = (lo_[a] - o[a]) * inv_d[a], tb = (hi_[a] - o[a]) * inv_d[a];
    if (ta > tb) std::swap(ta, tb);
    t_enter = std::max(t_enter, ta);
    t_leave = std::min(t_leave, tb);
  }
  // Large boxes first: their hit bounds the walk through the grid.
  for (std::uint32_t i : large_boxes_) {
    int axis;
    const double t = slab(o, inv_d, boxes_[i], 1e-9, axis);
    if (t < hit.range_m) hit = {t, static_cast<int>(i), axis};
  }
  t_leave = std::min(t_leave, hit.range_m);
  if (t_enter > t_leave) {
    if (hit.range_m > max_range_m) hit = RayHit();
    return hit;
  }
  // 2-D DDA over the cells from the entry point.
  const Eigen::Vector3d p = o + t_enter * d;
  int ix = std::clamp(static_cast<int>(std::floor((p.x() - lo_.x()) / c)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((p.y() - lo_.y()) / c)), 0, ny_ - 1);
  const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
  auto nextBoundary = [&](int i, int step, double origin, int a) {
    if (std::isinf(inv_d[a])) return kInf;
    const double edge = origin + (i + (step > 0 ? 1 : 0)) * c;
    return (edge - o[a]) * inv_d[a];
  };
  double t_max_x = nextBoundary(ix, step_x, lo_.x(), 0), t_max_y = nextBoundary(iy, step_y, lo_.y(), 1);
  const double t_delta_x = std::isinf(inv_d.x()) ? kInf : c * std::abs(inv_d.x());
  const double t_delta_y = std::isinf(inv_d.y()) ? kInf : c * std::abs(inv_d.y());
  while (true) {
    const size_t cell = static_cast<size_t>(iy) * nx_ + ix;
    for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
      const std::uint32_t i = cell_boxes_[k];
      int axis;
      const double t = slab(o, inv_d, boxes_[i], 1e-9, axis);
      if (t < hit.range_m) hit = {t, static_cast<int>(i), axis};
    }
    const double t_exit = std::min(t_max_x, t_max_y);
    if (hit.range_m <= t_exit || t_exit > t_leave) break;
    if (t_max_x < t_max_y) {
      ix += step_x;
      t_max_x += t_delta_x;
      if (ix < 0 || ix >= nx_) break;
    } else {
      iy += step_y;
      t_max_y += t_delta_y;
      if (iy < 0 || iy >= ny_) break;
    }
  }
  if (hit.range_m > max_range_m) hit = RayHit();
  return hit;
}

double Scene::distanceToSurface(const Eigen::Vector3d& p) const {
  double best = kInf;
  for (const Box& b : boxes_) {
    const Eigen::Vector3d outside = (b.lo - p).cwiseMax(p - b.hi).cwiseMax(0.0);
    double dist = outside.norm();
    if (dist == 0.0) dist = (p - b.lo).cwiseMin(b.hi - p).minCoeff();  // inside: depth below the nearest face
    best = std::min(best, dist);
  }
  return best;
}

}  // namespace mmlio::sim
