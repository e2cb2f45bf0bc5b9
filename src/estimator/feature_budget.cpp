#include "mmlio/estimator/feature_budget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/voxel_key.hpp"

namespace mmlio::estimator {
namespace {

/// Indices of the first point in each cell of a grid grown from cell_m until at most max_points
/// remain (all indices when the budget is 0 or already met).
std::vector<std::size_t> firstPerCell(const std::vector<Eigen::Vector3d>& pts, double cell_m, std::size_t max_points) {
  std::vector<std::size_t> kept(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) kept[i] = i;
  // Surface points thin out with the square of the cell: grow it by the square root of the excess
  // (and a little more, so one or two passes suffice).
  for (int pass = 0; pass < 8 && max_points > 0 && cell_m > 0 && kept.size() > max_points; ++pass) {
    cell_m *= 1.05 * std::max(1.0, std::sqrt(static_cast<double>(kept.size()) / static_cast<double>(max_points)));
    const double inv = 1.0 / cell_m;
    FlatKeySet cells;
    kept.clear();
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (cells.insert(scaledVoxelKeyOf(pts[i], inv))) kept.push_back(i);
  }
  return kept;
}

void keep(const std::vector<Eigen::Vector3d>& pts, const std::vector<std::uint8_t>& src,
          const std::vector<std::size_t>& kept, std::vector<Eigen::Vector3d>* out_pts,
          std::vector<std::uint8_t>* out_src) {
  out_pts->reserve(kept.size());
  for (std::size_t i : kept) out_pts->push_back(pts[i]);
  if (src.size() != pts.size()) return;
  out_src->reserve(kept.size());
  for (std::size_t i : kept) out_src->push_back(src[i]);
}

}  // namespace

Features thinToBudget(const Features& f, const FeatureBudget& budget) {
  Features out;
  keep(f.edges, f.edge_source, firstPerCell(f.edges, budget.edge_cell_m, budget.max_edges), &out.edges,
       &out.edge_source);
  keep(f.planes, f.plane_source, firstPerCell(f.planes, budget.plane_cell_m, budget.max_planes), &out.planes,
       &out.plane_source);
  return out;
}

}  // namespace mmlio::estimator
