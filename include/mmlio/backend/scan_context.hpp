#pragma once
// Scan-Context-style place descriptor (Kim & Kim 2018): the highest point per polar bin
// (ring = range, sector = azimuth) of a gravity-aligned keyframe cloud. Revisits match by the
// column-wise cosine distance at the best column shift, and that shift gives the relative yaw,
// so a loop can be found when drift has moved the estimate far from the true place.

#include <Eigen/Core>
#include <vector>

namespace mmlio::backend {

struct ScanContextConfig {
  int rings = 20;                // radial bins out to max_range_m
  int sectors = 60;              // azimuth bins (6 deg each)
  double max_range_m = 20.0;     // points farther away are ignored
  double height_offset_m = 2.0;  // added to z so that the floor is > 0 (empty bins are 0)
};

struct ScanContext {
  Eigen::MatrixXd bins;      // rings x sectors, max (z + height_offset_m), 0 when empty
  Eigen::VectorXd ring_key;  // per-ring mean: rotation invariant, for a quick pre-selection
};

ScanContext makeScanContext(const std::vector<Eigen::Vector3d>& cloud_body,
                            const ScanContextConfig& cfg = ScanContextConfig());

struct ScanContextMatch {
  double distance = 1.0;  // mean (1 - cosine) over the columns both occupy, at the best shift: 0 = same
  double yaw_rad = 0;     // yaw of the query's frame in the candidate's: R_candidate_query = Rz(yaw_rad)
};

ScanContextMatch compareScanContexts(const ScanContext& query, const ScanContext& candidate);

}  // namespace mmlio::backend
