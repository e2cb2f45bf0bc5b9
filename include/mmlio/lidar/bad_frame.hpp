#pragma once
// Bad-frame check of a solid-state LiDAR frame (paper, "Feature Clouds Merging"): a narrow-FoV
// LiDAR facing a close wall sees one plane and almost no edges; such a frame is left out of the
// merged feature cloud. Edges closer than min_edge_range_m are ignored (near clutter, the rig).

#include "mmlio/lidar/features.hpp"

namespace mmlio::lidar {

struct BadFrameConfig {
  bool enabled = true;            // false: never bad
  double min_edge_range_m = 2.0;  // only edges beyond this range (sensor frame) count
  int min_edge_points = 100;      // tau_e: fewer counted edges -> bad frame
};

struct BadFrameResult {
  bool bad = false;
  int counted_edges = 0;  // edges beyond min_edge_range_m
};

BadFrameResult checkSolidStateFrame(const FeatureCloud& features, const BadFrameConfig& cfg);

}  // namespace mmlio::lidar
