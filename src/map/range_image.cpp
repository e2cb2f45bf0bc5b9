#include "mmlio/map/range_image.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mmlio/core/floor_to.hpp"

namespace mmlio::map {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

int rowOf(double elevation_rad, double inv_res) { return floorTo<int>((elevation_rad * kRadToDeg + 90.0) * inv_res); }

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

// Summarising a window (summariseWindows for all, windowAt for one): the nearest return so far
// (kNone: none; larger than any saturated range), and on which sides of the window's centre
// pixel returns lie.
constexpr std::uint16_t kNone = 0xffff;
constexpr std::uint8_t kBelow = 1, kAbove = 2, kLeft = 4, kRight = 8, kAll = kBelow | kAbove | kLeft | kRight;

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
    // Centimetres rounded half up, as lround would for these positive values, inline (the libm
    // call was a tenth of building an image); truncation floors a positive value.
    const double cm = std::clamp(r * 100.0 + 0.5, 1.0, 65535.0);
    cells.push_back({col, row, static_cast<std::uint16_t>(cm)});
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
  int stored = 0;                                                                      // ... numbered in order
  for (std::int16_t& slot : slot_of_row_)
    if (slot == 0) slot = static_cast<std::int16_t>(stored++);
  ranges_.assign(static_cast<std::size_t>(stored) * static_cast<std::size_t>(cols_), 0);
  for (const Cell& c : cells) {
    const int x = (c.col - col0_ + circle_cols_) % circle_cols_;
    std::uint16_t& cell = ranges_[rangeIndex(slot_of_row_[static_cast<std::size_t>(c.row - lo)], x)];
    if (cell == 0 || c.cm < cell) cell = c.cm;
  }
  summariseWindows();
}

RangeImage RangeImage::withoutWindows() const {
  RangeImage copy = *this;  // once per keyframe: copying the windows to free them costs less than listing every field
  copy.windows_.clear();
  copy.windows_.shrink_to_fit();
  return copy;
}

std::uint16_t RangeImage::windowAt(int arc_col, int row) const {
  // summariseWindows for one window, in the same terms.
  const int wr = cfg_.window_rows, wc = cfg_.window_cols;
  std::uint16_t nearest = kNone;
  std::uint8_t sides = 0;
  for (int dc = -wc; dc <= wc; ++dc) {
    const int x = (arc_col + dc + 2 * circle_cols_) % circle_cols_;
    if (x >= cols_) continue;
    const auto lr = static_cast<std::uint8_t>((dc <= 0 ? kLeft : 0) | (dc >= 0 ? kRight : 0));
    for (int y = std::max(0, row - wr); y <= std::min(rows_ - 1, row + wr); ++y) {
      const int slot = slot_of_row_[static_cast<std::size_t>(y)];
      if (slot < 0) continue;
      const std::uint16_t cm = ranges_[rangeIndex(slot, x)];
      if (cm == 0) continue;
      nearest = std::min(nearest, std::min(cm, kNearestMask));
      sides |= static_cast<std::uint8_t>(lr | (row <= y ? kAbove : 0) | (row >= y ? kBelow : 0));
    }
  }
  return static_cast<std::uint16_t>((nearest == kNone ? 0 : nearest) | (sides == kAll ? kSurrounded : 0));
}

int RangeImage::windowColumn(int arc_col) const {
  const int wc = cfg_.window_cols;
  if (window_width_ == circle_cols_) return arc_col;  // the windows reach round the whole circle
  if (arc_col < cols_ + wc) return arc_col;
  if (arc_col >= circle_cols_ - wc) return cols_ + wc + (arc_col - (circle_cols_ - wc));  // just before col0_
  return -1;
}

