#include "mmlio/map/geometry_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace mmlio::map {
namespace {

struct Scatter {
  Eigen::Vector3d mean;
  Eigen::Vector3d eigenvalues;   // ascending
  Eigen::Matrix3d eigenvectors;  // columns match eigenvalues
};

Scatter scatterOf(const std::vector<Eigen::Vector3d>& pts) {
  Scatter s;
  s.mean.setZero();
  for (const auto& p : pts) s.mean += p;
  s.mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d d = p - s.mean;
    cov += d * d.transpose();
  }
  cov /= static_cast<double>(pts.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(cov);  // closed form: the fits run per correspondence, several times per sweep
  s.eigenvalues = es.eigenvalues();
  s.eigenvectors = es.eigenvectors();
  return s;
}

}  // namespace

PlaneFit fitPlane(const std::vector<Eigen::Vector3d>& pts, double max_residual_m, double min_spread_ratio) {
  PlaneFit fit;
  if (pts.size() < 3) return fit;
  const Scatter s = scatterOf(pts);
  // Collinear (or coincident) points leave the normal undetermined.
  if (s.eigenvalues(1) <= 1e-12 * std::max(1.0, s.eigenvalues(2))) return fit;
  if (s.eigenvalues(1) < min_spread_ratio * s.eigenvalues(2)) return fit;  // a line: normal undetermined
  fit.normal = s.eigenvectors.col(0).normalized();
  fit.d = -fit.normal.dot(s.mean);
  for (const auto& p : pts) fit.max_residual_m = std::max(fit.max_residual_m, std::abs(fit.normal.dot(p) + fit.d));
  fit.ok = fit.max_residual_m <= max_residual_m;
  return fit;
}

LineFit fitLine(const std::vector<Eigen::Vector3d>& pts, double min_eigen_ratio, double max_residual_m) {
  LineFit fit;
  if (pts.size() < 2) return fit;
  const Scatter s = scatterOf(pts);
  fit.point = s.mean;
  fit.direction = s.eigenvectors.col(2).normalized();
  for (const auto& p : pts) {
    const Eigen::Vector3d d = p - fit.point;
    fit.max_residual_m = std::max(fit.max_residual_m, (d - fit.direction * fit.direction.dot(d)).norm());
  }
  fit.ok = s.eigenvalues(2) > 0 && s.eigenvalues(2) > min_eigen_ratio * s.eigenvalues(1) &&
           fit.max_residual_m <= max_residual_m;
  return fit;
}

}  // namespace mmlio::map
