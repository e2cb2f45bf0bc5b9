#include "mmlio/calib/spatial_calibration.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

namespace mmlio::calib {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::vector<Eigen::Vector3d> inRange(const std::vector<Eigen::Vector3d>& pts, double min_m, double max_m) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(pts.size());
  for (const auto& p : pts) {
    const double r = p.norm();
    if (p.allFinite() && r >= min_m && r <= max_m) out.push_back(p);
  }
  return out;
}

/// Spinning points (spinning frame) that T_solid_spinning puts inside the solid FOV (+ margin).
std::vector<Eigen::Vector3d> cropToSolidView(const std::vector<Eigen::Vector3d>& spinning,
                                             const Eigen::Isometry3d& T_solid_spinning,
                                             const SpatialCalibrationConfig& cfg) {
  const double half_h = (0.5 * cfg.solid_fov_horizontal_deg + cfg.fov_margin_deg) * kDeg;
  const double half_v = (0.5 * cfg.solid_fov_vertical_deg + cfg.fov_margin_deg) * kDeg;
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : spinning) {
    const Eigen::Vector3d q = T_solid_spinning * p;
    if (q.x() <= 0) continue;  // the solid-state LiDAR looks along +x
    if (std::abs(std::atan2(q.y(), q.x())) > half_h) continue;
    if (std::abs(std::atan2(q.z(), q.head<2>().norm())) > half_v) continue;
    out.push_back(p);
  }
  return out;
}

std::string fmt(double v, int precision = 3) {
  std::ostringstream os;
  os.precision(precision);
  os << v;
  return os.str();
}

}  // namespace

SpatialCalibrationResult calibrateSpinningToSolid(const std::vector<Eigen::Vector3d>& spinning_in,
                                                  const std::vector<Eigen::Vector3d>& solid_in,
                                                  const std::optional<Eigen::Isometry3d>& guess,
                                                  const SpatialCalibrationConfig& cfg) {
  SpatialCalibrationResult res;
  const auto solid = map::voxelCentroids(inRange(solid_in, cfg.min_range_m, cfg.max_range_m), cfg.target_voxel_m);
  const auto spinning = map::voxelCentroids(inRange(spinning_in, cfg.min_range_m, cfg.max_range_m), cfg.source_voxel_m);
  res.solid_points = static_cast<int>(solid.size());
  if (static_cast<int>(solid.size()) < cfg.min_points || static_cast<int>(spinning.size()) < cfg.min_points) {
    res.message = "too few points to calibrate (solid-state " + std::to_string(solid.size()) + ", spinning " +
                  std::to_string(spinning.size()) + " within " + fmt(cfg.min_range_m) + "-" + fmt(cfg.max_range_m) +
                  " m; need " + std::to_string(cfg.min_points) + "): is either LiDAR blocked or missing at the start?";
    return res;
  }

  // One GICP run from an initial T_solid_spinning, on the spinning points that fall in the view.
  struct Attempt {
    GicpResult gicp;
    int source_points = 0;
  };
  const auto attempt = [&](const Eigen::Isometry3d& init) {
    Attempt a;
    const auto source = cropToSolidView(spinning, init, cfg);
    a.source_points = static_cast<int>(source.size());
    if (a.source_points < cfg.min_points) return a;
    a.gicp = gicp(source, solid, init, cfg.gicp);
    return a;
  };
  const auto better = [](const Attempt& a, const Attempt& b) {  // more matched points, then tighter
    if (a.gicp.converged != b.gicp.converged) return a.gicp.converged;
    const double sa = a.gicp.overlap / std::max(a.gicp.fitness_m, 1e-4),
                 sb = b.gicp.overlap / std::max(b.gicp.fitness_m, 1e-4);
    return sa > sb;
  };

  Attempt best;
  if (guess) {
    best = attempt(*guess);
  }
  const bool guess_good =
      guess && best.gicp.converged && best.gicp.fitness_m <= cfg.max_fitness_m && best.gicp.overlap >= cfg.min_overlap;
  if (!guess_good) {
    res.yaw_searched = true;
    const Eigen::Vector3d t0 = guess ? Eigen::Vector3d(guess->translation()) : Eigen::Vector3d::Zero();
    const Eigen::Matrix3d R0 = guess ? Eigen::Matrix3d(guess->linear()) : Eigen::Matrix3d::Identity();
    const int steps = std::max(1, static_cast<int>(std::round(360.0 / cfg.yaw_step_deg)));
    for (int i = 0; i < steps; ++i) {
      Eigen::Isometry3d init = Eigen::Isometry3d::Identity();
      init.linear() = Eigen::AngleAxisd(i * 2 * M_PI / steps, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R0;
      init.translation() = t0;
      const Attempt a = attempt(init);
      if (a.source_points > 0 && (best.source_points == 0 || better(a, best))) best = a;
    }
    // Refine the winner once more on the points its own estimate puts in view.
    if (best.gicp.converged) {
      const Attempt refined = attempt(best.gicp.T_target_source);
      if (refined.gicp.converged) best = refined;
    }
  }

  const GicpResult& g = best.gicp;
  res.T_solid_spinning = g.T_target_source;
  res.fitness_m = g.fitness_m;
  res.overlap = g.overlap;
  res.spinning_points = best.source_points;
  res.hessian = g.hessian;
  if (best.source_points < cfg.min_points) {
    res.message = "the spinning LiDAR sees fewer than " + std::to_string(cfg.min_points) +
                  " points inside the solid-state field of view: the two LiDARs do not overlap enough";
    return res;
  }
  if (!g.converged) {
    res.message = "GICP did not converge (" + std::to_string(g.inliers) +
                  " correspondences): give a rough "
                  "T_imu_sensor for the spinning LiDAR in the config, or start the bag facing a structured scene";
    return res;
  }
  if (g.fitness_m > cfg.max_fitness_m || g.overlap < cfg.min_overlap) {
    res.message = "GICP fitness " + fmt(g.fitness_m) + " m, overlap " + fmt(g.overlap) +
                  " (need <= " + fmt(cfg.max_fitness_m) + " m, >= " + fmt(cfg.min_overlap) +
                  "): the clouds do not agree; check that the rig stood still and both LiDARs see the same scene";
    return res;
  }
  // A single wall (or two parallel ones) in the overlap leaves translations along it free: the
  // alignment then only looks good. Compare the weakest translation direction with the strongest.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(g.hessian.topLeftCorner<3, 3>());
  const double conditioning = es.eigenvalues()(0) / std::max(es.eigenvalues()(2), 1e-12);
  if (conditioning < cfg.min_translation_conditioning) {
    res.message = "the overlapping region constrains the extrinsic poorly (translation conditioning " +
                  fmt(conditioning) + " < " + fmt(cfg.min_translation_conditioning) +
                  "): start the bag facing a corner or furniture, not a single wall";
    return res;
  }
  res.ok = true;
  res.message = "GICP fitness " + fmt(g.fitness_m) + " m, overlap " + fmt(g.overlap) + ", conditioning " +
                fmt(conditioning) + " on " + std::to_string(best.source_points) + " spinning / " +
                std::to_string(solid.size()) + " solid-state points" + (res.yaw_searched ? " (yaw search)" : "");
  return res;
}

}  // namespace mmlio::calib
