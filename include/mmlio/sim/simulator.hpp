#pragma once
// A simulated rig (IMU + VLP-16-like spinning LiDAR + Livox-Horizon-like solid-state LiDAR)
// walking through a built-in scenario. Everything is deterministic per (seed, sensor, index);
// LiDAR sweeps are generated on demand, never all held in memory.
//
// Time: the sequence starts at kSimStartNs. Livox frame k starts at start + k * 100 ms, Velodyne
// sweep k at start + 37 ms + k * 100 ms (true time). Velodyne stamps are written as
// t_true - velodyne_time_offset_s, so its extrinsic time_offset_s (t_imu = t_stamp + offset) is
// velodyne_time_offset_s.
//
// Truth extrinsics (T_imu_sensor), unless random_mount draws them from the seed:
//   livox:    identity rotation, translation (0.05512, 0.02226, -0.0297) m;
//   velodyne: R = Rz(3 deg) Ry(-2 deg) Rx(1.5 deg), translation (0.03, -0.02, 0.18) m.
// random_mount: livox yaw +-15 deg, pitch/roll +-5 deg, translation +-10 cm; velodyne yaw any,
// pitch/roll +-5 deg, translation +-10 cm about (0, 0, 0.18) m; Velodyne phase 0-100 ms.
// IMU: 200 Hz, white noise + bias random walk (ImuNoiseConfig), constant initial biases
// acc (0.02, -0.015, 0.02) m/s^2 (or acc_bias_m_s2 per axis), gyro (0.003, -0.002, 0.0025) rad/s.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/sim/lidar_patterns.hpp"
#include "mmlio/sim/motion.hpp"
#include "mmlio/sim/people.hpp"
#include "mmlio/sim/scenarios.hpp"
#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {

constexpr Stamp kSimStartNs = 1700000000000000000LL;  // 2023-11-14T22:13:20Z
constexpr Stamp kVelodynePhaseNs = 37000000LL;        // Velodyne sweeps start 37 ms after Livox frames

/// IMU noise model (continuous-time densities), Kalibr convention.
struct ImuNoiseConfig {
  double rate_hz = 200.0;
  double acc_noise_density = 0.02;    // m/s^2/sqrt(Hz)
  double gyro_noise_density = 0.002;  // rad/s/sqrt(Hz)
  double acc_random_walk = 5e-4;      // m/s^3/sqrt(Hz)
  double gyro_random_walk = 5e-5;     // rad/s^2/sqrt(Hz)
  ImuBias initial_bias;               // set by the simulator (see the header comment)
};

struct SimOptions {
  std::string scenario;               // one of scenarioNames()
  double duration_s = 0;              // 0: the scenario's full walk (office ~40 s, corridor ~110 s, hall ~150 s)
  std::uint64_t seed = 1;             // noise seed (the scene and the walk do not depend on it)
  double velodyne_time_offset_s = 0;  // Velodyne stamps are written as t_true - offset
  // Variations for benchmarks that must not depend on one set of conditions:
  ImuNoiseConfig imu;         // densities; initial_bias is replaced by the simulator
  double acc_bias_m_s2 = -1;  // >= 0: initial accelerometer bias of this size per axis, signs from the seed
  SolidStatePattern livox_pattern = SolidStatePattern::kLissajous;
  bool random_mount = false;              // both extrinsics and the Velodyne sweep phase drawn from the seed
  bool livox_no_returns_as_zero = false;  // beams without a return become (0,0,0) points, as the Livox driver does
  int people = 0;                         // people walking through the scene (see people.hpp), paths from the seed
  bool handheld = false;                  // the route carried by hand (carriedByHand in scenarios.hpp)
  double velodyne_phase_s = -1;           // 0..0.1: Velodyne sweeps start this long after Livox frames (< 0: 37 ms)
  int route_start = 0;                    // the closed route walked from this waypoint (startingAt)
  bool rearranged = false;                // the furniture moved (rearrangeFurniture), draws from the seed
};

/// A scenario's full walk with every other option at its default.
inline SimOptions fullWalk(std::string scenario) {
  SimOptions o;
  o.scenario = std::move(scenario);
  return o;
}

class Simulator {
 public:
  explicit Simulator(SimOptions options);

  const SimOptions& options() const { return options_; }
  const Scenario& scenario() const { return scenario_; }
  const Scene& scene() const { return scene_; }
  const SplineMotion& motion() const { return motion_; }
  Stamp startNs() const { return kSimStartNs; }
  double durationS() const { return motion_.durationS(); }

  /// IMU (body) poses at the IMU stamps, 200 Hz.
  const Trajectory& groundTruth() const { return ground_truth_; }
  /// True state (pose, velocity, bias) at a true time; clamped to the sequence.
  NavState trueState(Stamp stamp_ns) const;
  /// Noiseless IMU reading at a true time (for consistency checks).
  ImuSample idealImu(Stamp stamp_ns) const;
  /// Noisy IMU samples, m/s^2 and rad/s.
  const std::vector<ImuSample>& imu() const { return imu_; }
  const ImuNoiseConfig& imuNoise() const { return imu_noise_; }
  ImuBias initialBias() const { return imu_noise_.initial_bias; }

  int numVelodyneSweeps() const;
  /// Sweep k, sensor "velodyne", start_ns = true start - velodyne_time_offset_s. With on_person,
  /// one flag per returned point: 1 where the return hit a person (the ground truth of what moves).
  LidarScan velodyneSweep(int k, std::vector<std::uint8_t>* on_person = nullptr) const;
  /// True start time of Velodyne sweep k.
  Stamp velodyneTrueStartNs(int k) const { return kSimStartNs + velodyne_phase_ns_ + k * 100000000LL; }
  int numLivoxFrames() const;
  /// Frame k, sensor "livox" (on_person as for velodyneSweep).
  LidarScan livoxFrame(int k, std::vector<std::uint8_t>* on_person = nullptr) const;

  LidarExtrinsic velodyneExtrinsic() const;
  LidarExtrinsic livoxExtrinsic() const;
  const VelodyneConfig& velodyneConfig() const { return velodyne_; }
  const LivoxConfig& livoxConfig() const { return livox_; }

  double pathLengthM() const { return path_length_m_; }
  /// Pieces of furniture moved (SimOptions::rearranged).
  std::size_t furnitureMoved() const { return furniture_moved_; }
  const Crowd& crowd() const { return crowd_; }

 private:
  LidarScan cast(const std::vector<Beam>& beams, Stamp true_start_ns, const Eigen::Isometry3d& T_imu_sensor,
                 double range_noise_m, double min_range_m, double max_range_m, std::uint64_t sensor_id, int k,
                 bool keep_no_returns, std::vector<std::uint8_t>* on_person) const;
  void drawMount();

  SimOptions options_;
  Scenario scenario_;
  Scene scene_;
  SplineMotion motion_;
  Crowd crowd_;
  ImuNoiseConfig imu_noise_;
  VelodyneConfig velodyne_;
  LivoxConfig livox_;
  std::vector<Beam> velodyne_beams_;  // the same every sweep
  Trajectory ground_truth_;
  std::vector<ImuSample> imu_;
  std::vector<ImuBias> true_bias_;  // at each IMU sample
  double path_length_m_ = 0.0;
  std::size_t furniture_moved_ = 0;
  Stamp velodyne_phase_ns_ = kVelodynePhaseNs;
  Eigen::Isometry3d T_imu_velodyne_, T_imu_livox_;
};

}  // namespace mmlio::sim
