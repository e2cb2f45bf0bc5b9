#pragma once
// Synthetic scenes for the calibration tests: a furnished room of axis-aligned boxes, scanned by
// ray casting with a 16-ring spinning LiDAR (VLP-16-like) and a solid-state LiDAR with a random
// (non-repetitive) pattern inside an 81.7 x 25.1 deg field of view (Livox-Horizon-like).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "../common/box_scene.hpp"
#include "mmlio/core/types.hpp"

namespace mmlio::calib::testing {

constexpr double kDeg = M_PI / 180.0;

using mmlio::box_scene::Box;
using mmlio::box_scene::castRay;
using mmlio::box_scene::pose;
using mmlio::box_scene::Scene;

/// A 10 x 7 x 3 m office: shell, desks, cabinets, a pillar, boxes on the floor (no symmetry).
inline Scene office() {
  Scene s;
  const double w = 0.2, x0 = -4, x1 = 6, y0 = -3, y1 = 4, h = 3;
  s.push_back({{x0 - w, y0 - w, -w}, {x1 + w, y1 + w, 0}});
  s.push_back({{x0 - w, y0 - w, h}, {x1 + w, y1 + w, h + w}});
  s.push_back({{x0 - w, y0 - w, 0}, {x0, y1 + w, h}});
  s.push_back({{x1, y0 - w, 0}, {x1 + w, y1 + w, h}});
  s.push_back({{x0, y0 - w, 0}, {x1, y0, h}});
  s.push_back({{x0, y1, 0}, {x1, y1 + w, h}});
  s.push_back({{2.0, -1.0, 0}, {3.5, 0.2, 0.75}});     // desk ahead
  s.push_back({{4.5, 1.0, 0}, {5.9, 2.2, 1.9}});       // cabinet ahead left
  s.push_back({{1.0, 2.5, 0}, {1.5, 3.0, 3.0}});       // pillar
  s.push_back({{-3.0, -2.5, 0}, {-1.5, -1.2, 0.9}});   // desk behind
  s.push_back({{-3.9, 1.0, 0}, {-3.3, 3.5, 2.0}});     // shelf behind
  s.push_back({{3.0, -2.9, 0}, {3.6, -2.3, 1.2}});     // box ahead right
  s.push_back({{5.0, -2.0, 1.2}, {5.95, -1.0, 1.6}});  // wall-mounted box
  s.push_back({{-1.0, 3.5, 1.0}, {0.5, 3.95, 2.2}});   // whiteboard frame
  return s;
}

/// 16 rings in +-15 deg, `columns` azimuths per turn; points in the sensor frame, time_s over 0.1 s.
inline LidarScan spinningSweep(const Scene& s, const Eigen::Isometry3d& T_world_sensor, unsigned seed,
                               double noise_m = 0.0, int columns = 1800) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  const double az0 = jitter(rng);
  LidarScan scan;
  scan.sensor = "velodyne";
  for (int c = 0; c < columns; ++c) {
    const double az = 2 * M_PI * (c + az0) / columns;
    for (int r = 0; r < 16; ++r) {
      const double el = (-15.0 + 2.0 * r) * kDeg;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const double t = castRay(s, T_world_sensor.translation(), T_world_sensor.linear() * d);
      if (t > 100.0 || t < 0.3) continue;
      Point p;
      p.xyz = (d * (t + noise_m * noise(rng))).cast<float>();
      p.time_s = static_cast<float>(0.1 * c / columns);
      p.ring = static_cast<std::uint16_t>(r);
      scan.points.push_back(p);
    }
  }
  return scan;
}

/// Random directions inside an 81.7 x 25.1 deg field of view around +x.
inline LidarScan solidFrame(const Scene& s, const Eigen::Isometry3d& T_world_sensor, unsigned seed,
                            double noise_m = 0.0, int n = 12000) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  LidarScan scan;
  scan.sensor = "livox";
  for (int i = 0; i < n; ++i) {
    const double az = 81.7 * kDeg * u(rng), el = 25.1 * kDeg * u(rng);
    const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const double t = castRay(s, T_world_sensor.translation(), T_world_sensor.linear() * d);
    if (t > 100.0 || t < 0.3) continue;
    Point p;
    p.xyz = (d * (t + noise_m * noise(rng))).cast<float>();
    p.time_s = static_cast<float>(0.1 * i / n);
    p.ring = static_cast<std::uint16_t>(i % 6);
    scan.points.push_back(p);
  }
  return scan;
}

inline std::vector<Eigen::Vector3d> xyz(const LidarScan& s) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(s.points.size());
  for (const auto& p : s.points) out.push_back(p.xyz.cast<double>());
  return out;
}

inline double angleDeg(const Eigen::Isometry3d& T) { return Eigen::AngleAxisd(T.rotation()).angle() / kDeg; }

}  // namespace mmlio::calib::testing
