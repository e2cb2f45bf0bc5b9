#include "mmlio/map/range_image.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mmlio::map {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

int rowOf(double elevation_rad, double inv_res) { return static_cast<int>(std::floor((elevation_rad * kRadToDeg + 90.0) * inv_res)); }

// atan2 to within 1e-5 rad (a polynomial for atan on [0, 1], then octant folding): pixels are
// 0.5 deg, and libm's atan2 and asin were a third of a hall run's visibility tests.
double fastAtan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double hi = std::max(ax, ay);
  if (hi == 0.0) return 0.0;
  const double a = std::min(ax, ay) / hi, s = a * a;
  double r = a * (0.9998660 + s * (-0.3302995 + s * (0.1801410 + s * (-0.0851330 + s * 0.0208351))));
  if (ay > ax) r = 0.5 * M_PI - r;
  if (x < 0.0) r = M_PI - r;
  return y < 0.0 ? -r : r;
}

// sqrt, not hypot: metres are far from overflow, and hypot guards against it slowly.
double elevationOf(const Eigen::Vector3d& p) { return fastAtan2(p.z(), std::sqrt(p.x() * p.x() + p.y() * p.y())); }

}  // namespace

RangeImage::RangeImage(const std::vector<Point>& points, const RangeImageConfig& config) : cfg_(config) {
  inv_res_ = 1.0 / std::max(0.05, cfg_.resolution_deg);
  circle_cols_ = std::max(1, static_cast<int>(std::ceil(360.0 * inv_res_)));
  // One pass computes every return's pixel (rows relative to row 0 until the image's rows are known).
  struct Cell {
    int col, row;
    std::uint16_t cm;
  };
  thread_local std::vector<Cell> cells;
  cells.clear();
  cells.reserve(points.size());
  int lo = std::numeric_limits<int>::max(), hi = std::numeric_limits<int>::min();
  for (const Point& p : points) {
    const Eigen::Vector3d v = p.xyz.cast<double>();
    const double r = v.norm();
    if (!(r > 1e-3) || !std::isfinite(r)) continue;  // no-return (0,0,0) points, NaN
    int col, row;
    pixelOf(v, &col, &row);
    lo = std::min(lo, row);
    hi = std::max(hi, row);
    cells.push_back({col, row, static_cast<std::uint16_t>(std::clamp(std::lround(r * 100.0), 1L, 65535L))});
  }
  if (cells.empty()) return;
  row0_ = lo;
  rows_ = hi - lo + 1;
  // Keep the arc of columns outside the widest circular run of empty ones; a pixel outside it reads
  // as empty, as it would in the full image.
  thread_local std::vector<char> used;
  used.assign(static_cast<std::size_t>(circle_cols_), 0);
  for (const Cell& c : cells) used[static_cast<std::size_t>(c.col)] = 1;
  int gap = 0, widest = 0, widest_end = 0;
  for (int i = 0; i < 2 * circle_cols_; ++i) {
    gap = used[static_cast<std::size_t>(i % circle_cols_)] ? 0 : std::min(gap + 1, circle_cols_);
    if (gap > widest) {
      widest = gap;
      widest_end = i % circle_cols_;
    }
  }
  cols_ = circle_cols_ - widest;
  col0_ = widest == 0 ? 0 : (widest_end + 1) % circle_cols_;
  const int margin_cols = cfg_.window_cols + 1;
  if (2 * (cols_ + 2 * margin_cols) < circle_cols_) {
    narrow_arc_ = true;
    const double res_rad = M_PI / 180.0 / inv_res_;
    const double from = (col0_ - margin_cols) * res_rad - M_PI, to = (col0_ + cols_ + margin_cols) * res_rad - M_PI;
    arc_from_x_ = std::cos(from);
    arc_from_y_ = std::sin(from);
    arc_to_x_ = std::cos(to);
    arc_to_y_ = std::sin(to);
  }
  // Only rows with returns are stored: a spinning LiDAR's 16 rings fill 16 of the ~60 rows its
  // 30 deg span covers at 0.5 deg.
  slot_of_row_.assign(static_cast<std::size_t>(rows_), -1);
  for (const Cell& c : cells) slot_of_row_[static_cast<std::size_t>(c.row - lo)] = 0;  // has returns ...
  int stored = 0;  // ... numbered in order
  for (std::int16_t& slot : slot_of_row_)
    if (slot == 0) slot = static_cast<std::int16_t>(stored++);
  ranges_.assign(static_cast<std::size_t>(stored) * static_cast<std::size_t>(cols_), 0);
  for (const Cell& c : cells) {
    const int x = (c.col - col0_ + circle_cols_) % circle_cols_;
    const auto slot = static_cast<std::size_t>(slot_of_row_[static_cast<std::size_t>(c.row - lo)]);
    std::uint16_t& cell = ranges_[slot * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(x)];
    if (cell == 0 || c.cm < cell) cell = c.cm;
  }
}

