#pragma once
// Unified edge / plane feature extraction for spinning and solid-state LiDARs (paper, "Union
// Feature Extraction"; LOAM; Chen et al. 2021): points are split into scan lines (spinning
// rings ordered by azimuth, Livox lines ordered by time, or the rows of a range image when rings
// are missing), and every point is judged on its line neighbourhood of `neighbours` points each
// side, taken every `stride` points so that they are >= min_neighbour_spacing_m apart (the
// stride follows from the line's angular step, measured on bearings so range noise does not
// inflate it): on dense lines (a close wall, the Livox pattern) range noise would otherwise
// swamp the curvature.
//  1. continuity: a 3-D gap > continuity_jump_m between consecutive points, or the line turning
//     back on itself (Livox), breaks the line. At a depth jump the near-side point is a
//     break-point edge (a plane ends there: occlusion boundary); far-side points are left out.
//  2. curvature c = |sum_j (p_j - c_i)|^2 / sum_j |p_j - c_i|^2 over the neighbours j, with c_i the
//     mean of the points between the two nearest neighbours: scale free, 0 on a straight run,
//     ~4 at a right-angle corner with 5 neighbours each side, small on a noisy flat surface.
//  3. scatter matrices: the principal axes of the two half-neighbourhoods meet at more than
//     edge_min_bend_deg at a line edge (two surfaces meet), which rejects a single noisy point;
//     a plane point's neighbourhood is a straight run ((l2 + l3) / l1 < plane_max_flatness).
// Edges (c > edge_threshold) and planes (c < plane_threshold) are picked per line sector
// (LOAM): sharpest edges first with suppression of their neighbours, at most
// max_edges_per_sector; the flattest max_planes_per_sector planes.
// Known limits: a ring's azimuth seam (+-180 deg) loses one neighbourhood of points; a Livox
// cloud without line numbers is taken as a single time-ordered line.

#include <cstddef>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::lidar {

struct FeatureConfig {
  int neighbours = 5;              // points each side for curvature / scatter
  double edge_threshold = 1.0;     // curvature above which a point is an edge (dimensionless, see above)
  double plane_threshold = 0.1;    // curvature below which a point is a plane
  double continuity_jump_m = 0.3;  // gap between consecutive line points that breaks a neighbourhood
  double min_range_m = 0.5;        // closer returns are ignored
  int range_image_cols = 1800;     // azimuth bins of the range image used when rings are missing
  // Beyond the shared config:
  double min_neighbour_spacing_m = 0.05;  // neighbours are every n-th point so they are this far apart (noise)
  int max_stride = 8;                     // ... but at most every max_stride-th point
  double edge_min_bend_deg = 30.0;        // angle between the two half-neighbourhood lines for a line edge
  double plane_max_flatness = 0.05;       // lambda_2 / lambda_1 of the neighbourhood for a plane point
  int sectors_per_line = 6;               // each line is split into this many sectors for even spreading
  int max_edges_per_sector = 20;          // LOAM-style cap on edges per sector
  int max_planes_per_sector = 100;        // cap on planes per sector (the flattest are kept)
  bool planes = true;                     // false: edges only (a LiDAR whose every return is a surface point)
};

struct FeatureCloud {
  std::vector<Point> edges, planes;  // sensor frame, original points (line edges + break points; planes)
  std::size_t input_points = 0;      // points of the scan, before any filtering
};

/// num_rings: rings (spinning) or lines (solid state); <= 1 for a spinning cloud without usable
/// ring numbers triggers the range-image path. Points keep time_s, intensity and ring.
FeatureCloud extractFeatures(const LidarScan& scan, LidarKind kind, int num_rings, const FeatureConfig& cfg);

/// The scan lines used by extractFeatures: indices into scan.points, each ordered along the line
/// (exposed for tests and diagnostics).
std::vector<std::vector<std::size_t>> scanLines(const LidarScan& scan, LidarKind kind, int num_rings,
                                                const FeatureConfig& cfg);

}  // namespace mmlio::lidar
