#pragma once
// People walking through a scene: person-sized boxes (0.3 m along the walk, 0.5 m across, 1.75 m
// tall) pacing back and forth along paths at 0.8-1.5 m/s. Paths come from the rig's own route so
// the people are where the rig looks:
//   walkers  follow a stretch of the route 0.7-1.3 m to its left or right (they pass the rig in
//            both directions);
//   crossers walk from the side towards the route, stop 0.7 m short of it and walk back (people
//            stepping out of a doorway or a side passage).
// A path never enters static geometry and never comes closer than 0.7 m to the rig's route, so
// nobody walks through a wall or into the rig. Everything is a pure function of the seed.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {

struct Person {
  std::vector<Eigen::Vector2d> path;  // polyline the person paces along, m (world x, y)
  std::vector<double> arc_m;          // arc length at each path vertex
  double speed_m_s = 1.0;
  double phase_m = 0.0;  // where on the back-and-forth cycle the person is at t = 0
  bool crosser = false;
};

class Crowd {
 public:
  static constexpr double kLength = 0.3, kWidth = 0.5, kHeight = 1.75;

  Crowd() = default;
  /// `count` people along `route` (the rig's positions, x y, in walking order) in `scene`.
  Crowd(const Scene& scene, const std::vector<Eigen::Vector2d>& route, int count, std::uint64_t seed);

  const std::vector<Person>& people() const { return people_; }
  int size() const { return static_cast<int>(people_.size()); }
  bool empty() const { return people_.empty(); }

  /// Centre of person i's footprint at time t_s (seconds since the sequence start).
  Eigen::Vector2d position(int i, double t_s) const;
  /// Person i's box at t_s (axis-aligned; the long side across the direction of walking).
  Box boxAt(int i, double t_s) const;
  /// Nearest person hit along o + t d (d unit) with t < max_range_m at time t_s; box = person index.
  RayHit cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m, double t_s) const;

 private:
  std::vector<Person> people_;
};

}  // namespace mmlio::sim