// Two passes, as the window is a box: along each stored column, what lies within window_rows of
// every row (scattered from the returns: a spinning LiDAR's 16 rings fill few of the rows); then
// across window_cols of those columns. Column-major, so both passes run along contiguous memory.
void RangeImage::summariseWindows() {
  const int wr = cfg_.window_rows, wc = cfg_.window_cols;
  const int ext_rows = rows_ + 2 * wr;
  const auto ext = static_cast<std::size_t>(ext_rows);
  thread_local std::vector<std::uint16_t> nearest;       // per column and row: the nearest return within wr rows
  thread_local std::vector<std::uint8_t> sides;          // ... and whether one lies at or below, at or above
  thread_local std::vector<std::pair<int, int>> stored;  // (row, slot) of the rows with returns
  nearest.assign(ext * static_cast<std::size_t>(cols_), kNone);
  sides.assign(ext * static_cast<std::size_t>(cols_), 0);
  stored.clear();
  for (int y = 0; y < rows_; ++y)
    if (slot_of_row_[static_cast<std::size_t>(y)] >= 0)
      stored.emplace_back(y, slot_of_row_[static_cast<std::size_t>(y)]);
  for (int x = 0; x < cols_; ++x) {
    std::uint16_t* near = nearest.data() + static_cast<std::size_t>(x) * ext;
    std::uint8_t* side = sides.data() + static_cast<std::size_t>(x) * ext;
    for (const auto& [y, slot] : stored) {
      const std::uint16_t cm = ranges_[rangeIndex(slot, x)];
      if (cm == 0) continue;
      const std::uint16_t saturated = std::min(cm, kNearestMask);
      // Window row y - wr + k (stored at y + k) holds row y: at or below it for k >= wr, at or above for k <= wr.
      for (int k = 0; k <= 2 * wr; ++k) near[y + k] = std::min(near[y + k], saturated);
      for (int k = 0; k < wr; ++k) side[y + k] |= kAbove;
      side[y + wr] |= kBelow | kAbove;
      for (int k = wr + 1; k <= 2 * wr; ++k) side[y + k] |= kBelow;
    }
  }
  window_width_ = std::min(circle_cols_, cols_ + 2 * wc);
  windows_.assign(ext * static_cast<std::size_t>(window_width_), 0);
  // Raw pointers: stores through std::uint8_t* may alias anything, so the vectors' own pointers
  // would be reloaded in every iteration.
  std::vector<std::uint16_t> window_near(ext);
  std::vector<std::uint8_t> window_sides(ext);
  std::uint16_t* const wn = window_near.data();
  std::uint8_t* const ws = window_sides.data();
  const std::uint16_t* const column_near = nearest.data();
  const std::uint8_t* const column_sides = sides.data();
  for (int j = 0; j < window_width_; ++j) {
    const int arc_col = j < cols_ + wc ? j : circle_cols_ - wc + (j - cols_ - wc);
    std::fill(wn, wn + ext, kNone);
    std::fill(ws, ws + ext, 0);
    for (int dc = -wc; dc <= wc; ++dc) {  // the columns the window reaches, one at a time
      const int x = (arc_col + dc + 2 * circle_cols_) % circle_cols_;
      if (x >= cols_) continue;
      const std::uint16_t* near = column_near + static_cast<std::size_t>(x) * ext;
      const std::uint8_t* side = column_sides + static_cast<std::size_t>(x) * ext;
      const auto lr = static_cast<std::uint8_t>((dc <= 0 ? kLeft : 0) | (dc >= 0 ? kRight : 0));
      for (std::size_t at = 0; at < ext; ++at) {
        wn[at] = std::min(wn[at], near[at]);
        ws[at] |= static_cast<std::uint8_t>((near[at] != kNone) * (lr | side[at]));
      }
    }
    std::uint16_t* out = windows_.data() + static_cast<std::size_t>(j) * ext;
    for (std::size_t at = 0; at < ext; ++at)
      out[at] = static_cast<std::uint16_t>((wn[at] == kNone ? 0 : wn[at]) | (ws[at] == kAll ? kSurrounded : 0));
  }
}

int RangeImage::colOf(const Eigen::Vector3d& p) const {
  return std::clamp(floorTo<int>((fastAtan2(p.y(), p.x()) * kRadToDeg + 180.0) * inv_res_), 0, circle_cols_ - 1);
}

void RangeImage::pixelOf(const Eigen::Vector3d& p, int* col, int* row) const {
  *col = colOf(p);
  *row = rowOf(elevationOf(p), inv_res_) - row0_;
}

Visibility RangeImage::classify(const Eigen::Vector3d& p) const {
  if (ranges_.empty()) return Visibility::kUnknown;
  const double r = p.norm();
  if (!(r >= cfg_.min_range_m) || r > std::min(cfg_.max_range_m, kMaxJudgedRangeM)) return Visibility::kUnknown;
  if (narrow_arc_ && (arc_from_x_ * p.y() - arc_from_y_ * p.x() < 0 || p.x() * arc_to_y_ - p.y() * arc_to_x_ < 0))
    return Visibility::kUnknown;  // beyond the arc
  // Most points asked about lie outside a solid-state LiDAR's arc (turned away above) or rows.
  const int wr = cfg_.window_rows;
  const int row = rowOf(elevationOf(p), inv_res_) - row0_;  // a row just outside still sees measured rows
  if (row + wr < 0 || row - wr >= rows_) return Visibility::kUnknown;
  const int arc_col = (colOf(p) - col0_ + circle_cols_) % circle_cols_;
  const int j = windowColumn(arc_col);
  if (j < 0) return Visibility::kUnknown;
  const std::uint16_t window = windows_.empty()
                                   ? windowAt(arc_col, row)
                                   : windows_[static_cast<std::size_t>(j) * static_cast<std::size_t>(rows_ + 2 * wr) +
                                              static_cast<std::size_t>(row + wr)];
  if ((window & kNearestMask) == 0) return Visibility::kUnknown;
  const double nearest = 0.01 * (window & kNearestMask);
  if ((window & kSurrounded) && r < nearest - (cfg_.margin_m + cfg_.margin_fraction * r)) return Visibility::kFree;
  // Seen ON: a return at the point's range in its own pixel or the ones just above and below. The
  // rest of the window does not count: at grazing incidence it reaches a wall or the floor at every
  // range near the point's.
  if (arc_col < cols_) {
    const double hit_margin = cfg_.hit_margin_m + cfg_.hit_margin_fraction * r;
    const int reach = std::min(1, wr);
    for (int y = std::max(0, row - reach); y <= std::min(rows_ - 1, row + reach); ++y) {
      const int slot = slot_of_row_[static_cast<std::size_t>(y)];
      if (slot < 0) continue;
      const std::uint16_t cell = ranges_[rangeIndex(slot, arc_col)];
      if (cell != 0 && std::abs(0.01 * cell - r) <= hit_margin) return Visibility::kHit;
    }
  }
  return nearest < r ? Visibility::kOccluded : Visibility::kUnknown;
}

}  // namespace mmlio::map
