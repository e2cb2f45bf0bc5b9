#pragma once
// What one LiDAR saw from one place: the nearest return per (azimuth, elevation) pixel. It answers
// the visibility question behind dynamic-object handling: was a point in space seen THROUGH (the
// rays around it went farther: free space), seen ON (a return at its range), or hidden behind
// something nearer?
//
// "Free" is deliberately hard to get, because wrongly calling a static surface free removes it:
// every measured pixel in a window around the point must be farther than the point by a margin,
// and the measured pixels must surround the point in both azimuth and elevation. So a point
// beside a depth edge, between a spinning LiDAR's rings with no ring beyond it, at the edge of a
// solid-state field of view, or on a surface at grazing incidence is never free.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::map {

struct RangeImageConfig {
  double resolution_deg = 0.5;        // pixel size in azimuth and elevation
  int window_cols = 1;                // half-window in azimuth, pixels
  int window_rows = 4;                // half-window in elevation, pixels (spans a VLP-16's 2 deg ring gap)
  double margin_m = 0.1;              // free: every ray nearby went at least this much farther ...
  double margin_fraction = 0.02;      // ... plus this fraction of the point's range (range noise, pose error)
  double hit_margin_m = 0.05;         // seen on: a return this close to the point's range ...
  double hit_margin_fraction = 0.01;  // ... plus this fraction (tighter than free: a point 10-20 cm in
                                      // front of a wall is neither, not "seen on" by every view of the wall)
  double min_range_m = 0.5;           // nearer points are never judged (self returns, blind zone) ...
  double max_range_m = 20.0;          // ... nor farther ones (the margin there exceeds a person's depth;
                                      // never beyond kMaxJudgedRangeM)
};

/// Farthest point any image judges: window summaries hold ranges up to 327.67 m (15 bits of cm),
/// beyond any such point plus its free-space margin.
constexpr double kMaxJudgedRangeM = 250.0;

enum class Visibility : std::uint8_t { kUnknown, kFree, kHit, kOccluded };

class RangeImage {
 public:
  RangeImage() = default;
  /// From points in the sensor frame; (0,0,0) no-return points and non-finite ones are skipped.
  RangeImage(const std::vector<Point>& points_sensor, const RangeImageConfig& config);

  Visibility classify(const Eigen::Vector3d& p_sensor) const;
  bool empty() const { return ranges_.empty(); }
  /// A copy without the window summaries: the same answers from a fifth of a spinning LiDAR's
  /// memory, each read from the window's pixels (several times slower). For views kept in case
  /// they are asked (the map's ghost removal asks only about points near something that moved).
  RangeImage withoutWindows() const;
  std::size_t memoryBytes() const {
    return ranges_.size() * sizeof(ranges_[0]) + slot_of_row_.size() * sizeof(slot_of_row_[0]) +
           windows_.size() * sizeof(windows_[0]);
  }

 private:
  // For a finite, non-zero p; col on the full circle, row relative to row0_ (may lie outside the image).
  void pixelOf(const Eigen::Vector3d& p, int* col, int* row) const;
  int colOf(const Eigen::Vector3d& p) const;  // pixelOf's column alone
  /// The column of windows_ for a column counted from col0_ around the circle, -1 if no window
  /// around it reaches a stored column.
  int windowColumn(int arc_col) const;
  /// Where stored row `slot`'s pixel in column x (counted from col0_) lies in ranges_.
  std::size_t rangeIndex(int slot, int x) const {
    return static_cast<std::size_t>(slot) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(x);
  }
  void summariseWindows();
  /// What windows_ holds for window row `row` (relative to row0_) around stored column arc_col,
  /// read from ranges_.
  std::uint16_t windowAt(int arc_col, int row) const;

  RangeImageConfig cfg_;
  double inv_res_ = 1.0;
  int circle_cols_ = 0;  // columns of a full turn
  int cols_ = 0, rows_ = 0, row0_ = 0;
  int col0_ = 0;  // the stored columns are col0_ .. col0_ + cols_ - 1 around the circle: the azimuth
                  // arc with returns (a solid-state LiDAR's 82 deg, not 360)
  // An arc narrower than a half turn is also kept as its two bounding directions (x, y), widened
  // by the window and a column: a point outside them cannot reach a stored pixel, which two cross
  // products tell without the atan2s (most of the local map, seen from an 82 deg view).
  bool narrow_arc_ = false;
  double arc_from_x_ = 0, arc_from_y_ = 0, arc_to_x_ = 0, arc_to_y_ = 0;
  // Per row (relative to row0_): where its pixels are stored, -1 for a row without returns.
  std::vector<std::int16_t> slot_of_row_;
  // Stored rows x cols_, nearest return in cm (0 = none): half the memory of floats, far below the
  // margins (keyframes keep their images for the map's ghost removal).
  std::vector<std::uint16_t> ranges_;
  // What classify needs of the window around every pixel, computed once per image: a keyframe's
  // image is asked about every local-map point near it, and a sweep's about the features of the
  // sweeps after it. Column by column (as windowColumn numbers them), rows -window_rows ..
  // rows_ + window_rows - 1 (relative to row0_). Per pixel: the nearest return in the window in
  // cm (0 = none, saturating at 32767) and, in the top bit, whether returns surround it (above
  // and below, left and right).
  static constexpr std::uint16_t kSurrounded = 0x8000, kNearestMask = 0x7fff;
  int window_width_ = 0;
  std::vector<std::uint16_t> windows_;
};

}  // namespace mmlio::map
