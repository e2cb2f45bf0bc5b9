#pragma once
// A sweep's features thinned to a budget for its registration, so that registering a sweep costs
// about the same in a 60 m hall as in a small room: a 0.3 m plane voxel keeps about 1000 features
// of an office sweep and 9000 of a hall sweep, and every feature is a kNN search, a plane fit and a
// residual per solver iteration. The keyframes' window optimisation, which the map and the
// trajectory's accuracy rest on, keeps them all.

#include <cstddef>

#include "mmlio/estimator/map_matching.hpp"

namespace mmlio::estimator {

struct FeatureBudget {
  std::size_t max_edges = 0;  // 0: no limit
  std::size_t max_planes = 0;
  double edge_cell_m = 0.2;  // the thinning grid starts at the features' own voxel ...
  double plane_cell_m = 0.3;
};

/// The edges and planes of `f` (with their sources), each kept only if it is the first in its cell
/// of a grid coarsened until at most the budget remain. The kept points are features themselves
/// (voxel centroids on a surface), not centroids of larger cells, which straddle corners and lie
/// off every surface.
Features thinToBudget(const Features& f, const FeatureBudget& budget);

}  // namespace mmlio::estimator
