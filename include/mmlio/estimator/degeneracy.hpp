#pragma once
// What the LiDAR correspondences of one sweep constrain (Zhang, Kaess & Singh 2016, "On
// degeneracy of optimization-based state estimation problems"): the 6x6 information of the pose
// (world-frame translation, body-frame rotation) from its point-to-plane / point-to-edge matches,
// each whitened by the point noise. Its eigen-analysis names the directions the LiDARs cannot
// observe — a corridor's axis, the wall-normal plane of a blind solid-state frame — and the
// registration keeps the IMU prediction along them (solution remapping) instead of letting
// nearest-neighbour associations drag the pose there.
//
// Information is expressed as "effective points": an eigenvalue times sigma^2, i.e. how many
// perfectly aligned plane points the LiDARs' evidence along that direction is worth (for a
// rotation, per metre of lever arm). Translation and rotation are judged separately, each from
// its Schur complement (the other block free), so a direction only counts as observed when
// neither a rotation nor a translation can explain it away.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "mmlio/estimator/map_matching.hpp"

namespace mmlio::estimator {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Information of the pose from the matches, in effective points (J^T J with unit-normal plane
/// and unit-direction edge residuals, no 1/sigma^2). Matches whose residual at T exceeds
/// inlier_m are left out: a robust loss gives them no weight either.
/// source >= 0: only the matches of that LiDAR.
Matrix6d matchInformation(const std::vector<MapMatch>& matches, const Eigen::Isometry3d& T_world_body, double inlier_m,
                          int source = -1);

struct DegeneracyConfig {
  // A translation direction, or a rotation axis (per metre of lever arm), worth fewer effective
  // points than this is degenerate.
  double min_points = 30.0;
  // How fast the IMU prediction drifts along a translation direction the LiDARs leave unobserved,
  // as a white acceleration error (m/s^2/sqrt(Hz)) standing for the accelerometer bias and tilt the
  // estimator has not yet pinned down. The longer a direction goes unobserved, the less the
  // prediction is worth there and the weaker the LiDAR evidence that beats it: that direction's
  // threshold falls below min_points (a wall the solid-state LiDAR has faced for seconds still
  // says where the rig is along it better than the IMU alone). 0: the fixed threshold.
  double drift_m_s2 = 0.05;
  // ... but never below this many effective points: a handful of matches along a direction is as
  // likely a wrong association (a slab's top face matched to its underside on a staircase) as a
  // surface seen at a grazing angle.
  double min_points_drifted = 10.0;
};

struct Degeneracy {
  bool translation_degenerate = false, rotation_degenerate = false;
  double translation_points = 0.0;                                  // weakest translation eigenvalue
  double rotation_points = 0.0;                                     // weakest rotation eigenvalue
  Eigen::Vector3d weak_translation = Eigen::Vector3d::UnitX();      // its direction (world frame)
  Eigen::Matrix3d translation_basis = Eigen::Matrix3d::Identity();  // eigenvectors, ascending
  Eigen::Vector3d translation_eigenvalues = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_thresholds = Eigen::Vector3d::Zero();  // below which each is degenerate
  Eigen::Matrix3d rotation_basis = Eigen::Matrix3d::Identity();
  Eigen::Vector3d rotation_eigenvalues = Eigen::Vector3d::Zero();

  bool any() const { return translation_degenerate || rotation_degenerate; }
};

/// With `position_covariance_m2` (the prediction's, PredictionDrift), a translation direction
/// is also observed when its information beats the prediction's: more than sigma_m^2 / variance
/// effective points (sigma_m: the point residual's standard deviation).
Degeneracy analyseDegeneracy(const Matrix6d& information, const DegeneracyConfig& cfg,
                             const Eigen::Matrix3d* position_covariance_m2 = nullptr, double sigma_m = 0.0);

/// The covariance of the IMU prediction's position and velocity error (world frame) from sweep to
/// sweep: grown by DegeneracyConfig::drift_m_s2 over each interval, shrunk by the translation
/// information each registration used (a Kalman filter of the covariance alone).
class PredictionDrift {
 public:
  void predict(double dt_s, double drift_m_s2);
  /// The directions of `d` its thresholds call observed, with their information.
  void update(const Degeneracy& d, double sigma_m);
  Eigen::Matrix3d positionCovariance() const { return P_.topLeftCorner<3, 3>(); }
  /// The position's standard deviation along its least observed direction, m.
  double largestSigmaM() const;

 private:
  Matrix6d P_ = Matrix6d::Zero();  // position, velocity
};

/// Solution remapping: the solved pose and velocity keep the prediction's components along every
/// translation direction (and rotation axis) below the thresholds; observed directions keep the
/// solution. Returns how many directions were remapped.
int remapDegenerateDirections(const Degeneracy& d, const DegeneracyConfig& cfg, const Eigen::Vector3d& p_predicted,
                              const Eigen::Quaterniond& q_predicted, const Eigen::Vector3d& v_predicted,
                              Eigen::Vector3d* p, Eigen::Quaterniond* q, Eigen::Vector3d* v);

/// "forward", "left" or "up" (or their opposites' axis) for a body-frame direction: the body axis
/// it is closest to, for the report.
const char* bodyAxisName(const Eigen::Vector3d& direction_body);

}  // namespace mmlio::estimator
