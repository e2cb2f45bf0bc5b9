#include "mmlio/backend/scan_context.hpp"

#include <cmath>

namespace mmlio::backend {

ScanContext makeScanContext(const std::vector<Eigen::Vector3d>& cloud_body, const ScanContextConfig& cfg) {
  ScanContext sc;
  sc.bins = Eigen::MatrixXd::Zero(cfg.rings, cfg.sectors);
  for (const auto& p : cloud_body) {
    const double range = std::hypot(p.x(), p.y());
    if (range >= cfg.max_range_m || range < 1e-3) continue;
    const int r = std::min(cfg.rings - 1, static_cast<int>(range / cfg.max_range_m * cfg.rings));
    const double az = std::atan2(p.y(), p.x()) + M_PI;  // [0, 2 pi]
    const int s = std::min(cfg.sectors - 1, static_cast<int>(az / (2 * M_PI) * cfg.sectors));
    sc.bins(r, s) = std::max(sc.bins(r, s), std::max(0.0, p.z() + cfg.height_offset_m));
  }
  sc.ring_key = sc.bins.rowwise().mean();
  return sc;
}

ScanContextMatch compareScanContexts(const ScanContext& query, const ScanContext& candidate) {
  ScanContextMatch best;
  const int S = static_cast<int>(query.bins.cols());
  if (S == 0 || candidate.bins.cols() != S || candidate.bins.rows() != query.bins.rows()) return best;
  const Eigen::VectorXd qn = query.bins.colwise().norm(), cn = candidate.bins.colwise().norm();
  for (int k = 0; k < S; ++k) {
    double sum = 0;
    int count = 0;
    for (int j = 0; j < S; ++j) {
      const int jc = (j + k) % S;
      if (qn(j) < 1e-9 || cn(jc) < 1e-9) continue;
      sum += 1.0 - query.bins.col(j).dot(candidate.bins.col(jc)) / (qn(j) * cn(jc));
      ++count;
    }
    if (count == 0) continue;
    const double d = sum / count;
    if (d < best.distance) {
      best.distance = d;
      // A query point at azimuth a lies at a + yaw in the candidate: query column j <-> j + k.
      double yaw = 2 * M_PI * k / S;
      if (yaw > M_PI) yaw -= 2 * M_PI;
      best.yaw_rad = yaw;
    }
  }
  return best;
}

}  // namespace mmlio::backend
