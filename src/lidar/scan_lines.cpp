// Scan lines for feature extraction: rings, Livox lines, or range-image rows.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>

#include "mmlio/lidar/features.hpp"

namespace mmlio::lidar {
namespace {

constexpr double kRingGapDeg = 0.25;  // elevation gap separating two rings in the range image
constexpr int kMaxImageRows = 256;    // more elevation clusters than this: no ring structure

bool valid(const Point& p, double min_range_m) {
  return p.xyz.allFinite() && p.xyz.cast<double>().squaredNorm() >= min_range_m * min_range_m;
}

double azimuth(const Point& p) { return std::atan2(static_cast<double>(p.xyz.y()), static_cast<double>(p.xyz.x())); }

/// A strictly increasing function of the azimuth on (-pi, pi] (the "diamond angle", in (-2, 2]):
/// sorting by it orders a ring exactly as sorting by atan2 would, without the atan2.
double azimuthOrderKey(const Point& p) {
  const double x = p.xyz.x(), y = p.xyz.y();
  const double l1 = std::abs(x) + std::abs(y);
  if (l1 <= 0.0) return 0.0;
  const double t = y / l1;               // sin-like, in [-1, 1]
  if (x >= 0.0) return t;                // (-pi/2, pi/2) -> (-1, 1)
  return y >= 0.0 ? 2.0 - t : -2.0 - t;  // (pi/2, pi] -> (1, 2]; (-pi, -pi/2) -> (-2, -1)
}
double elevationDeg(const Point& p) {
  const Eigen::Vector3d v = p.xyz.cast<double>();
  return std::atan2(v.z(), v.head<2>().norm()) * 180.0 / M_PI;
}

/// Sorts by key as std::stable_sort would, without its n log n for the shapes a ring comes in: one
/// ascending run, or descending (a clockwise spin, as Velodyne's), cut once where the sweep started;
/// the two runs overlap in azimuth when the sweep is a little longer than a turn. They are merged
/// (linear). A merge keeps equal keys in their first-come order; a descending ring is merged from
/// its far ends, which keeps that order only where no two keys within a run are equal, so that case
/// asks for strictly descending runs.
void sortRingByKey(std::vector<std::pair<double, std::size_t>>* keyed) {
  auto& v = *keyed;
  const auto by_key = [](const auto& a, const auto& b) { return a.first < b.first; };
  const auto ascending_cut = std::is_sorted_until(v.begin(), v.end(), by_key);
  if (ascending_cut == v.end()) return;
  if (std::is_sorted(ascending_cut, v.end(), by_key)) {
    std::inplace_merge(v.begin(), ascending_cut, v.end(), by_key);
    return;
  }
  const auto strictly_descending = [](const auto& a, const auto& b) { return a.first >= b.first; };
  const auto descending_cut = std::is_sorted_until(v.begin(), v.end(), strictly_descending);
  if (std::is_sorted(descending_cut, v.end(), strictly_descending)) {
    // Both runs read backwards are ascending; of equal keys the first run's comes first.
    std::vector<std::pair<double, std::size_t>> merged(v.size());
    const auto first_run_end = std::make_reverse_iterator(descending_cut);
    std::merge(first_run_end, v.rend(), v.rbegin(), first_run_end, merged.begin(), by_key);
    v.swap(merged);
    return;
  }
  std::stable_sort(v.begin(), v.end(), by_key);
}

// Spinning rings are ordered by azimuth (drivers' per-point times are not always monotonic along a
// ring, e.g. dual-return packets); Livox lines by time (the scan pattern doubles back in azimuth).
void orderLine(const LidarScan& scan, bool spinning, std::vector<std::size_t>* line) {
  if (spinning) {
    std::vector<std::pair<double, std::size_t>> keyed;
    keyed.reserve(line->size());
    for (std::size_t i : *line) keyed.emplace_back(azimuthOrderKey(scan.points[i]), i);
    sortRingByKey(&keyed);
    for (std::size_t k = 0; k < keyed.size(); ++k) (*line)[k] = keyed[k].second;
  } else {
    // Drivers send a line in time order: checking costs a pass, sorting n log n.
    const auto by_time = [&](std::size_t a, std::size_t b) { return scan.points[a].time_s < scan.points[b].time_s; };
    if (!std::is_sorted(line->begin(), line->end(), by_time)) std::stable_sort(line->begin(), line->end(), by_time);
  }
}

// Spinning cloud without ring numbers: rows = elevation clusters (the lasers), columns = azimuth
// bins; each cell keeps its nearest return; a row read by column is a ring.
std::vector<std::vector<std::size_t>> rangeImageRows(const LidarScan& scan, const std::vector<std::size_t>& ids,
                                                     int cols) {
  std::vector<double> el(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) el[k] = elevationDeg(scan.points[ids[k]]);
  std::vector<double> sorted = el;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> row_upper;  // upper elevation bound of each row but the last
  for (std::size_t k = 1; k < sorted.size(); ++k)
    if (sorted[k] - sorted[k - 1] > kRingGapDeg) row_upper.push_back(0.5 * (sorted[k] + sorted[k - 1]));
  if (static_cast<int>(row_upper.size()) + 1 > kMaxImageRows) {  // no clear rings: uniform rows
    row_upper.clear();
    const double lo = sorted.front(), hi = sorted.back();
    const int rows = 64;
    for (int r = 1; r < rows; ++r) row_upper.push_back(lo + (hi - lo) * r / rows);
  }
  const std::size_t rows = row_upper.size() + 1;
  cols = std::max(cols, 1);
  std::vector<long> cell(rows * static_cast<std::size_t>(cols), -1);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::size_t r =
        static_cast<std::size_t>(std::upper_bound(row_upper.begin(), row_upper.end(), el[k]) - row_upper.begin());
    int c = static_cast<int>(std::floor((azimuth(scan.points[ids[k]]) + M_PI) / (2 * M_PI) * cols));
    c = std::clamp(c, 0, cols - 1);
    long& slot = cell[r * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)];
    if (slot < 0 ||
        scan.points[ids[k]].xyz.squaredNorm() < scan.points[static_cast<std::size_t>(slot)].xyz.squaredNorm())
      slot = static_cast<long>(ids[k]);
  }
  std::vector<std::vector<std::size_t>> lines(rows);
  for (std::size_t r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const long id = cell[r * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)];
      if (id >= 0) lines[r].push_back(static_cast<std::size_t>(id));
    }
  return lines;
}

}  // namespace

std::vector<std::vector<std::size_t>> scanLines(const LidarScan& scan, LidarKind kind, int num_rings,
                                                const FeatureConfig& cfg) {
  std::vector<std::size_t> ids;
  ids.reserve(scan.points.size());
  int max_ring = 0;
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    if (!valid(scan.points[i], cfg.min_range_m)) continue;
    ids.push_back(i);
    max_ring = std::max<int>(max_ring, scan.points[i].ring);
  }
  if (ids.empty()) return {};
  const bool has_rings = max_ring > 0;
  const bool spinning = kind == LidarKind::kSpinning;
  if (spinning && (num_rings <= 1 || !has_rings)) return rangeImageRows(scan, ids, cfg.range_image_cols);

  std::vector<std::vector<std::size_t>> lines(static_cast<std::size_t>(has_rings ? max_ring + 1 : 1));
  for (std::size_t i : ids) lines[has_rings ? scan.points[i].ring : 0].push_back(i);
  for (auto& line : lines) orderLine(scan, spinning, &line);
  return lines;
}

}  // namespace mmlio::lidar
