#pragma once
// Synthetic LiDAR scans of an axis-aligned box room, for the feature and bad-frame tests and the
// benchmark: a VLP-16-like ring scan and a Livox-Horizon-like 6-line zig-zag scan.
#include <cmath>
#include <random>

#include "mmlio/core/types.hpp"

namespace mmlio::synth {

struct BoxRoom {
  Eigen::Vector3d lo{-4.0, -3.0, -1.5}, hi{6.0, 5.0, 2.5};  // sensor at the origin, inside
  // Distance along unit ray d from the origin to the box wall.
  double hit(const Eigen::Vector3d& d) const {
    double t = 1e9;
    for (int a = 0; a < 3; ++a) {
      if (d[a] > 1e-12) t = std::min(t, hi[a] / d[a]);
      if (d[a] < -1e-12) t = std::min(t, lo[a] / d[a]);
    }
    return t;
  }
  // Azimuths (rad) of the four vertical corners.
  std::vector<double> cornerAzimuths() const {
    return {std::atan2(hi.y(), hi.x()), std::atan2(hi.y(), lo.x()), std::atan2(lo.y(), lo.x()),
            std::atan2(lo.y(), hi.x())};
  }
};

inline Eigen::Vector3d rayDir(double az, double el) {
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

/// VLP-16-like: 16 rings from -15 to +15 deg, 0.2 deg azimuth steps over 0.1 s, range noise sigma.
inline LidarScan vlp16Room(const BoxRoom& room, double noise_m, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_m);
  LidarScan s;
  s.sensor = "velodyne";
  const int cols = 1800;
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < 16; ++r) {
      const double az = -M_PI + 2 * M_PI * c / cols, el = (-15.0 + 2.0 * r) * M_PI / 180.0;
      const Eigen::Vector3d d = rayDir(az, el);
      Point p;
      p.xyz = ((room.hit(d) + n(rng)) * d).cast<float>();
      p.ring = static_cast<std::uint16_t>(r);
      p.time_s = static_cast<float>(0.1 * c / cols);
      p.intensity = 10.f;
      s.points.push_back(p);
    }
  return s;
}

/// Livox-Horizon-like: 6 lines stacked in elevation, each sweeping azimuth back and forth across
/// +-40 deg (4 passes, 1000 points each, per 0.1 s frame) with a slow elevation wobble; looking along
/// `yaw` (rad). Points interleaved across lines in firing order, ring = line.
inline LidarScan livoxRoom(const BoxRoom& room, double yaw, double noise_m, unsigned seed = 2) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_m);
  LidarScan s;
  s.sensor = "livox";
  const int per_line = 4000, passes = 4, per_pass = per_line / passes;
  for (int k = 0; k < per_line; ++k)
    for (int l = 0; l < 6; ++l) {
      const int pass = k / per_pass, j = k % per_pass;
      const double u = (pass % 2 == 0) ? double(j) / per_pass : 1.0 - double(j) / per_pass;
      const double az = yaw + (-40.0 + 80.0 * u) * M_PI / 180.0;
      const double el = (-12.5 + 4.2 * l + 1.5 * std::sin(0.7 * pass + 6.0 * u)) * M_PI / 180.0;
      const Eigen::Vector3d d = rayDir(az, el);
      Point p;
      p.xyz = ((room.hit(d) + n(rng)) * d).cast<float>();
      p.ring = static_cast<std::uint16_t>(l);
      p.time_s = static_cast<float>(0.1 * (k * 6 + l) / (per_line * 6.0));
      s.points.push_back(p);
    }
  return s;
}

}  // namespace mmlio::synth
