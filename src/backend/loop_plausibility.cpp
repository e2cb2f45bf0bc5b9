#include "mmlio/backend/loop_plausibility.hpp"

#include <cmath>

namespace mmlio::backend {

LoopCorrection loopCorrection(const PoseGraph& graph, const LoopResult& r, const MappingConfig& cfg) {
  LoopCorrection c;
  c.route_m = graph.routeLength(r.match, r.query);
  const Eigen::Isometry3d T_est = graph.pose(r.match).inverse() * graph.pose(r.query);
  c.correction_m = (T_est.translation() - r.T_match_query.translation()).norm();
  c.correction_deg =
      Eigen::AngleAxisd(T_est.rotation().transpose() * r.T_match_query.rotation()).angle() * 180.0 / M_PI;
  c.allowed_m = cfg.max_loop_correction_base_m + cfg.max_drift_fraction * c.route_m;
  c.allowed_deg = cfg.max_loop_rotation_base_deg + cfg.max_rotation_drift_deg_per_m * c.route_m;
  return c;
}

}  // namespace mmlio::backend
