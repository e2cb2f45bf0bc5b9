#include "mmlio/sim/people.hpp"

#include <algorithm>
#include <cmath>

#include "mmlio/sim/random.hpp"

namespace mmlio::sim {
namespace {

constexpr std::uint64_t kPeopleId = 5;
constexpr double kStepM = 0.25;           // path sampling
constexpr double kRouteClearanceM = 0.7;  // nearest a person comes to the rig's route

bool footprintFree(const Scene& scene, const Eigen::Vector2d& c) {
  const double half = 0.5 * Crowd::kWidth + 0.05;  // either orientation, with a margin
  for (const Box& b : scene.boxes()) {
    if (b.hi.z() <= 0.05 || b.lo.z() >= Crowd::kHeight) continue;  // floor slabs and ceilings
    if (c.x() + half > b.lo.x() && c.x() - half < b.hi.x() && c.y() + half > b.lo.y() && c.y() - half < b.hi.y())
      return false;
  }
  return c.x() - half > scene.lo().x() && c.x() + half < scene.hi().x() && c.y() - half > scene.lo().y() &&
         c.y() + half < scene.hi().y();
}

bool clearOfRoute(const std::vector<Eigen::Vector2d>& route, const Eigen::Vector2d& c) {
  const double min_sq = (kRouteClearanceM - 0.05) * (kRouteClearanceM - 0.05);
  return std::none_of(route.begin(), route.end(),
                      [&](const Eigen::Vector2d& r) { return (r - c).squaredNorm() < min_sq; });
}

std::vector<Eigen::Vector2d> resampleByArc(const std::vector<Eigen::Vector2d>& route) {
  std::vector<Eigen::Vector2d> out;
  for (const Eigen::Vector2d& p : route)
    if (out.empty() || (p - out.back()).norm() >= kStepM) out.push_back(p);
  return out;
}

Person finish(std::vector<Eigen::Vector2d> path, double speed, double phase_unit, bool crosser) {
  Person p;
  p.path = std::move(path);
  p.arc_m.push_back(0.0);
  for (std::size_t i = 1; i < p.path.size(); ++i)
    p.arc_m.push_back(p.arc_m.back() + (p.path[i] - p.path[i - 1]).norm());
  p.speed_m_s = speed;
  p.phase_m = phase_unit * 2.0 * p.arc_m.back();
  p.crosser = crosser;
  return p;
}

}  // namespace

Crowd::Crowd(const Scene& scene, const std::vector<Eigen::Vector2d>& rig_route, int count, std::uint64_t seed) {
  const std::vector<Eigen::Vector2d> route = resampleByArc(rig_route);
  if (route.size() < 3 || count <= 0) return;
  const int n = static_cast<int>(route.size());
  for (int person = 0; person < count; ++person) {
    std::uint64_t draw = 0;
    auto uniform = [&](double lo, double hi) {
      return lo + (hi - lo) * unitFromHash(hashKey(seed, kPeopleId, static_cast<std::uint64_t>(person), draw++));
    };
    const double speed = uniform(0.8, 1.5);
    const double phase = uniform(0.0, 1.0);
    const bool wants_crossing = person % 4 == 3;
    bool placed = false;
    for (int attempt = 0; attempt < 200 && !placed; ++attempt) {
      const bool crossing = wants_crossing && attempt < 50;
      const int j = std::clamp(static_cast<int>(uniform(1.0, n - 1.0)), 1, n - 2);
      const double side = uniform(0.0, 1.0) < 0.5 ? -1.0 : 1.0;
      const Eigen::Vector2d tangent = (route[j + 1] - route[j - 1]).normalized();
      const Eigen::Vector2d normal = side * Eigen::Vector2d(-tangent.y(), tangent.x());
      std::vector<Eigen::Vector2d> path;
      if (crossing) {
        // Outwards from the route until something blocks, then walked inwards and back.
        for (double d = kRouteClearanceM; d <= 6.0; d += kStepM) {
          const Eigen::Vector2d c = route[j] + d * normal;
          if (!footprintFree(scene, c) || !clearOfRoute(route, c)) break;
          path.push_back(c);
        }
        if (path.size() < 8) continue;
        std::reverse(path.begin(), path.end());
      } else {
        const double offset = uniform(kRouteClearanceM, 1.3);
        const int length = static_cast<int>(uniform(8.0, 30.0) / kStepM);
        for (int k = j; k < std::min(n - 1, j + length); ++k) {
          const Eigen::Vector2d t = (route[k + 1] - route[k - 1]).normalized();
          const Eigen::Vector2d c = route[k] + offset * side * Eigen::Vector2d(-t.y(), t.x());
          // Stop at walls, near the route, and where the offset flips sides (the rig turning on the spot).
          if (!footprintFree(scene, c) || !clearOfRoute(route, c) || (!path.empty() && (c - path.back()).norm() > 0.6))
            break;
          path.push_back(c);
        }
        if (path.size() < 12) continue;  // at least 3 m
      }
      people_.push_back(finish(std::move(path), speed, phase, crossing));
      placed = true;
    }
  }
}

Eigen::Vector2d Crowd::position(int i, double t_s) const {
  const Person& p = people_[static_cast<std::size_t>(i)];
  const double length = p.arc_m.back();
  if (length <= 0.0) return p.path.front();
  double u = std::fmod(p.phase_m + p.speed_m_s * std::max(0.0, t_s), 2.0 * length);
  const double s = u <= length ? u : 2.0 * length - u;
  const auto it = std::upper_bound(p.arc_m.begin(), p.arc_m.end(), s);
  const std::size_t k = std::clamp<std::size_t>(static_cast<std::size_t>(it - p.arc_m.begin()), 1, p.path.size() - 1);
  const double seg = p.arc_m[k] - p.arc_m[k - 1];
  const double a = seg > 0.0 ? (s - p.arc_m[k - 1]) / seg : 0.0;
  return p.path[k - 1] + a * (p.path[k] - p.path[k - 1]);
}

Box Crowd::boxAt(int i, double t_s) const {
  const Person& p = people_[static_cast<std::size_t>(i)];
  const Eigen::Vector2d c = position(i, t_s);
  const Eigen::Vector2d along = p.path.back() - p.path.front();
  const bool along_x = std::abs(along.x()) >= std::abs(along.y());
  const double hx = 0.5 * (along_x ? kLength : kWidth), hy = 0.5 * (along_x ? kWidth : kLength);
  Box b;
  b.lo = Eigen::Vector3d(c.x() - hx, c.y() - hy, 0.0);
  b.hi = Eigen::Vector3d(c.x() + hx, c.y() + hy, kHeight);
  b.reflectivity = 60.f;
  return b;
}

RayHit Crowd::cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m, double t_s) const {
  RayHit hit;
  for (int i = 0; i < size(); ++i) {
    const Box b = boxAt(i, t_s);
    const double t = rayBox(o, d, b);
    if (!(t < hit.range_m) || t > max_range_m) continue;
    hit.range_m = t;
    hit.box = i;
    const Eigen::Vector3d p = o + t * d;
    double best = 1e9;
    for (int a = 0; a < 3; ++a) {
      const double gap = std::min(std::abs(p[a] - b.lo[a]), std::abs(p[a] - b.hi[a]));
      if (gap < best) {
        best = gap;
        hit.axis = a;
      }
    }
  }
  return hit;
}

}  // namespace mmlio::sim
