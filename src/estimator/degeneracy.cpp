#include "mmlio/estimator/degeneracy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace mmlio::estimator {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Schur complement of block `keep` (0: translation, 3: rotation) with the other block free.
Eigen::Matrix3d schurBlock(const Matrix6d& H, int keep) {
  const int other = 3 - keep;
  const Eigen::Matrix3d A = H.block<3, 3>(keep, keep), B = H.block<3, 3>(keep, other), C = H.block<3, 3>(other, other);
  // C may be singular (no rotation information at all): a pseudo-inverse keeps what is observable.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  Eigen::Vector3d inv = Eigen::Vector3d::Zero();
  const double tol = 1e-9 * std::max(1.0, es.eigenvalues().maxCoeff());
  for (int i = 0; i < 3; ++i)
    if (es.eigenvalues()(i) > tol) inv(i) = 1.0 / es.eigenvalues()(i);
  const Eigen::Matrix3d C_pinv = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
  return A - B * C_pinv * B.transpose();
}

}  // namespace

Matrix6d matchInformation(const std::vector<MapMatch>& matches, const Eigen::Isometry3d& T_world_body, double inlier_m,
                          int source) {
  Matrix6d H = Matrix6d::Zero();
  const Eigen::Matrix3d R = T_world_body.linear();
  for (const MapMatch& m : matches) {
    if (source >= 0 && m.source != source) continue;
    const Eigen::Vector3d p_w = T_world_body * m.p_body;
    if (m.kind == MapMatch::Kind::kPlane) {
      const Eigen::Vector3d& n = m.a;
      if (std::abs(n.dot(p_w) + m.b.x()) > inlier_m) continue;
      Eigen::Matrix<double, 1, 6> J;
      J.head<3>() = n.transpose();
      J.tail<3>() = m.p_body.cross(R.transpose() * n).transpose();
      H.noalias() += J.transpose() * J;
    } else {
      const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - m.b * m.b.transpose();
      if ((P * (p_w - m.a)).norm() > inlier_m) continue;
      Eigen::Matrix<double, 3, 6> J;
      J.leftCols<3>() = P;
      J.rightCols<3>() = -P * R * skew(m.p_body);
      H.noalias() += J.transpose() * J;
    }
  }
  return H;
}

Degeneracy analyseDegeneracy(const Matrix6d& information, const DegeneracyConfig& cfg,
                             const Eigen::Matrix3d* position_covariance_m2, double sigma_m) {
  Degeneracy d;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> t(schurBlock(information, 0)), r(schurBlock(information, 3));
  d.translation_basis = t.eigenvectors();
  d.translation_eigenvalues = t.eigenvalues();
  d.rotation_basis = r.eigenvectors();
  d.rotation_eigenvalues = r.eigenvalues();
  d.translation_points = std::max(0.0, t.eigenvalues()(0));
  d.rotation_points = std::max(0.0, r.eigenvalues()(0));
  d.weak_translation = t.eigenvectors().col(0);
  for (int i = 0; i < 3; ++i) {
    d.translation_thresholds(i) = cfg.min_points;
    if (!position_covariance_m2) continue;
    const Eigen::Vector3d u = d.translation_basis.col(i);
    const double variance = u.dot(*position_covariance_m2 * u);
    if (variance > 0)
      d.translation_thresholds(i) =
          std::clamp(sigma_m * sigma_m / variance, std::min(cfg.min_points_drifted, cfg.min_points), cfg.min_points);
  }
  for (int i = 0; i < 3 && !d.translation_degenerate; ++i)
    if (d.translation_eigenvalues(i) < d.translation_thresholds(i)) {
      d.translation_degenerate = true;
      d.weak_translation = d.translation_basis.col(i);
    }
  d.rotation_degenerate = d.rotation_points < cfg.min_points;
  return d;
}

void PredictionDrift::predict(double dt_s, double drift_m_s2) {
  if (dt_s <= 0 || drift_m_s2 <= 0) return;
  Matrix6d F = Matrix6d::Identity();
  F.topRightCorner<3, 3>() = dt_s * Eigen::Matrix3d::Identity();
  const double q = drift_m_s2 * drift_m_s2;
  Matrix6d Q = Matrix6d::Zero();  // white acceleration over dt
  Q.topLeftCorner<3, 3>() = q * dt_s * dt_s * dt_s / 3.0 * Eigen::Matrix3d::Identity();
  Q.topRightCorner<3, 3>() = q * dt_s * dt_s / 2.0 * Eigen::Matrix3d::Identity();
  Q.bottomLeftCorner<3, 3>() = Q.topRightCorner<3, 3>();
  Q.bottomRightCorner<3, 3>() = q * dt_s * Eigen::Matrix3d::Identity();
  P_ = F * P_ * F.transpose() + Q;
}

double PredictionDrift::largestSigmaM() const {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(positionCovariance(), Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

void PredictionDrift::update(const Degeneracy& d, double sigma_m) {
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();  // of the position, 1/m^2
  for (int i = 0; i < 3; ++i) {
    const double points = d.translation_eigenvalues(i);
    if (points < d.translation_thresholds(i) || points <= 0) continue;
    const Eigen::Vector3d u = d.translation_basis.col(i);
    information += points / (sigma_m * sigma_m) * u * u.transpose();
  }
  if (information.isZero()) return;
  // P+ = P - P H^T (H P H^T + R)^-1 H P with H = [I 0] and R^-1 = information, written with
  // information so that unobserved directions (zero information) are left as they were.
  const Eigen::Matrix<double, 6, 3> PHt = P_.leftCols<3>();
  const Eigen::Matrix3d S = Eigen::Matrix3d::Identity() + information * P_.topLeftCorner<3, 3>();
  const Eigen::Matrix<double, 6, 3> K = PHt * S.inverse() * information;
  P_ -= K * PHt.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
}

int remapDegenerateDirections(const Degeneracy& d, const DegeneracyConfig& cfg, const Eigen::Vector3d& p_predicted,
                              const Eigen::Quaterniond& q_predicted, const Eigen::Vector3d& v_predicted,
                              Eigen::Vector3d* p, Eigen::Quaterniond* q, Eigen::Vector3d* v) {
  int remapped = 0;
  for (int i = 0; i < 3; ++i) {
    if (d.translation_eigenvalues(i) >= d.translation_thresholds(i)) continue;
    const Eigen::Vector3d u = d.translation_basis.col(i);
    *p -= u * u.dot(*p - p_predicted);
    *v -= u * u.dot(*v - v_predicted);
    ++remapped;
  }
  const Eigen::AngleAxisd solved_rotation(q_predicted.conjugate() * *q);
  Eigen::Vector3d dtheta = solved_rotation.angle() * solved_rotation.axis();
  bool rotated = false;
  for (int i = 0; i < 3; ++i) {
    if (d.rotation_eigenvalues(i) >= cfg.min_points) continue;
    const Eigen::Vector3d u = d.rotation_basis.col(i);
    dtheta -= u * u.dot(dtheta);
    rotated = true;
    ++remapped;
  }
  if (rotated) {
    const double angle = dtheta.norm();
    *q = angle > 0 ? q_predicted * Eigen::Quaterniond(Eigen::AngleAxisd(angle, dtheta / angle)) : q_predicted;
    q->normalize();
  }
  return remapped;
}

const char* bodyAxisName(const Eigen::Vector3d& direction_body) {
  const Eigen::Vector3d a = direction_body.cwiseAbs();
  if (a.x() >= a.y() && a.x() >= a.z()) return "forward";
  if (a.y() >= a.z()) return "left";
  return "up";
}

}  // namespace mmlio::estimator
