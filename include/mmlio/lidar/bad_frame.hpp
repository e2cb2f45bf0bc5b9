#pragma once
// Bad-frame check of a solid-state LiDAR frame (paper, "Feature Clouds Merging"): a narrow-FoV
// LiDAR facing a close wall sees one plane and almost no edges; such a frame is left out of the
// merged feature cloud. Edges closer than min_edge_range_m are ignored (near clutter, the rig).
// The edge count is only a proxy for what a frame constrains: by default a frame it condemns is
// kept when the information of its own map matches is well conditioned (few edges, but a room
// corner in view); only a frame poor in both is dropped.

#include "mmlio/lidar/features.hpp"

namespace mmlio::lidar {

struct BadFrameConfig {
  bool enabled = true;  // false: never bad
  // true: a frame the edge count marks bad is still kept when its own map matches constrain every
  // translation direction (judged by the estimator, see estimator/degeneracy.hpp); false: the
  // paper's tau_e count alone.
  bool by_information = true;
  double min_edge_range_m = 2.0;  // only edges beyond this range (sensor frame) count
  int min_edge_points = 100;      // tau_e: fewer counted edges -> bad frame
};

struct BadFrameResult {
  bool bad = false;
  int counted_edges = 0;  // edges beyond min_edge_range_m
};

BadFrameResult checkSolidStateFrame(const FeatureCloud& features, const BadFrameConfig& cfg);

}  // namespace mmlio::lidar
