#include "mmlio/backend/loop_plausibility.hpp"

#include <cmath>

namespace mmlio::backend {
namespace {

double toDeg(double rad) { return rad * 180.0 / M_PI; }

/// How far odometry can have turned over route_m of travel, deg.
double allowedRotationDeg(double route_m, const MappingConfig& cfg) {
  return cfg.max_loop_rotation_base_deg + cfg.max_rotation_drift_deg_per_m * route_m;
}

}  // namespace

LoopCorrection loopCorrection(const PoseGraph& graph, const LoopResult& r, const MappingConfig& cfg) {
  LoopCorrection c;
  c.route_m = graph.routeLength(r.match, r.query);
  const Eigen::Isometry3d T_est = graph.pose(r.match).inverse() * graph.pose(r.query);
  c.correction_m = (T_est.translation() - r.T_match_query.translation()).norm();
  c.correction_deg = toDeg(Eigen::AngleAxisd(T_est.rotation().transpose() * r.T_match_query.rotation()).angle());
  c.allowed_m = cfg.max_loop_correction_base_m + cfg.max_drift_fraction * c.route_m;
  c.allowed_deg = allowedRotationDeg(c.route_m, cfg);
  return c;
}

bool plausibleHeading(const PoseGraph& graph, int match, int query, double yaw_rad, double slack_deg,
                      const MappingConfig& cfg) {
  const Eigen::Matrix3d R_est = graph.pose(match).rotation().transpose() * graph.pose(query).rotation();
  const double estimated_rad = std::atan2(R_est(1, 0), R_est(0, 0));  // the heading of query's x axis
  const double off_deg = toDeg(std::abs(std::remainder(yaw_rad - estimated_rad, 2.0 * M_PI)));
  return off_deg <= allowedRotationDeg(graph.routeLength(match, query), cfg) + slack_deg;
}

}  // namespace mmlio::backend
