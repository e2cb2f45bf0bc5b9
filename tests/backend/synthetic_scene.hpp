#pragma once
// Synthetic scenes for the backend tests: solids as axis-aligned boxes, scanned by a ray-cast
// spinning LiDAR (occlusion included), so two scans of one place never share their points.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "../common/box_scene.hpp"

namespace mmlio::backend::testing {

using mmlio::box_scene::Box;
using mmlio::box_scene::castRay;
using mmlio::box_scene::pose;
using mmlio::box_scene::Scene;

/// A ray-cast scan from T_world_body: `rings` beams between +-fov_deg/2 elevation, `columns`
/// azimuths, returns within max_range_m, Gaussian range noise. Points in the body frame.
inline std::vector<Eigen::Vector3d> scan(const Scene& scene, const Eigen::Isometry3d& T_world_body, unsigned seed,
                                         double noise_m = 0.01, double max_range_m = 30.0, int rings = 32,
                                         double fov_deg = 50.0, int columns = 720) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  const double az_offset = jitter(rng);  // the columns of two scans never coincide
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d o = T_world_body.translation();
  for (int r = 0; r < rings; ++r) {
    const double el = (-fov_deg / 2 + fov_deg * r / (rings - 1)) * M_PI / 180.0;
    for (int c = 0; c < columns; ++c) {
      const double az = 2 * M_PI * (c + az_offset) / columns;
      const Eigen::Vector3d d_body(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d = T_world_body.linear() * d_body;
      const double t = castRay(scene, o, d);
      if (t > max_range_m) continue;
      out.push_back(d_body * (t + noise(rng)));
    }
  }
  return out;
}

/// Walls (0.2 m thick), floor and ceiling of a room [x0,x1] x [y0,y1] x [0,h].
inline void addRoomShell(Scene& s, double x0, double x1, double y0, double y1, double h) {
  const double w = 0.2;
  s.push_back({{x0 - w, y0 - w, -w}, {x1 + w, y1 + w, 0}});     // floor
  s.push_back({{x0 - w, y0 - w, h}, {x1 + w, y1 + w, h + w}});  // ceiling
  s.push_back({{x0 - w, y0 - w, 0}, {x0, y1 + w, h}});          // walls
  s.push_back({{x1, y0 - w, 0}, {x1 + w, y1 + w, h}});
  s.push_back({{x0, y0 - w, 0}, {x1, y0, h}});
  s.push_back({{x0, y1, 0}, {x1, y1 + w, h}});
}

/// Room A: 16 x 12 x 3 m with boxes of assorted sizes at irregular places.
inline Scene roomA() {
  Scene s;
  addRoomShell(s, -8, 8, -6, 6, 3);
  s.push_back({{2.0, 1.0, 0}, {3.0, 2.5, 1.2}});
  s.push_back({{-4.0, -3.0, 0}, {-2.5, -2.2, 2.0}});
  s.push_back({{5.0, -4.5, 0}, {6.5, -3.0, 0.8}});
  s.push_back({{-6.5, 3.0, 0}, {-5.0, 5.5, 1.5}});
  s.push_back({{0.5, -2.0, 0}, {1.0, -1.5, 2.5}});   // a pillar
  s.push_back({{-1.5, 4.0, 0.8}, {1.5, 5.0, 1.0}});  // a table top
  return s;
}

/// Room B: a different room, 10 x 9 x 2.6 m, other furniture.
inline Scene roomB() {
  Scene s;
  addRoomShell(s, -5, 5, -4.5, 4.5, 2.6);
  s.push_back({{-3.0, -3.5, 0}, {-1.0, -2.5, 1.8}});
  s.push_back({{2.5, 2.0, 0}, {3.5, 3.5, 0.6}});
  s.push_back({{1.0, -1.0, 0}, {1.4, -0.6, 2.6}});
  return s;
}

/// A long straight corridor along x, 2 m wide, 2.8 m high, with 1 m wide, 0.4 m deep door
/// recesses every `period_m` on both walls: locally every period looks the same.
inline Scene corridor(double length_m = 120.0, double period_m = 4.0, bool doors = true) {
  Scene s;
  const double h = 2.8, half = 1.0, w = 0.2, depth = 0.4;
  const double x0 = -length_m / 2, x1 = length_m / 2;
  s.push_back({{x0, -half - depth - w, -w}, {x1, half + depth + w, 0}});
  s.push_back({{x0, -half - depth - w, h}, {x1, half + depth + w, h + w}});
  s.push_back({{x0 - w, -half - depth, 0}, {x0, half + depth, h}});
  s.push_back({{x1, -half - depth, 0}, {x1 + w, half + depth, h}});
  if (!doors) {
    s.push_back({{x0, -half - w, 0}, {x1, -half, h}});
    s.push_back({{x0, half, 0}, {x1, half + w, h}});
    return s;
  }
  // Back walls of the recesses, then wall segments between the doors.
  s.push_back({{x0, -half - depth - w, 0}, {x1, -half - depth, h}});
  s.push_back({{x0, half + depth, 0}, {x1, half + depth + w, h}});
  for (double x = x0; x < x1; x += period_m) {
    const double seg_end = std::min(x1, x + period_m - 1.0);
    s.push_back({{x, -half - depth, 0}, {seg_end, -half, h}});
    s.push_back({{x, half, 0}, {seg_end, half + depth, h}});
  }
  return s;
}

}  // namespace mmlio::backend::testing
