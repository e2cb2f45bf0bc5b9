#pragma once
// Smooth (C2) rig motion: a uniform cubic B-spline in (x, y, z, yaw, pitch, roll) whose control
// points sample a piecewise-linear keyframe path, so derivatives are analytic and the IMU
// computed from them is exactly consistent with the poses.
// Orientation: R_world_body = Rz(yaw) Ry(pitch) Rx(roll); world z up, gravity (0, 0, -9.81).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace mmlio::sim {

constexpr double kGravityM_s2 = 9.81;

/// A keyframe of the linear path: where the body is at time t_s.
struct Keyframe {
  double t_s = 0.0;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // m
  double yaw_rad = 0.0, pitch_rad = 0.0, roll_rad = 0.0;
};

/// A waypoint of a walk: the body passes (x, y) with heading yaw (unwrapped, rad), `height_m`
/// (WalkConfig) above a floor at z_m, pitched and rolled by pitch_rad and roll_rad (a look down is
/// a positive pitch, a robot on a ramp pitches with it).
struct Waypoint {
  double x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;
  double z_m = 0.0, pitch_rad = 0.0, roll_rad = 0.0;
};

/// How a walk through waypoints is timed.
struct WalkConfig {
  double speed_m_s = 1.0;          // translation speed on legs
  double yaw_rate_rad_s = 1.2;     // rotation speed (in-place turns are limited by it)
  double height_m = 1.2;           // body height above the floor
  double bob_amplitude_m = 0.015;  // vertical bobbing while walking
  double bob_period_s = 1.1;
  double sway_rad = 0.012;       // roll at half the bobbing rate (the weight going from foot to foot)
  double nod_rad = 0.012;        // pitch at the bobbing rate
  double yaw_wobble_rad = 0.0;   // yaw at half the bobbing rate (a hand-held rig swinging)
  double climb_rate_m_s = 0.35;  // vertical speed on stairs and ramps (legs are slower there)
  double look_rate_rad_s = 1.0;  // pitch / roll speed of deliberate looks up, down or sideways
  // Knot spacing of the motion spline. 0.25 s carries a robot's slow bobbing; a walking gait
  // (steps at ~2 Hz) needs finer knots, which then carry the gait on top of a path that is still
  // smoothed at 0.25 s (finer knots on the path itself would turn its corners into jerks).
  double knot_interval_s = 0.25;
  double rest_start_s = 2.5;  // at rest before moving
  double rest_end_s = 2.5;    // at rest after returning
};

/// Keyframes of a walk: rest, waypoints at the configured speeds, rest. When `motion_budget_s`
/// (> 0) is shorter than the walk, a prefix of the walk is walked out and back (turning around
/// twice) so the walk still ends at its start pose; leftover time is added to the final rest.
std::vector<Keyframe> walkKeyframes(const std::vector<Waypoint>& waypoints, const WalkConfig& config,
                                    double total_duration_s = 0.0);

/// Full kinematic state at one time.
struct MotionState {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_world = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_world_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();  // rad/s, body frame

  /// Ideal accelerometer (specific force, body frame): R^T (a_world - g_world).
  Eigen::Vector3d specificForce() const;
  Eigen::Isometry3d pose() const;
};

class SplineMotion {
 public:
  SplineMotion() = default;
  /// Control points sample the linear interpolation of `keyframes` every `knot_interval_s`.
  explicit SplineMotion(const std::vector<Keyframe>& keyframes, double knot_interval_s = 0.25);

  double durationS() const { return duration_s_; }
  /// Clamped to [0, duration]. Before the first and after the last keyframe the body rests.
  MotionState at(double t_s) const;
  /// The spline's coordinates at t: x y z (m), yaw pitch roll (rad).
  Eigen::Matrix<double, 6, 1> coordinates(double t_s) const;

 private:
  struct Jet {
    Eigen::Matrix<double, 6, 1> x, dx, ddx;  // coordinates and their first and second time derivatives
  };
  Jet evaluate(double t_s) const;

  double h_ = 0.25, duration_s_ = 0.0;
  std::vector<Eigen::Matrix<double, 6, 1>> control_;  // x y z yaw pitch roll
};

/// The motion of a walk (walkKeyframes), on knots of config.knot_interval_s.
SplineMotion walkMotion(const std::vector<Waypoint>& waypoints, const WalkConfig& config,
                        double total_duration_s = 0.0);
/// A recorded motion (poses over a floor at z = 0; config.height_m is added) replayed as recorded,
/// between rests of config.rest_start_s and rest_end_s, with config's gait on top. A
/// `total_duration_s` (> 0) shorter than the recording cuts it; the rest fills up to it.
SplineMotion recordedMotion(const std::vector<Keyframe>& recorded, const WalkConfig& config,
                            double total_duration_s = 0.0);

}  // namespace mmlio::sim
