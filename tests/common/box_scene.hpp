#pragma once
// Test helper shared by the test modules: scenes of axis-aligned boxes and the rays cast into them,
// so that scans of one place taken from two poses never share their points.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace mmlio::box_scene {

struct Box {
  Eigen::Vector3d lo, hi;
};
using Scene = std::vector<Box>;

/// R = Rz(yaw) Ry(pitch) Rx(roll), angles in rad.
inline Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad, double pitch_rad = 0, double roll_rad = 0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

/// Distance along the ray o + t d to box b (t > 0), or +inf.
inline double rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0 > 1e-9 ? t0 : std::numeric_limits<double>::infinity();
}

/// Distance along the ray o + t d to the nearest box of the scene, or +inf.
inline double castRay(const Scene& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t = std::numeric_limits<double>::infinity();
  for (const Box& b : s) t = std::min(t, rayBox(o, d, b));
  return t;
}

}  // namespace mmlio::box_scene