int RangeImage::colOf(const Eigen::Vector3d& p) const {
  return std::clamp(static_cast<int>(std::floor((fastAtan2(p.y(), p.x()) * kRadToDeg + 180.0) * inv_res_)), 0,
                    circle_cols_ - 1);
}

void RangeImage::pixelOf(const Eigen::Vector3d& p, int* col, int* row) const {
  *col = colOf(p);
  *row = rowOf(elevationOf(p), inv_res_) - row0_;
}

Visibility RangeImage::classify(const Eigen::Vector3d& p) const {
  if (ranges_.empty()) return Visibility::kUnknown;
  const double r = p.norm();
  if (!(r >= cfg_.min_range_m) || r > cfg_.max_range_m) return Visibility::kUnknown;
  if (narrow_arc_ && (arc_from_x_ * p.y() - arc_from_y_ * p.x() < 0 || p.x() * arc_to_y_ - p.y() * arc_to_x_ < 0))
    return Visibility::kUnknown;  // beyond the arc
  // Most points asked about lie outside a solid-state LiDAR's arc (turned away above) or rows: the
  // window is placed row first, then column by column (x once per column), and left as soon as it
  // is empty.
  const int row = rowOf(elevationOf(p), inv_res_) - row0_;  // a row just outside still sees measured rows
  if (row + cfg_.window_rows < 0 || row - cfg_.window_rows >= rows_) return Visibility::kUnknown;
  const int col = colOf(p);
  const double margin = cfg_.margin_m + cfg_.margin_fraction * r;
  const double hit_margin = cfg_.hit_margin_m + cfg_.hit_margin_fraction * r;
  const int y_lo = std::max(0, row - cfg_.window_rows), y_hi = std::min(rows_ - 1, row + cfg_.window_rows);
  double nearest = std::numeric_limits<double>::infinity();
  bool hit = false, below = false, above = false, left = false, right = false;
  for (int dc = -cfg_.window_cols; dc <= cfg_.window_cols; ++dc) {
    const int x = (col + dc - col0_ + 2 * circle_cols_) % circle_cols_;
    if (x >= cols_) continue;
    for (int y = y_lo; y <= y_hi; ++y) {
      const int slot = slot_of_row_[static_cast<std::size_t>(y)];
      if (slot < 0) continue;
      const std::uint16_t cell = ranges_[static_cast<std::size_t>(slot) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(x)];
      if (cell == 0) continue;
      const int dr = y - row;
      const double m = 0.01 * cell;
      nearest = std::min(nearest, m);
      // Seen ON: a return at the point's range in its own pixel or the ones just above and below.
      // The rest of the window does not count: at grazing incidence it reaches a wall or the floor
      // at every range near the point's.
      hit = hit || (dc == 0 && std::abs(dr) <= 1 && std::abs(m - r) <= hit_margin);
      below = below || dr <= 0;
      above = above || dr >= 0;
      left = left || dc <= 0;
      right = right || dc >= 0;
    }
  }
  if (!std::isfinite(nearest)) return Visibility::kUnknown;
  if (below && above && left && right && r < nearest - margin) return Visibility::kFree;
  if (hit) return Visibility::kHit;
  return nearest < r ? Visibility::kOccluded : Visibility::kUnknown;
}

}  // namespace mmlio::map
