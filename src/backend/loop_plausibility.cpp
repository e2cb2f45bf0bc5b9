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

bool plausibleHeading(const PoseGraph& graph, int match, int query, double yaw_rad, double slack_deg,
                      const MappingConfig& cfg) {
  const Eigen::Matrix3d R_est = graph.pose(match).rotation().transpose() * graph.pose(query).rotation();
  const double estimated_rad = std::atan2(R_est(1, 0), R_est(0, 0));  // the heading of query's x axis
  const double off_deg = std::abs(std::remainder(yaw_rad - estimated_rad, 2.0 * M_PI)) * 180.0 / M_PI;
  const double allowed_deg =
      cfg.max_loop_rotation_base_deg + cfg.max_rotation_drift_deg_per_m * graph.routeLength(match, query) + slack_deg;
  return off_deg <= allowed_deg;
}

}  // namespace mmlio::backend
