#include "mmlio/sim/lidar_patterns.hpp"

#include <cmath>

namespace mmlio::sim {

namespace {
constexpr double kDeg = M_PI / 180.0;

Eigen::Vector3f direction(double azimuth_rad, double elevation_rad) {
  return Eigen::Vector3f(static_cast<float>(std::cos(elevation_rad) * std::cos(azimuth_rad)),
                         static_cast<float>(std::cos(elevation_rad) * std::sin(azimuth_rad)),
                         static_cast<float>(std::sin(elevation_rad)));
}

// Triangle wave in [-1, 1] with period 1, continuous.
double triangle(double u) {
  const double f = u - std::floor(u);
  return f < 0.5 ? 4 * f - 1 : 3 - 4 * f;
}
}  // namespace

std::vector<Beam> velodyneBeams(const VelodyneConfig& config) {
  constexpr int kRings = 16;
  const double period_s = 1.0 / config.rate_hz;
  const int columns = static_cast<int>(std::lround(360.0 / config.azimuth_step_deg));
  const double column_s = period_s / columns;
  std::vector<Beam> beams;
  beams.reserve(static_cast<size_t>(columns) * kRings);
  for (int c = 0; c < columns; ++c) {
    for (int laser = 0; laser < kRings; ++laser) {
      // VLP-16 laser id -> ring: even ids -15, -13, ..., odd ids 1, 3, ..., 15 deg.
      const int ring = laser % 2 == 0 ? laser / 2 : 8 + laser / 2;
      const double t = c * column_s + laser * config.laser_interval_s;
      // Clockwise rotation: the azimuth (counter-clockwise from x) decreases with time.
      const double azimuth = (config.start_azimuth_deg - 360.0 * t / period_s) * kDeg;
      Beam b;
      b.dir = direction(azimuth, velodyneRingElevationDeg(ring) * kDeg);
      b.time_s = static_cast<float>(t);
      b.ring = static_cast<std::uint16_t>(ring);
      beams.push_back(b);
    }
  }
  return beams;
}

std::vector<Beam> livoxBeams(const LivoxConfig& config, int frame_index) {
  const int firings = config.points_per_frame / config.num_lines;
  const double period_s = 1.0 / config.frame_rate_hz;
  const double firing_s = period_s / firings;
  const double half_h = 0.5 * config.fov_horizontal_deg * kDeg, half_v = 0.5 * config.fov_vertical_deg * kDeg;
  std::vector<Beam> beams;
  beams.reserve(static_cast<size_t>(firings) * config.num_lines);
  for (int f = 0; f < firings; ++f) {
    const double t_local = f * firing_s;
    const double t = frame_index * period_s + t_local;  // since the sensor started
    for (int line = 0; line < config.num_lines; ++line) {
      double u_h = 0, u_v = 0;  // in [-1, 1] across the view
      if (config.pattern == SolidStatePattern::kLissajous) {
        // Lines are spread over the vertical drift and slightly over the horizontal phase.
        u_h = std::sin(2 * M_PI * config.horizontal_hz * t + 0.37 * line);
        u_v = triangle(config.vertical_hz * t + static_cast<double>(line) / config.num_lines);
      } else {
        // Two counter-rotating unit circles, half each: the sum stays in the unit disc; lines are
        // spread over the phase of the slow prism.
        const double fast = 2 * M_PI * config.rosette_fast_hz * t;
        const double slow = -2 * M_PI * config.rosette_slow_hz * t + 2 * M_PI * line / config.num_lines;
        u_h = 0.5 * (std::cos(fast) + std::cos(slow));
        u_v = 0.5 * (std::sin(fast) + std::sin(slow));
      }
      Beam b;
      b.dir = direction(half_h * u_h, half_v * u_v);
      b.time_s = static_cast<float>(t_local);
      b.ring = static_cast<std::uint16_t>(line);
      beams.push_back(b);
    }
  }
  return beams;
}

}  // namespace mmlio::sim
