#include "mmlio/lidar/bad_frame.hpp"

namespace mmlio::lidar {

BadFrameResult checkSolidStateFrame(const FeatureCloud& features, const BadFrameConfig& cfg) {
  BadFrameResult r;
  const double min_sq = cfg.min_edge_range_m * cfg.min_edge_range_m;
  for (const Point& p : features.edges)
    if (p.xyz.cast<double>().squaredNorm() >= min_sq) ++r.counted_edges;
  r.bad = cfg.enabled && r.counted_edges < cfg.min_edge_points;
  return r;
}

}  // namespace mmlio::lidar
