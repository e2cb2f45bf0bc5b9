#pragma once
// Settings of the mapping back end (backend::MappingBackend): loop closure, submaps, the output
// map and its ghost removal. Here, beside the loop closer, so the rig config can bind them from
// YAML without depending on the pipeline.
#include "mmlio/backend/loop_closer.hpp"

namespace mmlio::backend {

struct MappingConfig {
  bool loop_enabled = true;
  LoopCloser::Config loop;
  double map_leaf_m = 0.05;          // output map resolution (0: every point)
  double loop_cloud_voxel_m = 0.1;   // keyframe clouds kept for loop verification ...
  bool keep_keyframe_clouds = true;  // ... and, with loop closure off, still for the session (relocalization)
  int loop_check_every = 4;          // try loop detection on every n-th keyframe
  // A loop may move the pose by at most max_loop_correction_base_m plus max_drift_fraction of the
  // route between its ends through the graph, and turn it by at most max_loop_rotation_base_deg
  // plus max_rotation_drift_deg_per_m per metre of it (loop_plausibility.hpp).
  double max_loop_correction_base_m = 0.3;
  double max_drift_fraction = 0.02;
  double max_loop_rotation_base_deg = 5.0;
  double max_rotation_drift_deg_per_m = 0.05;
  int map_point_stride = 4;           // each sweep adds every n-th point (offset rotates per sweep):
                                      // overlapping sweeps still fill every voxel, at 1/n the cost
  bool per_lidar_maps = false;        // keep each LiDAR's points apart too (lidarMap)
  bool dedupe_revisits = true;        // a closed submap keeps only voxels no earlier keyframe
                                      // holds (at the estimate then): memory follows the mapped
                                      // surface, not the time spent in it
  double revisit_new_fraction = 0.1;  // a closed keyframe with fewer new voxels than this
                                      // fraction frees its loop cloud (a revisit)
  bool clean_map = true;              // drop submap points keyframes saw through (ghosts of movers)
  bool dynamic_map = true;            // keep what was removed as moving (dynamicMap)
  double ghost_range_m = 20.0;        // keyframes judge map points up to this far from a LiDAR
  int ghost_keyframes = 40;           // a submap is judged by the views of this many keyframes
                                      // before and after its own, once they exist
};

}  // namespace mmlio::backend
