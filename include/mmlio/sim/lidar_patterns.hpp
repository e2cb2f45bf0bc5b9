#pragma once
// Firing patterns of the simulated LiDARs: which direction (sensor frame, x forward, z up) each
// beam of one sweep/frame takes, and when (offset from the sweep start). Geometry is added by
// ray casting in the simulator.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace mmlio::sim {

struct Beam {
  Eigen::Vector3f dir = Eigen::Vector3f::UnitX();  // unit vector, sensor frame
  float time_s = 0.f;                              // offset from the sweep/frame start
  std::uint16_t ring = 0;                          // spinning ring (0 = lowest) or Livox line
};

/// VLP-16-like spinning LiDAR.
struct VelodyneConfig {
  double rate_hz = 10.0;               // rotations per second
  double azimuth_step_deg = 0.2;       // between firing sequences
  double laser_interval_s = 2.304e-6;  // between two lasers of a firing sequence
  double start_azimuth_deg = 180.0;    // where a sweep starts (x axis = 0, counter-clockwise)
  double range_noise_m = 0.015;        // 1 sigma
  double max_range_m = 100.0;
  double min_range_m = 0.4;
};

/// Elevation of ring r (ring 0 = -15 deg, 2 deg apart), deg.
inline double velodyneRingElevationDeg(int ring) { return -15.0 + 2.0 * ring; }

/// The beams of one sweep in firing order (sorted by time, all in [0, 1/rate)). The lasers fire
/// in the VLP-16 order (elevations -15, 1, -13, 3, ...); the head turns clockwise seen from above.
std::vector<Beam> velodyneBeams(const VelodyneConfig& config);

/// Solid-state scan pattern: both are non-repetitive (incommensurate frequencies), so coverage grows
/// with time, but their lines have different shapes, which a feature extractor must not depend on.
///  kLissajous: each line a fast sinusoidal horizontal sweep with a slow triangular vertical drift
///              (nearly straight horizontal runs, turning back at the edges of the view; Horizon-like).
///  kRosette:   each line the sum of two counter-rotating circles (Risley prisms; Mid-40 / Avia-like):
///              petals that curve all the time and cross the centre of the view.
enum class SolidStatePattern { kLissajous, kRosette };

/// Livox-Horizon-like solid-state LiDAR: 6 lines scan the field of view together (see
/// SolidStatePattern).
struct LivoxConfig {
  SolidStatePattern pattern = SolidStatePattern::kLissajous;
  double frame_rate_hz = 10.0;
  int points_per_frame = 24000;  // 6 lines fire together: points_per_frame / 6 firings
  int num_lines = 6;
  double fov_horizontal_deg = 81.7;
  double fov_vertical_deg = 25.1;
  double horizontal_hz = 47.31;    // full horizontal oscillations per second, per line
  double vertical_hz = 1.2833;     // triangular vertical drift cycles per second
  double rosette_fast_hz = 73.13;  // rosette: the two prism rotation rates, opposite senses
  double rosette_slow_hz = 41.71;
  double range_noise_m = 0.02;  // 1 sigma
  double max_range_m = 90.0;
  double min_range_m = 0.5;
};

/// Beams of frame k (the pattern depends on the time since the sensor started, k / rate).
std::vector<Beam> livoxBeams(const LivoxConfig& config, int frame_index);

}  // namespace mmlio::sim
